//! An exact all-mode time response written in the tests, the reference of the crate's
//! modal superposition: every mode of a dense (K, M) by a dense eigen-solve
//! ([`crate::dense_fem::dense_eig`]), each mode's first-order system [q, q̇, g, ġ]
//! (force linear between samples) propagated by nalgebra's matrix exponential (Padé with
//! scaling and squaring) — no closed form of the crate's propagator. Rayleigh damping
//! C = αM + βK is diagonal in the M-orthonormal modes (ζ_j = (α + βλ_j)/(2ω_j), computed
//! here from α and β), so the reference is the exact response of M ü + C u̇ + K u = f; a
//! modal ratio is each mode's ζ by definition.

use crate::dense_fem::dense_eig;
use cablevib::estimator::Estimator;
use cablevib::modal::response::ModalResponse;
use cablevib::scene::Damping;
use cablevib::study::simulate::added_load::{convective_force, AddedKind, AddedLoad};
use cablevib::study::simulate::pilot;
use cablevib::trajectory::moves::{Move, Profile};
use nalgebra::{DMatrix, DVector, Matrix4, Matrix6, Vector3, Vector4, Vector6};

/// The damping ratio of a mode at ω (rad/s), from the damping's own numbers.
fn zeta_of(d: &Damping, omega: f64) -> f64 {
    match *d {
        Damping::None => 0.0,
        Damping::Rayleigh {
            alpha_per_s,
            beta_s,
        } => (alpha_per_s + beta_s * omega * omega) / (2.0 * omega),
        Damping::ModalRatio { zeta } => zeta,
        Damping::LossFactor { .. } => panic!("a loss factor has no time response"),
    }
}

/// What [`exact_response`] found besides the response.
#[derive(Debug)]
pub struct ExactModes {
    /// Modes of the dense model.
    pub count: usize,
    /// Of which overdamped (ζ > 1).
    pub overdamped: usize,
    /// Largest ζ.
    pub zeta_max: f64,
}

/// The end-effector translation at each sample of M ü + C u̇ + K u = [f(t); 0], at rest at
/// the start, f linear between the samples `dt` apart: every mode of (K, M) (DOF 0..`dim`
/// the end-effector, 3 or 6; `f`'s entries beyond `dim` unused), each propagated by exp(A·dt) of its scaled first-order system
/// x = [ωq, q̇, g/ω, ġ/ω] (entries of A: ω, 2ζω and 1, so the exponential's scaling and
/// squaring meets no ω² against 1).
pub fn exact_response(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt: f64,
) -> (Vec<Vector3<f64>>, ExactModes) {
    exact_response_by(k, m, dim, damping, loads.len(), dt, |u, s| {
        (0..dim).map(|r| u[r] * loads[s][r]).sum()
    })
}

/// As [`exact_response`] for any load on the whole model: `modal_force(u, s)` is the force
/// uᵀP(t_s) of the load P at sample s on the mass-normalised mode u (every DOF), over
/// `samples` samples.
pub fn exact_response_by(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    samples: usize,
    dt: f64,
    modal_force: impl Fn(&DVector<f64>, usize) -> f64,
) -> (Vec<Vector3<f64>>, ExactModes) {
    let (lambda, u) = dense_eig(k, m);
    let mut out = vec![Vector3::zeros(); samples];
    let mut info = ExactModes {
        count: lambda.len(),
        overdamped: 0,
        zeta_max: 0.0,
    };
    for (j, &l) in lambda.iter().enumerate() {
        let w = l.sqrt();
        let z = zeta_of(damping, w);
        info.overdamped += usize::from(z > 1.0);
        info.zeta_max = info.zeta_max.max(z);
        let uj: DVector<f64> = u.column(j).into_owned();
        let mut phi = Vector6::zeros();
        for (r, v) in phi.iter_mut().enumerate().take(dim) {
            *v = uj[r];
        }
        #[rustfmt::skip]
        let a = Matrix4::new(
            0.0, w, 0.0, 0.0,
            -w, -2.0 * z * w, w, 0.0,
            0.0, 0.0, 0.0, 1.0,
            0.0, 0.0, 0.0, 0.0,
        );
        let prop = (a * dt).exp();
        let g: Vec<f64> = (0..samples).map(|s| modal_force(&uj, s)).collect();
        let mut x = Vector4::new(0.0, 0.0, g[0] / w, 0.0);
        for (s, o) in out.iter_mut().enumerate().skip(1) {
            // The ramp of this interval: ġ/ω set at its start, g/ω carried (continuous).
            x[2] = g[s - 1] / w;
            x[3] = (g[s] - g[s - 1]) / dt / w;
            x = prop * x;
            *o += phi.fixed_rows::<3>(0) * (x[0] / w);
        }
    }
    (out, info)
}

/// The exact response of the whole robot to a prescribed end-effector motion with
/// accelerations `acc` (m/s², translation) at the samples: the influence field
/// r = [I; −K_ii⁻¹ K_ie] by an LU solve of the dense K (DOF 0..`dim` the end-effector), the
/// load −M r a on every DOF (the relative-motion problem M ü + C u̇ + K u = −M r a), every
/// mode propagated as [`exact_response_by`]; also the quasi-static mass rᵀ M r (kg).
pub fn exact_whole_robot(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    acc: &[Vector3<f64>],
    dt: f64,
) -> (Vec<Vector3<f64>>, ExactModes, DMatrix<f64>) {
    let n = k.nrows();
    let kii = k.view((dim, dim), (n - dim, n - dim)).into_owned();
    let kie = k.view((dim, 0), (n - dim, dim)).into_owned();
    let mut r = DMatrix::<f64>::zeros(n, dim);
    for d in 0..dim {
        r[(d, d)] = 1.0;
    }
    let ri = kii.lu().solve(&kie).expect("K_ii regular");
    r.view_mut((dim, 0), (n - dim, dim)).copy_from(&(-ri));
    exact_with_field(k, m, dim, damping, &r, acc, dt)
}

/// As [`exact_whole_robot`] with the field `r` given (n × 3: every DOF's motion per unit
/// end-effector translation; a sagging robot's path field, `crate::sag_field`).
pub fn exact_with_field(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    r: &DMatrix<f64>,
    acc: &[Vector3<f64>],
    dt: f64,
) -> (Vec<Vector3<f64>>, ExactModes, DMatrix<f64>) {
    let mr = m * r;
    let mqs = r.transpose() * &mr;
    let (u, info) = exact_response_by(k, m, dim, damping, acc.len(), dt, |u, s| {
        let l = u.transpose() * &mr;
        -(0..3).map(|d| l[d] * acc[s][d]).sum::<f64>()
    });
    (u, info, mqs)
}

/// max |a − b| / max |b| over the samples (translation norms).
pub fn relative_error(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    let peak = b.iter().fold(0.0f64, |p, x| p.max(x.norm()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |e, (x, y)| e.max((x - y).norm()))
        / peak
}

/// −M_ee [a; 0] at the samples of a move of `d` (m) in `t` s (S-curve), then `rest` s,
/// every `dt` (central differences, at rest beyond the ends): the inertial load of the
/// quasi-static motion on the end-effector.
pub fn move_loads(
    ee_mass: &Matrix6<f64>,
    d: Vector3<f64>,
    t: f64,
    rest: f64,
    dt: f64,
) -> Vec<Vector6<f64>> {
    move_accelerations(d, t, rest, dt)
        .iter()
        .map(|a| -(ee_mass * Vector6::new(a.x, a.y, a.z, 0.0, 0.0, 0.0)))
        .collect()
}

/// The accelerations (m/s²) of [`move_loads`]' move at its samples.
pub fn move_accelerations(d: Vector3<f64>, t: f64, rest: f64, dt: f64) -> Vec<Vector3<f64>> {
    let mv = Move::new(Vector3::zeros(), d, t, Profile::SCurve).unwrap();
    let p = mv.sampled(dt, rest).unwrap().position_m;
    let n = p.len();
    (0..n)
        .map(|k| {
            let prev = p[k.saturating_sub(1)];
            let next = p[(k + 1).min(n - 1)];
            (next - p[k] * 2.0 + prev) / (dt * dt)
        })
        .collect()
}

/// The crate's response (translation) of the first `kk` modes (a cluster cut completed)
/// of the estimator's pose with the static correction, and the modes it kept; `whole`: the
/// end-effector load `loads` (−M_ee a) taken through the basis's load shapes (the whole
/// robot's quasi-static inertia, as `simulate`), else on the end-effector alone.
pub fn crate_response(
    est: &mut Estimator,
    kk: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt: f64,
    whole: bool,
) -> (Vec<Vector3<f64>>, usize) {
    crate_response_with(est, kk, damping, loads, None, dt, whole)
}

/// [`crate_response`] (the whole robot's load) with a sagging robot's convective load of
/// the path's velocities `velocities` (m/s, one per sample) added through the crate's
/// second response (`study::simulate::added_load`, as `simulate` adds it); panics where
/// the basis has no second field.
pub fn crate_response_convective(
    est: &mut Estimator,
    kk: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    velocities: &[Vector3<f64>],
    dt: f64,
) -> (Vec<Vector3<f64>>, usize) {
    crate_response_with(est, kk, damping, loads, Some(velocities), dt, true)
}

fn crate_response_with(
    est: &mut Estimator,
    kk: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    velocities: Option<&[Vector3<f64>]>,
    dt: f64,
    whole: bool,
) -> (Vec<Vector3<f64>>, usize) {
    let b = est.ee_modal_basis(kk).unwrap();
    let mut r = ModalResponse::new(b.dim);
    r.set_basis(&b.lambda, &b.phi_ee, damping, &b.flexibility, &b.ee_mass)
        .unwrap_or_else(|e| panic!("{damping:?}: {e}"));
    if whole {
        r.set_load_shapes(&b.load_ee, &b.load_flexibility).unwrap();
    }
    let mut c = AddedLoad::new(AddedKind::Convective);
    if velocities.is_some() {
        c.install(&b, None, damping).unwrap();
        assert!(c.is_on(), "the basis has the convective load");
    }
    let g = |s: usize| velocities.map_or(Vector6::zeros(), |v| convective_force(&v[s]));
    let flex = b.convective_flexibility;
    let at = |r: &ModalResponse, c: &AddedLoad, s: usize| {
        r.displacement(&loads[s]).fixed_rows::<3>(0).into_owned()
            + c.displacement_with(&g(s), &flex)
    };
    let mut out = vec![at(&r, &c, 0)];
    for s in 1..loads.len() {
        r.step(&loads[s - 1], &loads[s], dt);
        c.step(&g(s - 1), &g(s), dt);
        out.push(at(&r, &c, s));
    }
    (out, b.lambda.len())
}

/// What [`default_choice`] measured.
#[derive(Debug)]
pub struct DefaultChoice {
    /// Modes the crate chose for the default tolerance.
    pub modes: usize,
    /// Its truncation estimate relative to the peak.
    pub estimate: f64,
    /// The crate's response with them against the exact one: max error / peak.
    pub error: f64,
    /// The exact response's peak |translation|, m.
    pub peak_m: f64,
    /// The dense model's modes, overdamped ones, largest ζ.
    pub exact: ExactModes,
}

/// At the estimator's pose: the modes `simulate` chooses by default
/// (`study::simulate::pilot::choose` at the default tolerance), the crate's response with
/// them (the whole robot's inertia, as `simulate`), and its error against
/// [`exact_whole_robot`] of the dense (K, M) (DOF 0..`dim` the end-effector) under the
/// path's accelerations `acc` (`loads` = −M_ee a of the same). Sagging models (a point mass
/// without pulleys) are loaded along the path's field instead of the fixed-length one (the
/// crate's `modal::quasi_static` docs): for them the field is [`crate::sag_field`]'s
/// reference at the estimator's pose and the reference [`exact_with_field`].
#[allow(clippy::too_many_arguments)]
pub fn default_choice(
    est: &mut Estimator,
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    acc: &[Vector3<f64>],
    loads: &[Vector6<f64>],
    dt: f64,
) -> DefaultChoice {
    let c = pilot::choose(est, damping, loads, dt, pilot::DEFAULT_TOLERANCE, None).unwrap();
    assert!(c.met, "the choice reports it missed the tolerance: {c:?}");
    let (got, kept) = crate_response(est, c.modes, damping, loads, dt, true);
    assert_eq!(kept, c.modes, "the choice ends a cluster");
    let (exact, info) = if est.scene().model.sag {
        let scene = est.scene().clone();
        let p = est.loaded_pose().expect("an ok cycle").position_m;
        let n = scene.model.elements_per_cable;
        let r = crate::sag_field::dense_reference_field(&scene, p, n, k.nrows());
        let (exact, info, _) = exact_with_field(k, m, dim, damping, &r, acc, dt);
        (exact, info)
    } else {
        let (exact, info, _) = exact_whole_robot(k, m, dim, damping, acc, dt);
        (exact, info)
    };
    DefaultChoice {
        modes: c.modes,
        estimate: c.estimate,
        error: relative_error(&got, &exact),
        peak_m: exact.iter().fold(0.0f64, |a, x| a.max(x.norm())),
        exact: info,
    }
}

/// The dampings of the default-choice checks: ζ = 2 %, Rayleigh with the high modes
/// overdamped, every mode overdamped.
pub const DEFAULT_CASES: [Damping; 3] = [
    Damping::ModalRatio { zeta: 0.02 },
    Damping::Rayleigh {
        alpha_per_s: 0.5,
        beta_s: 2e-4,
    },
    Damping::ModalRatio { zeta: 1.5 },
];

/// The default choice at the estimator's pose for each of [`DEFAULT_CASES`] under the
/// inertial load of a move of `d` (m) in 0.3 s then 0.2 s at rest, 1 ms samples: within
/// the default tolerance (1e-3 of the peak) of the exact response of the dense (K, M) to
/// the prescribed motion ([`exact_whole_robot`]).
pub fn assert_default_within_tolerance(
    label: &str,
    est: &mut Estimator,
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    d: Vector3<f64>,
) {
    let dt = 1e-3;
    let b = est.ee_modal_basis(1).unwrap();
    let loads = move_loads(&b.ee_mass, d, 0.3, 0.2, dt);
    let acc = move_accelerations(d, 0.3, 0.2, dt);
    for damping in &DEFAULT_CASES {
        let c = default_choice(est, k, m, b.dim, damping, &acc, &loads, dt);
        println!(
            "{label} {damping:?}: chose K = {} of {} (estimate {:.2e}), {} overdamped (ζ max {:.2}): peak {:.4e} m, max error / peak {:.2e}",
            c.modes, c.exact.count, c.estimate, c.exact.overdamped, c.exact.zeta_max, c.peak_m, c.error
        );
        assert!(
            c.error <= pilot::DEFAULT_TOLERANCE,
            "{label} {damping:?}: {:e} over the tolerance {:e}",
            c.error,
            pilot::DEFAULT_TOLERANCE
        );
    }
}

/// `simulate`'s default basis-update policy on `path` against a run updating the modes at
/// every sample with the same K (settling `settle_s` after a path at rest): the largest
/// difference relative to that run's peak, asserted within the default tolerance, and the
/// policy's updates asserted fewer than `at_most` of that run's. Prints both.
pub fn assert_update_policy_within_tolerance(
    name: &str,
    scene: &cablevib::scene::Scene,
    path: &cablevib::study::simulate::SampledPath,
    settle_s: f64,
    at_most: f64,
) -> f64 {
    use cablevib::study::simulate::{simulate, SimulateConfig};
    let default = SimulateConfig {
        settle_s,
        ..SimulateConfig::default()
    };
    let chosen = simulate(scene, path, &default).unwrap();
    let every = SimulateConfig {
        modes: Some(chosen.modes),
        update_every: Some(1),
        ..default
    };
    let reference = simulate(scene, path, &every).unwrap();
    assert_eq!(reference.modes, chosen.modes);
    let peak = reference
        .deviation_m
        .iter()
        .fold(0.0f64, |a, u| a.max(u.norm()));
    let err = chosen
        .deviation_m
        .iter()
        .zip(&reference.deviation_m)
        .fold(0.0f64, |a, (x, y)| a.max((x - y).norm()))
        / peak;
    println!(
        "{name}: K = {}, {} updates (every sample: {}), predicted largest interval error {:.2e}, max |default − every sample| / peak {err:.2e}",
        chosen.modes, chosen.updates, reference.updates, chosen.accuracy.interval_estimate
    );
    assert!(
        (chosen.updates as f64) < at_most * reference.updates as f64,
        "{name}: the policy saves updates ({} of {})",
        chosen.updates,
        reference.updates
    );
    assert!(err <= pilot::DEFAULT_TOLERANCE, "{name}: {err:e}");
    err
}
