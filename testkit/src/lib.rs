//! Shared helpers of the workspace's integration tests (every crate's `tests/<area>/`): the
//! paper's tables and scene builders, the one test random-number generator, the counting
//! allocator's set-up ([`count_allocations!`]), and
//!
//! | module | what |
//! |---|---|
//! | [`calibration_truth`] | "measured" modes for the calibration tests from the dense FEM of a true scene |
//! | [`dense_fem`] | dense references written in the tests: a FEM with explicit hidden-cable nodes, dense eigenpairs |
//! | [`hard_cases`] | the real-time-against-dense checks of the hard-case tests |
//! | [`sag_cases`] | the sagged scenes and poses the sag tests share, the sagged shipped robots with FEM chains |
//! | [`sag_field`] | the path's influence field of a sagging robot (Irvine's catenaries, differences), the reference of the crate's |
//! | [`sag_reference_py`] | the independent sagged-cable reference, tests/py/sag_reference.py |
//! | [`sag_robot`] | sagged chains (`modal::sagged`) of a small robot, for the sagged FEM tests |
//! | [`pinned_venv`] | a Python venv under target/ with pinned packages |
pub mod calibration_truth;
pub mod dense_fem;
pub mod exact_response;
pub mod hard_cases;
pub mod modal_record;
pub mod pinned_venv;
pub mod sag_cases;
pub mod sag_field;
pub mod sag_reference_py;
pub mod sag_robot;
pub mod vibration;

/// The allocator every test that counts allocations runs under: `count_allocations!();` at
/// the root of a test binary (its `main.rs`) sets [`cablevib::alloc_count::CountingAlloc`]
/// as the global allocator, so `alloc_count::thread_system_allocations` counts the calling
/// thread's allocations. One set-up for every binary (a binary has one global allocator).
#[macro_export]
macro_rules! count_allocations {
    () => {
        #[global_allocator]
        static COUNTING_ALLOCATOR: $crate::CountingAlloc = $crate::CountingAlloc;
    };
}
#[doc(hidden)]
pub use cablevib::alloc_count::CountingAlloc;

use cablevib::scene::{ElementKind, Scene};
use nalgebra::Vector3;
use serde_json::Value;

/// The paper's tables with the faithful values (tests/data/paper_tables.json).
pub fn tables() -> Value {
    serde_json::from_str(include_str!("../../tests/data/paper_tables.json")).expect("valid json")
}

pub fn table(n: u64) -> Value {
    tables()["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["table"].as_u64() == Some(n))
        .unwrap()
        .clone()
}

pub fn vec3(v: &Value) -> Vector3<f64> {
    Vector3::new(
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    )
}

pub fn f64s(v: &Value) -> Vec<Option<f64>> {
    v.as_array().unwrap().iter().map(|x| x.as_f64()).collect()
}

/// The shipped scene for a table, checked against the table's robot data.
pub fn scene_for(t: &Value, element: ElementKind, n: usize, t_min: f64) -> Scene {
    let robot = &t["robot"];
    let mut s = if robot["gravity_carried_by_cables"].as_bool().unwrap() {
        Scene::default_scene()
    } else {
        Scene::planar_paper()
    };
    let g = robot["g"].as_f64().unwrap();
    assert_eq!(s.gravity_m_s2.norm(), g);
    assert_eq!(s.ee_mass_kg, robot["ee_mass_kg"].as_f64().unwrap());
    assert_eq!(s.t_max_n, robot["t_max_n"].as_f64().unwrap());
    let anchors = robot["anchors"].as_array().unwrap();
    assert_eq!(anchors.len(), s.n_cables());
    for (c, a) in s.cables.iter().zip(anchors) {
        assert_eq!(c.anchor_m, vec3(a));
        assert_eq!(
            c.youngs_modulus_pa,
            robot["youngs_modulus_pa"].as_f64().unwrap()
        );
        assert_eq!(c.area_m2, robot["area_m2"].as_f64().unwrap());
        let mu = robot["weight_per_length_n_per_m"].as_f64().unwrap() / g;
        assert!((c.mass_per_length_kg_m - mu).abs() <= 1e-16 * mu);
    }
    s.ee_position_m = vec3(&t["ee_position"]);
    s.t_min_n = t_min;
    s.with_model(element, n)
}

/// The rows of a FEM convergence table (3 or 7): elements per cable, the shipped scene
/// with that many FEM elements at the table's T_min, and the row.
pub fn convergence_rows(t: &Value) -> Vec<(usize, Scene, &Value)> {
    let t_min = t["robot"]["t_min_n"].as_f64().unwrap();
    t["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            let n = row["elements_per_cable"].as_u64().unwrap() as usize;
            (n, scene_for(t, ElementKind::Fem, n, t_min), row)
        })
        .collect()
}

/// Table 4's result columns (planar robot): key, element, elements per cable.
pub const TABLE4_COLUMNS: [(&str, ElementKind, usize); 4] = [
    ("faithful_fem_N10", ElementKind::Fem, 10),
    ("faithful_analytical_N10", ElementKind::Catenary, 10),
    ("faithful_fem_N40", ElementKind::Fem, 40),
    ("faithful_analytical_N40", ElementKind::Catenary, 40),
];

/// Table 8's result columns (spatial robot, 40 elements per cable): key, element.
pub const TABLE8_COLUMNS: [(&str, ElementKind); 2] = [
    ("faithful_fem_N40", ElementKind::Fem),
    ("faithful_analytical_N40", ElementKind::Catenary),
];

pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Deterministic pseudo-random numbers (the core's [`cablevib::rng::SplitMix64`]). Never allocates, so it can drive
/// loops whose heap allocations are counted.
pub struct Rng(pub u64);
impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut s = cablevib::rng::SplitMix64(self.0);
        let z = s.next_u64();
        self.0 = s.0;
        z
    }
    /// Uniform in [0, 1). (Not an `Iterator`: the tests call it as a plain method, a stream
    /// without end.)
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.next() < p
    }
    /// A random direction: a point of the cube [−1, 1]³ with 0.1 < |v| ≤ 1, normalised.
    pub fn unit(&mut self) -> Vector3<f64> {
        loop {
            let v = Vector3::new(
                2.0 * self.next() - 1.0,
                2.0 * self.next() - 1.0,
                2.0 * self.next() - 1.0,
            );
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }
}

/// A paper scene's text without its `[effects]` table (`sag = false`), so that a test can
/// append a table of its own.
pub fn without_effects(text: &str) -> String {
    let i = text.find("[effects]\n").expect("[effects]");
    let j = i
        + text[i..]
            .find("\n\n")
            .expect("a blank line after [effects]")
        + 2;
    format!("{}{}", &text[..i], &text[j..])
}

/// The end-effector mode's frequency of an estimate as the tests compare it, Hz: NaN when
/// none is known (`Estimate::ee_mode` is None).
pub fn ee_hz(e: &cablevib::estimator::Estimate) -> f64 {
    e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz)
}

/// The end-effector mode's participation of an estimate: NaN when none is known.
pub fn ee_p(e: &cablevib::estimator::Estimate) -> f64 {
    e.ee_mode.map_or(f64::NAN, |m| m.participation)
}

/// The age of an estimate's end-effector mode, cycles: None when none is known.
pub fn ee_age(e: &cablevib::estimator::Estimate) -> Option<u32> {
    e.ee_mode.map(|m| m.age_cycles)
}
