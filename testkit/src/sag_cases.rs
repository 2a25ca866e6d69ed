//! The sagging robots of the sag tests (tests/sag/, cli/tests/models/hard_cases_sag.rs), a
//! short way to analyse one of them at a pose, and the sagged robots with FEM chains
//! ([`sagged_robots`]) with an estimator loaded at their own pose ([`loaded`]).
//!
//! - `fast-like` and `suspended-8`: the shipped scenes (scenes/fast_like.toml,
//!   scenes/suspended_8.toml) at the centre and off-centre poses their comments suggest.
//! - [`heavy_paper`]: the paper's spatial robot (scenes/spatial_paper.toml) with a cable 50×
//!   heavier (γ = 12.55 N/m instead of 0.251 N/m), t_min = 30 N and `[effects] sag = true`:
//!   the lower cables (anchors on the floor, ~2.1 m long, weighing ~26 N at ≲ 30 N of
//!   tension) are very slack, with their lowest point between their ends at the centre.
//!   Its off-centre pose (+0.3, +0.2, 0) m from the centre is feasible; (+0.5, −0.3, +0.2) m
//!   makes cable 5 slack.
use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene, DEFAULT_SCENE_TOML};
use cablevib::study::analysis::{analyze, AnalysisReport, AnalyzeOptions};
use nalgebra::{Matrix3, Vector3};

/// The paper's spatial scene file (the embedded default scene).
const SPATIAL_PAPER_TOML: &str = include_str!("../../scenes/spatial_paper.toml");

/// 50 × the paper's 0.251 N/m.
pub const HEAVY_WEIGHT_PER_LENGTH_N_M: f64 = 12.55;
/// The heavy robot's lower tension bound, N.
pub const HEAVY_T_MIN_N: f64 = 30.0;
/// The heavy robot's centre (the paper's default pose), m.
pub const HEAVY_CENTRE_M: [f64; 3] = [0.0, 0.0, 1.25];
/// A feasible off-centre pose of the heavy robot: (+0.3, +0.2, 0) m from the centre.
pub const HEAVY_OFF_CENTRE_M: [f64; 3] = [0.3, 0.2, 1.25];
/// A pose of the heavy robot where cable 5 goes slack: (+0.5, −0.3, +0.2) m from the centre.
pub const HEAVY_SLACK_M: [f64; 3] = [0.5, -0.3, 1.45];

/// The sagging scenes' suggested poses (their files' comments): (name, centre, off-centre).
pub const SHIPPED_POSES: [(&str, [f64; 3], [f64; 3]); 2] = [
    ("fast-like", [0.0, 0.0, 0.0], [60.0, 30.0, 10.0]),
    ("suspended-8", [0.0, 0.0, 2.0], [4.0, 2.5, 1.5]),
];

/// The TOML text of the heavy paper robot (see the module docs).
pub fn heavy_paper_toml() -> String {
    let swap = |text: &str, from: &str, to: &str| {
        assert!(text.contains(from), "spatial_paper.toml lost `{from}`");
        text.replacen(from, to, 1)
    };
    let t = swap(
        SPATIAL_PAPER_TOML,
        "weight_per_length = 0.251",
        &format!("weight_per_length = {HEAVY_WEIGHT_PER_LENGTH_N_M}"),
    );
    let t = swap(&t, "t_min = 60.0", &format!("t_min = {HEAVY_T_MIN_N}"));
    let t = t.replacen("[effects]\nsag = false", "[effects]\nsag = true", 1);
    assert!(
        t.contains("[effects]\nsag = true"),
        "spatial_paper.toml lost its sag line"
    );
    t
}

/// The heavy paper robot (see the module docs), checked to be the paper's robot otherwise.
pub fn heavy_paper() -> Scene {
    let s = Scene::from_toml_str(&heavy_paper_toml(), "<heavy paper robot>").expect("heavy");
    let paper = Scene::default_scene();
    assert_eq!(s.cables.len(), paper.cables.len());
    for (c, p) in s.cables.iter().zip(&paper.cables) {
        assert_eq!(c.anchor_m, p.anchor_m);
        assert_eq!(c.ea_n(), p.ea_n());
        let ratio = c.mass_per_length_kg_m / p.mass_per_length_kg_m;
        assert!((ratio - 50.0).abs() <= 1e-12, "{ratio}");
    }
    assert!(s.model.sag && s.t_min_n == HEAVY_T_MIN_N);
    s
}

/// `scene` at `position_m` with `element` and `n` elements per cable.
pub fn at(scene: &Scene, position_m: [f64; 3], element: ElementKind, n: usize) -> Scene {
    let mut s = scene.with_model(element, n);
    s.ee_position_m = Vector3::from(position_m);
    s
}

/// The library's analysis (structured solver, `modes` frequencies) of `scene` at a pose.
pub fn analyze_at(
    scene: &Scene,
    position_m: [f64; 3],
    element: ElementKind,
    n: usize,
    modes: usize,
) -> AnalysisReport {
    let s = at(scene, position_m, element, n);
    let opts = AnalyzeOptions {
        modes,
        ..AnalyzeOptions::default()
    };
    analyze(&s, &opts).unwrap_or_else(|e| panic!("{} at {position_m:?}: {e}", s.name))
}

/// The principal values (eigenvalues, ascending) of a report's 3 × 3 stiffness, N/m.
pub fn principal_n_m(r: &AnalysisReport) -> Vec<f64> {
    let k = Matrix3::from_fn(|i, j| r.stiffness_n_m[i][j]);
    let mut v: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    v.sort_by(f64::total_cmp);
    v
}

/// |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The largest relative difference of two lists (compared up to the shorter's length).
pub fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| rel(*x, *y))
        .fold(0.0, f64::max)
}

/// A scene file of the repository's scenes/ (e.g. `suspended_8.toml`).
pub fn shipped(file: &str) -> Scene {
    let path = format!("{}/../scenes/{file}", env!("CARGO_MANIFEST_DIR"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The paper's spatial robot (the embedded default scene) with `[effects] sag = true`, its
/// other effects at their defaults; named `spatial-paper-sag`.
pub fn paper_with_sag() -> Scene {
    let text = format!(
        "{}\n[effects]\nsag = true\n",
        crate::without_effects(DEFAULT_SCENE_TOML)
    );
    Scene::from_toml_str(&text, "spatial-paper-sag").expect("paper robot with sag")
}

/// `scene` with sag on and `n` FEM elements per cable.
pub fn sagged_fem(mut scene: Scene, n: usize) -> Scene {
    scene.model.sag = true;
    scene.model.element = ElementKind::Fem;
    scene.model.elements_per_cable = n;
    scene
}

/// The three sagging robots, `n` FEM elements per cable: suspended-8, fast-like
/// (scenes/suspended_8.toml, scenes/fast_like.toml) and the paper's spatial robot with sag
/// ([`paper_with_sag`]).
pub fn sagged_robots(n: usize) -> [Scene; 3] {
    [
        shipped("suspended_8.toml"),
        shipped("fast_like.toml"),
        paper_with_sag(),
    ]
    .map(|s| sagged_fem(s, n))
}

/// The scene's own pose: its end-effector position and orientation.
pub fn home(scene: &Scene) -> Pose {
    Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    }
}

/// An estimator of `scene` after one update at [`home`], its status asserted ok.
pub fn loaded(scene: &Scene) -> Estimator {
    let mut est = Estimator::new(scene).unwrap();
    let e = *est.update(&home(scene), Tmin::Scene);
    assert!(e.status.is_ok(), "{}: {:?}", scene.name, e.error);
    est
}
