//! The structured spectrum engine (`ModalSolver::modes`, `Estimator::modes`) against
//! references that do not share its code: the dense generalised eigensolver on the same
//! assembled K and M (good to ε·λ_max/λ relative, `dense_relative_accuracy`).

use cablevib::estimator::Estimator;
use cablevib::estimator::Tmin;
use cablevib::kinematics::Pose;
use cablevib::modal::{dense_relative_accuracy, Mode};
use cablevib::scene::{ElementKind, Scene};

/// Safety factor on the dense solver's backward-error bound ε·λ_max/λ (the constant of a
/// backward-stable eigensolver's error is a modest multiple of ε).
const DENSE_SAFETY: f64 = 8.0;
/// The structured engine's own error, relative (Newton to 1e-14, the chain evaluation and
/// the 3 × 3 eigenvalues of D to a few hundred ε on these scenes).
const STRUCTURED_TOL: f64 = 1e-11;

fn estimator_at_default(s: &Scene) -> Estimator {
    let mut est = Estimator::new(s).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let pose = Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: s.ee_orientation_wxyz,
    };
    let st = est.update(&pose, Tmin::Scene).status;
    assert_eq!(st.as_str(), "ok", "{}", s.name);
    est
}

/// K structured modes and the dense spectrum of the same models: every λ within the dense
/// bound, multiplicities and summed cluster participations equal.
fn check_against_dense(s: &Scene, k: usize) {
    let mut est = estimator_at_default(s);
    let d = est.dense_modes(true).unwrap();
    let mut out = vec![Mode::default(); k.min(d.lambda.len() + 1)];
    let n = est.modes(k, &mut out).unwrap();
    assert_eq!(n, k.min(d.lambda.len()), "{}", s.name);
    for (i, m) in out[..n].iter().enumerate() {
        let l = d.lambda[i];
        let tol = DENSE_SAFETY * dense_relative_accuracy(l, d.lambda_max) + STRUCTURED_TOL;
        let err = (m.lambda - l).abs() / l;
        eprintln!(
            "{} mode {i}: {:.12e} vs dense {:.12e} rel {err:.1e} (tol {tol:.1e}) mult {} p {:.6} vs {:.6}",
            s.name, m.lambda, l, m.multiplicity, m.ee_participation, d.ee_participation[i]
        );
        assert!(
            err <= tol,
            "{} mode {i}: {} vs {l}: {err:.2e} > {tol:.2e}",
            s.name,
            m.lambda
        );
    }
    check_participations(&s.name, &out[..n], &d);
}

#[test]
fn every_model_matches_dense_at_n10() {
    let base = [Scene::default_scene(), Scene::planar_paper()];
    for s in &base {
        for el in [
            ElementKind::Fem,
            ElementKind::Catenary,
            ElementKind::Massless,
        ] {
            check_against_dense(&s.with_model(el, 10), 12);
        }
    }
    let b = Scene::box_6dof();
    for el in [
        ElementKind::Fem,
        ElementKind::Catenary,
        ElementKind::Massless,
    ] {
        check_against_dense(&b.with_model(el, 10), 12);
    }
}

// ---------------------------------------------------------------------------------------
// Certificate in 40-digit arithmetic: the inertia of K − σM (tests/py/inertia_certificate.py)

/// The probe of the certificate: the k-th eigenvalue lies in [λ(1 − 1e-10), λ(1 + 1e-10)],
/// so the frequency is within 5e-11 — inside the required 1e-9. The assembled f64 K and M
/// are exactly uniform chains of the rounded element block, whose own eigenvalues differ
/// from the unrounded model's by ~ε·EA/T ≲ 1e-12 relative (transverse stiffness T/l is
/// carried next to EA/l in one rounded block), far inside the probe.
const CERT_REL: f64 = 1e-10;

/// A venv under target/ with mpmath pinned; returns its python.
fn mpmath_python() -> std::path::PathBuf {
    cablevib_testkit::pinned_venv::pinned_venv_python(
        "py-mpmath-1.3.0",
        &[("mpmath", "mpmath", "1.3.0")],
    )
}

/// `cablevib analyze ARGS --json` parsed.
fn analyze_json(args: &[&str]) -> serde_json::Value {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .arg("analyze")
        .args(args)
        .arg("--json")
        .output()
        .expect("run cablevib");
    assert!(
        out.status.success(),
        "analyze {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("analyze JSON")
}

fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Upper-triangle non-zeros of a dense matrix as [i, j, "v"] (shortest round-trip f64).
fn triplets(a: &nalgebra::DMatrix<f64>) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for j in 0..a.ncols() {
        for i in 0..=j {
            let v = a[(i, j)];
            if v != 0.0 {
                out.push(serde_json::json!([i, j, format!("{v:?}")]));
            }
        }
    }
    out
}

/// Number of eigenvalues of the assembled (K, M) below λ(1 + rel), for each pair.
fn certified_counts(est: &Estimator, sigmas: &[(f64, f64)]) -> Vec<u64> {
    let (k, m) = est.dense_matrices().unwrap();
    let n = k.nrows();
    let dim = est.modal().dim();
    let order: Vec<usize> = (dim..n).chain(0..dim).collect();
    let input = serde_json::json!({
        "n": n,
        "order": order,
        "k": triplets(&k),
        "m": triplets(&m),
        "sigmas": sigmas.iter().map(|&(l, r)| [format!("{l:?}"), format!("{r:e}")]).collect::<Vec<_>>(),
    });
    let script = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("tests/py/inertia_certificate.py");
    let mut child = std::process::Command::new(mpmath_python())
        .arg(script)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("python");
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "inertia_certificate.py failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["negatives"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

/// `analyze SCENE --modes 10 --json`: each frequency certified to CERT_REL in λ by the
/// 40-digit inertia of K − σM, and each cluster's multiplicity equal to the count there.
fn certify_analyze(scene_arg: &str, s: &Scene) {
    let j = analyze_json(&[scene_arg, "--modes", "10"]);
    let f = f64s(&j["frequencies_hz"]);
    let mult: Vec<u64> = j["multiplicity"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    let start: Vec<u64> = j["cluster_start"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(f.len(), 10);
    let est = estimator_at_default(s);
    // The certificate is about the CLI's model: same tensions, bit for bit.
    assert_eq!(f64s(&j["tensions_n"]), est.estimate().tensions().to_vec());
    let lambda: Vec<f64> = f
        .iter()
        .map(|&x| cablevib::modal::hz_to_lambda(x))
        .collect();
    let sig: Vec<(f64, f64)> = lambda
        .iter()
        .flat_map(|&l| [(l, -CERT_REL), (l, CERT_REL)])
        .collect();
    let c = certified_counts(&est, &sig);
    for (i, l) in lambda.iter().enumerate() {
        let (below, above) = (c[2 * i], c[2 * i + 1]);
        eprintln!("{scene_arg} mode {i}: λ {l:.15e}: {below} below, {above} below λ(1+1e-10); cluster {} × {}", start[i], mult[i]);
        assert!(
            below <= i as u64 && above > i as u64,
            "{scene_arg} mode {i} not certified"
        );
        assert_eq!(
            (below, above),
            (start[i], start[i] + mult[i]),
            "{scene_arg} mode {i}: cluster"
        );
    }
}

#[test]
fn spatial_paper_n40_certified_in_40_digits() {
    let s = Scene::default_scene();
    assert_eq!(s.model.elements_per_cable, 40);
    certify_analyze("spatial-paper", &s);
}

#[test]
fn planar_paper_certified_in_40_digits() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/planar_paper.toml");
    certify_analyze(path, &Scene::load(path).unwrap());
}

/// Participations against dense: summed over each whole cluster (basis-invariant; for a
/// simple mode, the mode's own). The dense invariant subspace of a cluster is accurate to
/// ~ε·λ_max/gap (gap: the absolute distance to the nearest other eigenvalue), and the
/// participation, a quadratic form on it, to a few times that.
fn check_participations(name: &str, modes: &[Mode], d: &cablevib::modal::DenseModes) {
    let mut i = 0;
    while i < modes.len() {
        let end = modes[i].cluster_start + modes[i].multiplicity as usize;
        assert_eq!(modes[i].cluster_start, i, "{name}: cluster order");
        if end > modes.len() {
            break;
        }
        let ps: f64 = modes[i..end].iter().map(|m| m.ee_participation).sum();
        let pd: f64 = d.ee_participation[i..end].iter().sum();
        let lam = d.lambda[i];
        let below = if i > 0 {
            lam - d.lambda[i - 1]
        } else {
            f64::INFINITY
        };
        let above = d
            .lambda
            .get(end)
            .map_or(f64::INFINITY, |&x| x - d.lambda[end - 1]);
        let gap = below.min(above);
        let tol = DENSE_SAFETY * f64::EPSILON * d.lambda_max / gap + 1e-12;
        eprintln!(
            "{name} cluster {i} ×{}: participation {ps:.12} vs dense {pd:.12} (tol {tol:.1e})",
            end - i
        );
        assert!(
            (ps - pd).abs() <= tol,
            "{name} cluster at {i} (×{}): participation {ps} vs dense {pd} (tol {tol:.1e})",
            end - i
        );
        i = end;
    }
}

// ---------------------------------------------------------------------------------------
// Continuous and N → ∞

/// The first K structured frequencies of `s` at its default pose.
fn structured_hz(s: &Scene, k: usize) -> Vec<f64> {
    let mut est = estimator_at_default(s);
    let mut out = vec![Mode::default(); k];
    let n = est.modes(k, &mut out).unwrap();
    out[..n].iter().map(|m| m.frequency_hz).collect()
}

/// The consistent-mass FEM converges to the continuous string as 1/N² (its λ error is
/// (jπ/N)²/12 relative for string mode j): from N = 10⁴ to 10⁵ to 10⁶ the difference to
/// the continuous model (φ cot φ, code the discrete chains do not share) falls 100× per
/// step. Only modes whose N = 10⁶ difference (≳ 4e-13) stands well above the engine's
/// noise (~1e-15 relative, from the chain's closed form and Newton to 1e-14) are used: f1
/// of these scenes is the end-effector's, its discretisation error sits at rounding level.
/// Tolerances: ±2 % for 10⁴ → 10⁵ (the O(1/N⁴) term and noise are far below), ±15 % for
/// 10⁵ → 10⁶ (noise of a few 1e-15 against differences of a few 1e-13).
#[test]
fn fem_at_a_million_elements_follows_the_inverse_square_law() {
    for base in [Scene::planar_paper(), Scene::default_scene()] {
        let k = 10;
        let cont = structured_hz(&base.with_model(ElementKind::Continuous, 1), k);
        let diffs: Vec<Vec<f64>> = [10_000usize, 100_000, 1_000_000]
            .iter()
            .map(|&n| {
                let f = structured_hz(&base.with_model(ElementKind::Fem, n), k);
                f.iter().zip(&cont).map(|(a, b)| (a - b) / b).collect()
            })
            .collect();
        let mut used = 0;
        let triples = diffs[0].iter().zip(&diffs[1]).zip(&diffs[2]);
        for (j, ((&d4, &d5), &d6)) in triples.enumerate() {
            eprintln!(
                "{} mode {j}: rel diff {d4:.3e} {d5:.3e} {d6:.3e}: ratios {:.2} {:.2}",
                base.name,
                d4 / d5,
                d5 / d6
            );
            if d6.abs() < 1e-13 {
                continue;
            }
            used += 1;
            assert!(
                (d4 / d5 - 100.0).abs() <= 2.0,
                "{} mode {j}: 1e4/1e5 ratio {}",
                base.name,
                d4 / d5
            );
            assert!(
                (d5 / d6 - 100.0).abs() <= 15.0,
                "{} mode {j}: 1e5/1e6 ratio {}",
                base.name,
                d5 / d6
            );
        }
        assert!(
            used >= 5,
            "{}: only {used} modes above the noise",
            base.name
        );
    }
}

/// The continuous model against Richardson's extrapolation of the FEM at N and 2N,
/// (4 f(2N) − f(N))/3, whose remaining error is O(1/N⁴): ~1e-12 relative at N = 400 for
/// the string modes here (and the engine's noise ~1e-15), so 1e-10 is a safe bound.
#[test]
fn continuous_matches_richardson_extrapolated_fem() {
    for base in [Scene::planar_paper(), Scene::default_scene()] {
        let k = 10;
        let cont = structured_hz(&base.with_model(ElementKind::Continuous, 1), k);
        let f1 = structured_hz(&base.with_model(ElementKind::Fem, 400), k);
        let f2 = structured_hz(&base.with_model(ElementKind::Fem, 800), k);
        for j in 0..k {
            let r = (4.0 * f2[j] - f1[j]) / 3.0;
            let err = (r - cont[j]).abs() / cont[j];
            eprintln!("{} mode {j}: continuous vs Richardson {err:.2e}", base.name);
            assert!(
                err <= 1e-10,
                "{} mode {j}: continuous {} vs Richardson {r}: {err:.2e}",
                base.name,
                cont[j]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Bounds

/// The per-mode evaluation budget is honoured: a budget of 3 evaluations cannot bracket and
/// converge a mode, and the answer is `NoConvergence`, not a wrong number.
#[test]
fn exceeding_the_budget_is_an_error() {
    use cablevib::modal::{ModalError, ModalParams, ModalSolver, SpectrumParams};
    let s = Scene::default_scene();
    let est = estimator_at_default(&s);
    let mut m = ModalSolver::new(ModalParams::default());
    m.load(est.cable_models(), s.ee_mass_kg);
    let p = SpectrumParams {
        max_evaluations_per_mode: 3,
        ..SpectrumParams::default()
    };
    let mut out = [Mode::default(); 4];
    let r = m.modes_with(4, &p, &mut out);
    assert!(matches!(r, Err(ModalError::NoConvergence { .. })), "{r:?}");
    // The default budget solves the same problem.
    assert_eq!(m.modes(4, &mut out).unwrap(), 4);
}

/// The dense reference refuses a model beyond its memory budget with an error before
/// allocating, and the structured engine answers the same model.
#[test]
fn dense_refuses_beyond_its_budget() {
    use cablevib::estimator::EstimatorError;
    use cablevib::modal::{dense_memory_bytes, ModalError, DENSE_MEMORY_BUDGET_BYTES};
    let s = Scene::default_scene().with_model(ElementKind::Fem, 10_000);
    let mut est = estimator_at_default(&s);
    let dof = 3 + 3 * 8 * 9_999;
    assert!(dense_memory_bytes(dof) > DENSE_MEMORY_BUDGET_BYTES);
    let r = est.dense_modes(false);
    assert!(
        matches!(
            r,
            Err(EstimatorError::Modal(ModalError::DenseTooLarge { .. }))
        ),
        "{r:?}"
    );
    let mut out = [Mode::default(); 10];
    assert_eq!(est.modes(10, &mut out).unwrap(), 10);
}

/// The whole spectrum of the N = 10 models (every string and axial mode, up to and beyond
/// the chains' cut-off 12k/m where the closed form switches to its hyperbolic branch)
/// against dense.
#[test]
fn whole_spectrum_matches_dense_at_n10() {
    for s in [
        Scene::default_scene(),
        Scene::planar_paper(),
        Scene::box_6dof(),
    ] {
        for el in [ElementKind::Fem, ElementKind::Catenary] {
            check_against_dense(&s.with_model(el, 10), usize::MAX / 2);
        }
    }
}

/// Off the symmetric pose the clusters split into nearly degenerate modes (1e-9 .. 1e-3
/// apart) and poles of different cables come close without coinciding: the count still
/// separates every mode (whole spectrum against dense).
#[test]
fn nearly_degenerate_poses_match_dense() {
    for d in [1e-9, 1e-6, 1e-3, 0.1] {
        let mut s = Scene::default_scene().with_model(ElementKind::Fem, 10);
        s.ee_position_m.x += d;
        s.ee_position_m.y += 0.5 * d;
        check_against_dense(&s, usize::MAX / 2);
        let mut p = Scene::planar_paper().with_model(ElementKind::Catenary, 10);
        p.ee_position_m.x += d;
        check_against_dense(&p, usize::MAX / 2);
    }
}
