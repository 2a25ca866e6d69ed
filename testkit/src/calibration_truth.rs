//! "Measured" modes for the calibration tests from a model independent of the fit: the dense
//! FEM assembled here ([`crate::dense_fem::dense_with_hidden`]: the element blocks
//! EA/l e eᵀ + T/l (I − e eᵀ) written below, the hidden cables' nodes explicit) at tensions of
//! the Clarabel reference (not the fit's active-set solver), solved by a dense eigensolver
//! ([`crate::dense_fem::dense_eig`]). Point-mass end-effectors.

use crate::dense_fem::{dense_eig, dense_with_hidden, FreeCable};
use crate::Rng;
use cablevib::kinematics::Geometry;
use cablevib::scene::Scene;
use nalgebra::{Matrix3, Vector3};

/// A standard normal deviate (Box-Muller on two uniforms of `rng`).
pub fn gaussian(rng: &mut Rng) -> f64 {
    let u1 = rng.next().max(1e-300);
    let u2 = rng.next();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// One mode of the dense truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenseMode {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// End-effector participation m_ee‖φ_ee‖².
    pub participation: f64,
    /// Unit direction of the end-effector's displacement (zero when it does not move).
    pub ee_direction: Vector3<f64>,
}

/// Every mode of `truth` at position `p` (its scene's T_min unless `t_min_n`), ascending,
/// with `n` elements per free and hidden cable; Err when the tensions cannot hold the pose.
pub fn dense_modes(
    truth: &Scene,
    n: usize,
    p: &Vector3<f64>,
    t_min_n: Option<f64>,
) -> Result<Vec<DenseMode>, String> {
    assert!(!truth.rigid, "point-mass truth only");
    let nc = truth.n_cables();
    let mut g = Geometry::for_scene(truth);
    g.update(truth.cables.iter().map(|c| &c.anchor_m), p)
        .map_err(|e| e.to_string())?;
    let lo: Vec<f64> = (0..nc)
        .map(|i| t_min_n.unwrap_or(truth.cable_t_min_n(i)))
        .collect();
    let hi: Vec<f64> = (0..nc).map(|i| truth.cable_t_max_n(i)).collect();
    let t = cablevib::tension::clarabel_reference_bounds(&g, &truth.wrench6_n(), &lo, &hi)
        .map_err(|e| e.to_string())?;
    let (k, m) = dense_with_hidden(truth, n, |i, c| {
        let e = g.unit[i];
        let l = g.length_m[i] / n as f64;
        let eet = e * e.transpose();
        let kc = eet * (c.ea_n() / l) + (Matrix3::identity() - eet) * (t[i] / l);
        FreeCable {
            blocks: vec![kc; n],
            element_mass_kg: c.mass_per_length_kg_m * l,
            junction_dir: e,
        }
    });
    let (lambda, v) = dense_eig(&k, &m);
    Ok(lambda
        .iter()
        .enumerate()
        .map(|(j, &l)| {
            let u = Vector3::new(v[(0, j)], v[(1, j)], v[(2, j)]);
            DenseMode {
                frequency_hz: l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                participation: truth.ee_mass_kg * u.norm_squared(),
                ee_direction: u.try_normalize(0.0).unwrap_or_else(Vector3::zeros),
            }
        })
        .collect())
}

/// The modes CSV (`x_m,y_m,z_m,frequency_hz,sigma_hz,mode`) of the first `per_pose`
/// end-effector modes (participation ≥ `threshold`) of `truth` at each of `poses`, each
/// frequency times (1 + `noise_rel` · N(0, 1)) with σ = `noise_rel` × the true frequency;
/// `mode` is `ee1`, `ee2`, … when `labelled`, else empty.
#[allow(clippy::too_many_arguments)]
pub fn measured_csv(
    truth: &Scene,
    n: usize,
    poses: &[Vector3<f64>],
    per_pose: usize,
    threshold: f64,
    noise_rel: f64,
    labelled: bool,
    rng: &mut Rng,
) -> String {
    let mut out = String::from("x_m,y_m,z_m,frequency_hz,sigma_hz,mode\n");
    for p in poses {
        let modes = dense_modes(truth, n, p, None).expect("a pose the truth holds");
        for (k, f) in modes
            .iter()
            .filter(|m| m.participation >= threshold)
            .map(|m| m.frequency_hz)
            .take(per_pose)
            .enumerate()
        {
            let measured = f * (1.0 + noise_rel * gaussian(rng));
            let label = if labelled {
                format!("ee{}", k + 1)
            } else {
                String::new()
            };
            out.push_str(&format!(
                "{:?},{:?},{:?},{measured:?},{:?},{label}\n",
                p.x,
                p.y,
                p.z,
                noise_rel * f
            ));
        }
    }
    out
}

/// `count` positions drawn uniformly from the box [lo, hi] at which `truth` holds its weight
/// within its tension bounds (Clarabel), in the order drawn.
pub fn feasible_poses(
    truth: &Scene,
    count: usize,
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    rng: &mut Rng,
) -> Vec<Vector3<f64>> {
    let nc = truth.n_cables();
    let t_lo: Vec<f64> = (0..nc).map(|i| truth.cable_t_min_n(i)).collect();
    let t_hi: Vec<f64> = (0..nc).map(|i| truth.cable_t_max_n(i)).collect();
    let mut out = Vec::with_capacity(count);
    for _ in 0..100 * count {
        if out.len() == count {
            break;
        }
        let p = Vector3::new(
            rng.range(lo.x, hi.x),
            rng.range(lo.y, hi.y),
            rng.range(lo.z, hi.z),
        );
        let mut g = Geometry::for_scene(truth);
        if g.update(truth.cables.iter().map(|c| &c.anchor_m), &p)
            .is_ok()
            && cablevib::tension::clarabel_reference_bounds(&g, &truth.wrench6_n(), &t_lo, &t_hi)
                .is_ok()
        {
            out.push(p);
        }
    }
    assert_eq!(out.len(), count, "feasible poses in the box");
    out
}

/// The tensions CSV (`x_m,y_m,z_m,cable,tension_n,sigma_n`) of every cable of `truth` at
/// each of `poses` (Clarabel tensions), each times (1 + `noise_rel` · N(0, 1)) with
/// σ = `noise_rel` × the true tension.
pub fn measured_tensions_csv(
    truth: &Scene,
    poses: &[Vector3<f64>],
    noise_rel: f64,
    rng: &mut Rng,
) -> String {
    let nc = truth.n_cables();
    let lo: Vec<f64> = (0..nc).map(|i| truth.cable_t_min_n(i)).collect();
    let hi: Vec<f64> = (0..nc).map(|i| truth.cable_t_max_n(i)).collect();
    let mut out = String::from("x_m,y_m,z_m,cable,tension_n,sigma_n\n");
    for p in poses {
        let mut g = Geometry::for_scene(truth);
        g.update(truth.cables.iter().map(|c| &c.anchor_m), p)
            .expect("a pose the truth holds");
        let t = cablevib::tension::clarabel_reference_bounds(&g, &truth.wrench6_n(), &lo, &hi)
            .expect("a pose the truth holds");
        for (i, ti) in t.iter().enumerate() {
            let measured = ti * (1.0 + noise_rel * gaussian(rng));
            out.push_str(&format!(
                "{:?},{:?},{:?},{},{measured:?},{:?}\n",
                p.x,
                p.y,
                p.z,
                i + 1,
                noise_rel * ti
            ));
        }
    }
    out
}

/// Elements per cable of the recovery scene.
pub const RECOVERY_ELEMENTS: usize = 10;

/// The recovery tests' robot as a scene file: the paper's spatial robot (fem × 10) with a
/// rope 25 times lighter per length (a synthetic fibre's weight at the steel's EA: its
/// string modes start near 55 Hz, above the end-effector modes, 20-35 Hz with hidden cables
/// of 0-3 m, so those stay clean modes of the platform; with the paper's steel rope the
/// string harmonics at 11, 22, 33 Hz cross them and the modes hybridise) and, when given,
/// each cable's hidden length (m).
pub fn recovery_scene_toml(hidden_m: Option<&[f64]>) -> String {
    let base = cablevib::scene::DEFAULT_SCENE_TOML;
    let light = base.replacen(
        "weight_per_length = 0.251",
        "weight_per_length = 0.01004",
        1,
    );
    assert_ne!(light, base, "the paper scene's weight per length");
    let n = light
        .find("elements_per_cable = ")
        .expect("elements_per_cable");
    let end = n + light[n..].find('\n').expect("line end");
    let mut text = format!(
        "{}elements_per_cable = {RECOVERY_ELEMENTS}{}",
        &light[..n],
        &light[end..]
    );
    if let Some(h) = hidden_m {
        let mut out = String::new();
        let mut k = 0;
        for line in text.lines() {
            out.push_str(line);
            out.push('\n');
            if line.trim_start().starts_with("anchor") {
                out.push_str(&format!("hidden_length = {:?}\n", h[k]));
                k += 1;
            }
        }
        assert_eq!(k, h.len(), "one hidden length per cable");
        text = out;
    }
    text
}

/// A true robot for the recovery: per-cable EA factors drawn from [0.6, 1.2], hidden
/// lengths from [0, 3] m, the end-effector mass +8 %. Returns its scene, the EA factors,
/// the mass (kg) and the hidden lengths (m).
pub fn recovery_truth(rng: &mut Rng) -> (Scene, Vec<f64>, f64, Vec<f64>) {
    let factors: Vec<f64> = (0..8).map(|_| rng.range(0.6, 1.2)).collect();
    let hidden: Vec<f64> = (0..8).map(|_| rng.range(0.0, 3.0)).collect();
    let mut s = Scene::from_toml_str(&recovery_scene_toml(Some(&hidden)), "truth").unwrap();
    for (c, f) in s.cables.iter_mut().zip(&factors) {
        c.youngs_modulus_pa *= f;
        if let Some(h) = c.hidden.as_mut() {
            h.youngs_modulus_pa *= f;
        }
    }
    s.ee_mass_kg *= 1.08;
    let m = s.ee_mass_kg;
    (s, factors, m, hidden)
}

/// The recovery's measurements of `truth`: 20 feasible poses drawn in
/// [−0.6, 0.6]² × [0.6, 1.9] m, its first three end-effector modes there with 0.3 % noise
/// (`mode` = `eeK` when `labelled`) and every cable's tension with 1 % noise.
pub struct RecoveryData {
    /// The poses, m.
    pub poses: Vec<Vector3<f64>>,
    /// The modes CSV.
    pub modes_csv: String,
    /// The tensions CSV.
    pub tensions_csv: String,
}

/// [`RecoveryData`] of `truth`, drawn from `rng`.
pub fn recovery_data(truth: &Scene, labelled: bool, rng: &mut Rng) -> RecoveryData {
    let lo = Vector3::new(-0.6, -0.6, 0.6);
    let hi = Vector3::new(0.6, 0.6, 1.9);
    let poses = feasible_poses(truth, 20, lo, hi, rng);
    let modes_csv = measured_csv(
        truth,
        RECOVERY_ELEMENTS,
        &poses,
        3,
        0.5,
        0.003,
        labelled,
        rng,
    );
    let tensions_csv = measured_tensions_csv(truth, &poses, 0.01, rng);
    RecoveryData {
        poses,
        modes_csv,
        tensions_csv,
    }
}
