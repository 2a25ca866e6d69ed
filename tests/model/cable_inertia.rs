//! The cables' inertial load in the time response, against the whole robot's dense model
//! loaded by the prescribed end-effector motion.
//!
//! The reference is written here: at a frozen pose, the dense (K, M) of the whole robot
//! (the paper robot's taut FEM assembled from the scene's numbers, `hidden_cable::dense_ref`;
//! for the sagging robot the crate's dense sagged assembly, `Estimator::dense_matrices`,
//! independent of the structured shapes the response uses), its influence field
//! r = [I; −K_ii⁻¹ K_ie] by an LU solve of the dense K, the load −M r a(t) of the path's
//! acceleration on every DOF, and every mode propagated exactly
//! (`exact_response::exact_whole_robot`). The crate's response is its modal superposition
//! of the structured shapes with the load shapes of `ee_modal_basis` (participation factors
//! φ_kᵀ M r from the structured shapes and the structured influence field).
//!
//! Scenes: the paper robot (fem × 10) at the centre and off-centre and the same robot with
//! 10× the cable mass per length (a heavy-cable robot). Sagging robots, loaded along the
//! path's field instead of the fixed-length one: `sag_path_field.rs`. The move: an S-curve
//! of (0.1, 0.2, −0.15) m in 0.3 s, then 0.2 s at rest, 1 ms samples, ζ = 2 %.

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{Damping, ElementKind, Scene};
use cablevib::study::simulate::pilot::{self, DEFAULT_TOLERANCE};
use cablevib_testkit::exact_response::{
    crate_response, exact_response, exact_whole_robot, move_accelerations, move_loads,
    relative_error,
};
use nalgebra::{DMatrix, Vector3};

use crate::hidden_cable::dense_ref;

const DT: f64 = 1e-3;
const DAMPING: Damping = Damping::ModalRatio { zeta: 0.02 };

/// The paper robot (fem × 10) with its cables' mass per length × `mass_factor`, at `p`:
/// its estimator and the test's own dense (K, M) at the estimator's tensions.
fn paper_at(p: Vector3<f64>, mass_factor: f64) -> (Estimator, DMatrix<f64>, DMatrix<f64>) {
    let mut s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    for c in &mut s.cables {
        c.mass_per_length_kg_m *= mass_factor;
    }
    let mut est = Estimator::new(&s).unwrap();
    let e = *est.update(&Pose::at(p), Tmin::Scene);
    assert!(e.is_ok(), "{p:?}: {:?}", e.error);
    let (k, m) = dense_ref(&s, &p, e.tensions(), 10, false);
    (est, k, m)
}

fn peak(u: &[Vector3<f64>]) -> f64 {
    u.iter().fold(0.0f64, |a, x| a.max(x.norm()))
}

/// What one scene measured.
struct Measured {
    /// The crate's response with the cables' load against the exact whole robot: every
    /// mode kept (None: not run), and the default K.
    all_modes: Option<f64>,
    default_k: (usize, f64),
    /// The end-effector-only model (today's before this term) against the exact whole
    /// robot, both exact: max difference / peak.
    model_difference: f64,
    /// Peaks of the whole robot's and the end-effector-only response, m.
    peaks_m: (f64, f64),
}

/// The checks of the module docs on one scene; `all_modes`: also with every mode kept.
fn check(
    label: &str,
    est: &mut Estimator,
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    d: Vector3<f64>,
    all_modes: bool,
) -> Measured {
    let acc = move_accelerations(d, 0.3, 0.2, DT);
    let ee_mass = est.ee_modal_basis(1).unwrap().ee_mass;
    let loads = move_loads(&ee_mass, d, 0.3, 0.2, DT);
    let (exact, _, mqs_dense) = exact_whole_robot(k, m, 3, &DAMPING, &acc, DT);
    let mqs_dense = mqs_dense[(0, 0)];
    let (ee_only, _) = exact_response(k, m, 3, &DAMPING, &loads, DT);
    let all = all_modes.then(|| {
        let (got, kept) = crate_response(est, k.nrows(), &DAMPING, &loads, DT, true);
        assert_eq!(kept, k.nrows(), "{label}: every mode kept");
        relative_error(&got, &exact)
    });
    let c = pilot::choose(est, &DAMPING, &loads, DT, DEFAULT_TOLERANCE, None).unwrap();
    let (got, kept) = crate_response(est, c.modes, &DAMPING, &loads, DT, true);
    let mqs = est.ee_modal_basis(1).unwrap().quasi_static_mass_kg[(0, 0)];
    let default_err = relative_error(&got, &exact);
    // The quasi-static mass: the structured field's against the dense solve's (rounding
    // of the two O(N) sums; a wrong field is off by a share of the cables' mass).
    assert!(
        (mqs - mqs_dense).abs() <= 1e-9 * mqs_dense,
        "{label}: M_qs {mqs} vs {mqs_dense} kg"
    );
    let (today, _) = crate_response(est, c.modes, &DAMPING, &loads, DT, false);
    let today_err = relative_error(&today, &exact);
    let out = Measured {
        all_modes: all,
        default_k: (kept, default_err),
        model_difference: relative_error(&ee_only, &exact),
        peaks_m: (peak(&exact), peak(&ee_only)),
    };
    println!(
        "{label}: M_ee {:.3} kg, M_qs(x) {mqs:.4} kg (dense {mqs_dense:.4}); every mode: {:?}; default K = {kept}: {default_err:.2e} (end-effector load only, same K: {today_err:.2e}); peak whole robot {:.5e} m, end-effector only {:.5e} m ({:+.2} %), max difference / peak {:.2e}",
        ee_mass[(0, 0)],
        out.all_modes,
        out.peaks_m.0,
        out.peaks_m.1,
        100.0 * (out.peaks_m.1 / out.peaks_m.0 - 1.0),
        out.model_difference
    );
    out
}

/// Every mode kept, the crate's response with the cables' load equals the exact whole
/// robot's to 1e-9 of the peak (the structured shapes and field against the dense
/// eigen-solve and LU solve of the same FEM, and the exponential's rounding over 500
/// steps, as in `vibration_exact`: there measured 5e-12 to 2.4e-11; a wrong or missing
/// term of the load is of the size of the cables' share of M_qs, ≥ 3e-3 of the peak here);
/// with the default K within the default tolerance 1e-3 (the pilot's estimate, which now
/// includes the load shapes). The end-effector-only load (the model before this term)
/// misses it by more than the tolerance on the heavy robot (it fails this test's
/// assertions): the term's size, measured.
#[test]
fn cable_inertia_matches_the_dense_whole_robot_on_the_paper_robot() {
    let d = Vector3::new(0.1, 0.2, -0.15);
    for p in [Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.3, 0.2, 1.0)] {
        let (mut est, k, m) = paper_at(p, 1.0);
        let r = check(&format!("paper {p:?}"), &mut est, &k, &m, d, true);
        assert!(r.all_modes.unwrap() < 1e-9, "{p:?}: {:?}", r.all_modes);
        assert!(
            r.default_k.1 <= DEFAULT_TOLERANCE,
            "{p:?}: {:?}",
            r.default_k
        );
    }
}

/// The heavy-cable robot (the paper robot with 10× the cable mass per length): as above,
/// and the end-effector-only model off by more than 10× the tolerance.
#[test]
fn cable_inertia_matches_the_dense_whole_robot_with_heavy_cables() {
    let d = Vector3::new(0.1, 0.2, -0.15);
    let (mut est, k, m) = paper_at(Vector3::new(0.3, 0.2, 1.0), 10.0);
    let r = check("paper, 10x cable mass", &mut est, &k, &m, d, true);
    assert!(r.all_modes.unwrap() < 1e-9, "{:?}", r.all_modes);
    assert!(r.default_k.1 <= DEFAULT_TOLERANCE, "{:?}", r.default_k);
    assert!(
        r.model_difference > 10.0 * DEFAULT_TOLERANCE,
        "the cables' load is {:e} of the peak",
        r.model_difference
    );
}
