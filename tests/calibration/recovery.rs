//! Recovery of known parameters: "measured" end-effector modes of a true scene (per-cable EA
//! factors drawn from [0.6, 1.2], end-effector mass +8 %, hidden lengths drawn from [0, 3] m)
//! from the dense FEM assembled in the testkit (`calibration_truth`: its own element blocks,
//! the Clarabel tensions, a dense eigensolver), 0.3 % noise, at 20 poses; the fit (the
//! structured engine, the active-set tensions, the analytic sensitivities) must put each
//! parameter within its reported 2σ in ≥ 90 % of the trials.

use cablevib::calibration::data::{parse_modes, parse_tensions};
use cablevib::calibration::{calibrate, CalibrationParams, FitSpec, SigmaDefaults};
use cablevib::scene::Scene;
use cablevib_testkit::calibration_truth::{recovery_data, recovery_scene_toml, recovery_truth};
use cablevib_testkit::Rng;

/// The nominal robot (`recovery_scene_toml`: the paper's robot with a light rope, fem × 10),
/// with hidden cables of the given lengths.
fn nominal(hidden_m: Option<&[f64]>) -> Scene {
    Scene::from_toml_str(&recovery_scene_toml(hidden_m), "nominal").unwrap()
}

/// A true scene and its parameter values in the order of `ea_factor, ee_mass, hidden_length`.
fn truth(rng: &mut Rng) -> (Scene, Vec<f64>) {
    let (s, factors, mass, hidden) = recovery_truth(rng);
    let mut values = factors;
    values.push(mass);
    values.extend(hidden);
    (s, values)
}

/// What a trial fits.
#[derive(Clone, Copy)]
struct Setup {
    /// Fit the hidden lengths too (else the nominal scene knows them).
    hidden: bool,
    /// Prior σ of the hidden lengths about 1.5 m, m (with `hidden`).
    hidden_prior_m: Option<f64>,
    /// Measured tensions in the data.
    tensions: bool,
}

/// One trial: the report and the true values of its parameters.
fn trial(seed: u64, setup: Setup, verbose: bool) -> (cablevib::calibration::Report, Vec<f64>) {
    let mut rng = Rng(seed);
    let (t, values) = truth(&mut rng);
    let d = recovery_data(&t, true, &mut rng);
    let mut data = parse_modes(&d.modes_csv, "truth.csv", &SigmaDefaults::default()).unwrap();
    if setup.tensions {
        let sd = SigmaDefaults::default();
        parse_tensions(&d.tensions_csv, "tensions.csv", 8, &sd, &mut data).unwrap();
    }
    let mut values = values;
    let s = if setup.hidden {
        nominal(Some(&[1.5; 8]))
    } else {
        // The designer knows the hidden cables: the nominal scene has the truth's.
        let s = nominal(Some(&values[9..]));
        values.truncate(9);
        s
    };
    let names: &[&str] = if setup.hidden {
        &["ea_factor", "ee_mass", "hidden_length"]
    } else {
        &["ea_factor", "ee_mass"]
    };
    let mut spec = FitSpec::new(&s, names).unwrap();
    if setup.hidden {
        spec.set_bounds("hidden_length", 0.0, 6.0).unwrap();
        if let Some(sigma) = setup.hidden_prior_m {
            spec.set_prior("hidden_length", sigma).unwrap();
        }
    }
    let c = calibrate(&s, &data, &spec, &CalibrationParams::default()).unwrap();
    if verbose {
        let r = &c.report;
        println!(
            "seed {seed}: χ²/dof {:.3} ({}), {} iterations, {} evaluations, {:.2} s, left out {}",
            r.chi2_per_dof,
            r.fits,
            r.iterations,
            r.evaluations,
            r.seconds,
            r.left_out.len()
        );
        for (p, v) in r.parameters.iter().zip(&values) {
            println!(
                "  {:<16} true {v:>8.4} fit {:>8.4} ± {:>8.4} {} {}",
                p.name,
                p.value,
                p.std_error.unwrap_or(f64::NAN),
                if p.determined { "" } else { "undetermined" },
                if p.at_bound { "at bound" } else { "" }
            );
        }
    }
    (c.report, values)
}

/// The recovery's setup: EA factors and the end-effector mass fitted, the hidden cables
/// known (in the nominal scene), frequencies and tensions measured.
const SETUP: Setup = Setup {
    hidden: false,
    hidden_prior_m: None,
    tensions: true,
};

/// One trial in detail: it fits, and every parameter is within 3σ of the truth.
#[test]
fn one_trial_recovers_the_truth() {
    let (r, values) = trial(7, SETUP, true);
    assert!(r.fits, "{}", r.verdict);
    for (p, v) in r.parameters.iter().zip(&values) {
        let s = p.std_error.expect("determined");
        assert!(
            (p.value - v).abs() <= 3.0 * s,
            "{}: {} ± {s} vs {v}",
            p.name,
            p.value
        );
    }
}

/// The coverage over seeded trials: a hundred calibrations, each against its own dense-FEM
/// truth, take minutes of CPU, so it is a slow reference sweep (tests/README.md; `.ci/run`
/// runs it). The quick suite keeps [`one_trial_recovers_the_truth`]: the same pipeline
/// (truth, data, fit) on one trial, held to 3σ.
mod slow {
    use super::*;

    /// Coverage over 100 seeded trials (`CALIBRATION_TRIALS` sets another number): each
    /// parameter within its reported 2σ of the truth in at least 90 % of the trials (a Gaussian
    /// estimate with honest σ is, in 95.4 %), and the calibrated model's frequencies within the
    /// noise (the χ² verdict "fits", P(χ² larger) ≥ 0.01, in at least 95 % of the trials).
    /// Printed: the coverage table of docs/calibration.md.
    #[test]
    #[ignore = "slow reference sweep: 100 calibrations against the dense-FEM truth (minutes of CPU)"]
    fn coverage_over_seeded_trials() {
        use rayon::prelude::*;
        let trials: u64 = std::env::var("CALIBRATION_TRIALS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(100);
        let setup = match std::env::var("CALIBRATION_SETUP").as_deref() {
            Ok("hidden") => Setup {
                hidden: true,
                hidden_prior_m: None,
                tensions: true,
            },
            Ok("hidden-prior") => Setup {
                hidden: true,
                hidden_prior_m: Some(0.5),
                tensions: true,
            },
            _ => SETUP,
        };
        let results: Vec<_> = (1..=trials)
            .into_par_iter()
            .map(|seed| trial(1000 + seed, setup, false))
            .collect();
        let names: Vec<String> = results[0]
            .0
            .parameters
            .iter()
            .map(|p| p.name.clone())
            .collect();
        let n = names.len();
        let (mut within, mut determined) = (vec![0usize; n], vec![0usize; n]);
        let mut worst = vec![0.0f64; n];
        for (r, values) in &results {
            for (k, (p, v)) in r.parameters.iter().zip(values).enumerate() {
                if let (true, Some(s)) = (p.determined, p.std_error) {
                    determined[k] += 1;
                    within[k] += usize::from((p.value - v).abs() <= 2.0 * s);
                    worst[k] = worst[k].max((p.value - v).abs() / s);
                }
            }
        }
        let fits = results.iter().filter(|(r, _)| r.fits).count();
        let mut chi2: Vec<f64> = results.iter().map(|(r, _)| r.chi2_per_dof).collect();
        chi2.sort_by(f64::total_cmp);
        let mut secs: Vec<f64> = results.iter().map(|(r, _)| r.seconds).collect();
        secs.sort_by(f64::total_cmp);
        println!(
            "{trials} trials: {fits} fit the stated noise; χ²/dof median {:.3}, 95th percentile {:.3}; fit time median {:.2} s, 95th percentile {:.2} s (shared machine)",
            chi2[chi2.len() / 2],
            chi2[(chi2.len() * 95) / 100 - 1],
            secs[secs.len() / 2],
            secs[(secs.len() * 95) / 100 - 1]
        );
        println!("| parameter | determined | within 2σ | coverage | largest |error|/σ |");
        println!("|---|---|---|---|---|");
        for k in 0..n {
            println!(
                "| {} | {}/{trials} | {} | {:.0} % | {:.2} |",
                names[k],
                determined[k],
                within[k],
                100.0 * within[k] as f64 / determined[k].max(1) as f64,
                worst[k]
            );
        }
        if setup.hidden {
            return; // the exploratory setups print their table only
        }
        assert!(
            fits as f64 >= 0.95 * trials as f64,
            "{fits} of {trials} fit"
        );
        for k in 0..n {
            assert_eq!(
                determined[k], trials as usize,
                "{}: undetermined in some trials",
                names[k]
            );
            assert!(
                within[k] as f64 >= 0.9 * trials as f64,
                "{}: within 2σ in {} of {trials} trials",
                names[k],
                within[k]
            );
        }
    }
}
