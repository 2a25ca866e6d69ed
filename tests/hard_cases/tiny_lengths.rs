//! A pulley radius or a hidden length from 5e-324 to 1e-3 m on one cable: every path (the
//! real-time estimator the service runs, the offline estimator's first modes, the dense
//! reference) answers continuously with the radius-0 / no-hidden-cable model, or refuses;
//! none says ok with a non-finite or absurd number. The part behind the exit point whose
//! compliance is below `BEHIND_EXIT_COMPLIANCE_FLOOR` of the free cable's is taken as 0
//! (docs/hidden-cable.md); above it, the exact model.
//!
//! **Tolerance** (against the same scene with the value 0). The part behind cable 0's exit
//! point has length ℓ ≤ 2π·R (a wrapped arc) or ℓ = hidden length, of the free cable's EA
//! and μ. In series with the free cable of length L it lowers that cable's axial stiffness by
//! at most ℓ/L relative and adds at most μℓ of mass, so (Rayleigh quotients) every
//! eigenvalue moves by at most 2ℓ/L_min relative, its frequency by ℓ/L_min; plus the
//! solver's tolerance (1e-12 on λ, 1e-10 allowed). The dense reference adds its own bound
//! 8ε·λ_max/λ, or refuses when that bound leaves no digit.

use cablevib::estimator::{Estimator, EstimatorParams, Status, Tmin, MAX_EIGEN_RESIDUAL};
use cablevib::kinematics::Pose;
use cablevib::modal::{dense_relative_accuracy, hz_to_lambda, Mode};
use cablevib::scene::Scene;
use cablevib::study::analysis::{analyze, AnalyzeOptions, SolverChoice};

/// Modes compared on the structured and dense paths.
const MODES: usize = 12;
/// Cycles of the service's estimator at the pose.
const SERVICE_CYCLES: usize = 50;

/// The values tried (m): the subnormal floor, far below the compliance floor, across it, and
/// a millimetre.
const VALUES_M: [f64; 14] = [
    5e-324, 1e-300, 1e-200, 1e-150, 1e-140, 1e-100, 1e-50, 1e-20, 1e-13, 1e-12, 1e-11, 1e-9, 1e-6,
    1e-3,
];

/// `file` of scenes/ at N = 10 with `line` added after the first cable's anchor (or the
/// first pulley's radius replaced by `radius`).
fn scene(file: &str, edit: &dyn Fn(String) -> String) -> Scene {
    let path = format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let text = edit(text).replace("elements_per_cable = 40", "elements_per_cable = 10");
    Scene::from_toml_str(&text, file).unwrap()
}

fn with_radius(r: f64) -> Scene {
    scene("spatial_paper_pulleys.toml", &|t: String| {
        t.replacen("radius = 0.05", &format!("radius = {r:e}"), 1)
    })
}

fn with_hidden(l: f64) -> Scene {
    scene("spatial_paper.toml", &|t: String| {
        let anchor = "anchor = [1.25, 1.25, 2.5]";
        t.replacen(anchor, &format!("{anchor}\nhidden_length = {l:e}"), 1)
    })
}

/// What one scene gives on each path.
struct Answers {
    /// The estimator's first cycle (what `analyze --realtime` prints): status, f1 and
    /// end-effector mode (Hz), eigen residual.
    realtime: (Status, f64, f64, f64),
    /// The same for each cycle of the service's estimator (`EstimatorParams::realtime`).
    service: Vec<(Status, f64, f64, f64)>,
    /// The offline estimator's first modes (λ, participation).
    structured: Vec<(f64, f64)>,
    /// The dense reference's λ and its bound ε·λ_max/λ₁, or its refusal.
    dense: Result<(Vec<f64>, f64), String>,
}

fn answers(s: &Scene) -> Answers {
    let pose = Pose::in_scene(s, s.ee_position_m);
    let mut off = Estimator::new(s).unwrap();
    let e = *off.update(&pose, Tmin::Scene);
    let realtime = (
        e.status,
        e.f1_hz,
        cablevib_testkit::ee_hz(&e),
        e.eigen_residual,
    );
    // The service's estimator: its per-cycle budget may spread the end-effector mode over
    // a few cycles at one pose; every cycle is checked, the last one kept.
    let mut rt = Estimator::with_params(s, EstimatorParams::realtime()).unwrap();
    let mut service = Vec::new();
    for _ in 0..SERVICE_CYCLES {
        let e = *rt.update(&pose, Tmin::Scene);
        service.push((
            e.status,
            e.f1_hz,
            cablevib_testkit::ee_hz(&e),
            e.eigen_residual,
        ));
    }
    let mut modes = vec![Mode::default(); MODES];
    let n = off.modes(MODES, &mut modes).unwrap();
    let structured = modes[..n]
        .iter()
        .map(|m| (m.lambda, m.ee_participation))
        .collect();
    let opts = AnalyzeOptions {
        modes: MODES,
        solver: SolverChoice::Dense,
        compare_dense: false,
    };
    let dense = analyze(s, &opts).map_err(|e| e.to_string()).map(|r| {
        let l: Vec<f64> = r.frequencies_hz.iter().map(|&f| hz_to_lambda(f)).collect();
        let lambda_max = off.dense_modes(false).unwrap().lambda_max;
        let bound = dense_relative_accuracy(l[0], lambda_max);
        (l, bound)
    });
    Answers {
        realtime,
        service,
        structured,
        dense,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Every path against the value-0 scene, for the radius of one pulley and for a hidden
/// length (module docs for the tolerance). Before the floor and the checks, a radius of
/// 1e-150 m gave ok with an eigen residual of 7.9e301 and no end-effector mode, 1e-300 a NaN
/// residual and stiffness, the offline modes NaN participations, and the dense reference
/// NaN frequencies from 1e-6 m down.
#[test]
fn tiny_radius_or_hidden_length_answers_as_zero_or_refuses() {
    let l_min_m = 2.0; // the free cables at the default pose are 2.06 .. 2.38 m
    for (name, make, arc_per_m) in [
        (
            "radius",
            with_radius as fn(f64) -> Scene,
            std::f64::consts::TAU,
        ),
        ("hidden_length", with_hidden as fn(f64) -> Scene, 1.0),
    ] {
        let zero = answers(&make(0.0));
        let (st0, f1_0, ee_0, _) = zero.realtime;
        assert_eq!(st0, Status::Ok);
        let Ok((dense0, _)) = &zero.dense else {
            panic!("{name} = 0: dense refused: {:?}", zero.dense.err())
        };
        for v in VALUES_M {
            let label = format!("{name} = {v:e} m");
            let tol = arc_per_m * v / l_min_m + 1e-10;
            let a = answers(&make(v));
            // The estimator's cycle, and every cycle of the service's: ok, its residual
            // checked, f1 and the end-effector mode continuous with the value 0 (the
            // service's mode where it has one: its bounded scan may leave it unknown, NaN,
            // on the symmetric paper robot, with or without the tiny part).
            for (k, &(st, f1, ee_k, res)) in
                std::iter::once(&a.realtime).chain(&a.service).enumerate()
            {
                let label = format!("{label}, cycle {k}");
                assert_eq!(st, Status::Ok, "{label}");
                assert!(res <= MAX_EIGEN_RESIDUAL, "{label}: residual {res:e}");
                assert!(rel(f1, f1_0) <= tol, "{label}: f1 {f1} vs {f1_0}");
                if k == 0 || ee_k.is_finite() {
                    assert!(rel(ee_k, ee_0) <= tol, "{label}: ee mode {ee_k} vs {ee_0}");
                }
            }
            // The offline modes: finite participations, eigenvalues within 2·tol.
            assert_eq!(a.structured.len(), zero.structured.len(), "{label}");
            for (j, (&(l, p), &(l0, _))) in a.structured.iter().zip(&zero.structured).enumerate() {
                assert!(
                    p.is_finite() && (0.0..=1.0).contains(&p),
                    "{label}: p{j} {p}"
                );
                assert!(rel(l, l0) <= 2.0 * tol, "{label}: λ{j} {l} vs {l0}");
            }
            // The dense reference: continuous within its bound, or a refusal naming the
            // structured solver.
            match &a.dense {
                Ok((l, bound)) => {
                    for (j, (&l, &l0)) in l.iter().zip(dense0).enumerate() {
                        let t = 2.0 * tol + 8.0 * bound.max(f64::EPSILON * 1e3);
                        assert!(
                            rel(l, l0) <= t,
                            "{label}: dense λ{j} {l} vs {l0} (tol {t:e})"
                        );
                    }
                }
                Err(e) => {
                    assert!(e.contains("structured solver"), "{label}: {e}");
                    assert!(!e.contains('\n'), "{label}: {e}");
                }
            }
            println!(
                "{label}: f1 {:.3e}, ee {:.3e} from the value 0; dense {}",
                rel(a.realtime.1, f1_0),
                rel(a.realtime.2, ee_0),
                match &a.dense {
                    Ok((_, b)) => format!("answers (bound {b:.1e})"),
                    Err(_) => "refuses".into(),
                }
            );
        }
    }
}

/// The estimator's check of its own answer (the guard behind every ok, whatever overflows
/// next): the values the tiny radius produced before the floor (a residual of 7.9e301, NaN
/// residual and stiffness) are refused with status `not_converged` and a one-line reason
/// naming what failed; a sound answer passes.
#[test]
fn an_answer_with_a_non_finite_or_absurd_internal_is_never_ok() {
    use cablevib::estimator::{check_answer, EstimatorError};
    use nalgebra::Matrix6;
    let k = Matrix6::identity() * 1.2e6;
    let m = Matrix6::identity() * 30.0;
    assert!(check_answer(5.1e3, 2e-15, 2e-5, &k, &m).is_ok());
    assert!(check_answer(5.1e3, 0.0, 0.0, &k, &m).is_ok());
    // A root far below the stiffness's scale (T_min = 1e-100 N on the paper robot: λ₁ 8e-98,
    // exact, residual 2.4e75 from rounding in D) passes.
    assert!(check_answer(8.2e-98, 2.4e75, 0.0, &k, &m).is_ok());
    let mut nan_k = k;
    nan_k[(1, 2)] = f64::NAN;
    for (lambda, residual, p, k6, what) in [
        (5.1e3, 7.876e301, 0.0, k, "residual"),
        (5.1e3, f64::NAN, 0.0, k, "residual"),
        (5.1e3, 2.0 * MAX_EIGEN_RESIDUAL, 0.0, k, "residual"),
        (8.2e-98, 1e100, 0.0, k, "residual"),
        (f64::NAN, 0.0, 0.0, k, "first eigenvalue"),
        (-1.0, 0.0, 0.0, k, "first eigenvalue"),
        (f64::INFINITY, 0.0, 0.0, k, "first eigenvalue"),
        (5.1e3, 0.0, f64::NAN, k, "participation"),
        (5.1e3, 0.0, 0.0, nan_k, "static stiffness"),
    ] {
        let e = check_answer(lambda, residual, p, &k6, &m).unwrap_err();
        assert!(matches!(e, EstimatorError::Unverified { .. }), "{e:?}");
        assert_eq!(e.status(), Status::NotConverged);
        let msg = e.to_string();
        assert!(msg.contains(what) && !msg.contains('\n'), "{msg}");
    }
}
