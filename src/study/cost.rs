//! What a long study costs, said before it runs, and its progress while it runs.
//!
//! **Memory.** Every study whose memory grows with the user's input checks its estimate
//! against the one budget of the offline work ([`crate::memory_budget`], 2 GiB) before it
//! allocates: the mode shapes of the modes and analysis studies (and their CSV text), the
//! modal basis of `frf` with modal damping, the two bases `simulate` holds across a basis
//! update (and its path); the dense reference by the same rule
//! ([`crate::modal::check_dense_budget`]).
//!
//! **Time.** [`estimate_cost`] gives the work's size and an estimate of its time from rates
//! measured on the development machine (2 shared cores; order of magnitude, not a
//! promise): per element of a chain at a complex λ ([`COMPLEX_CHAIN_ELEMENT_S`], the exact
//! damped `frf` at N elements per cable costs O(N) per frequency), per node and mode of a
//! shape recovery ([`SHAPE_NODE_MODE_S`], [`SIMULATE_NODE_MODE_S`]), per row of a shapes
//! CSV ([`CSV_ROW_S`]). The command line prints it on stderr when it is over
//! [`ANNOUNCE_AFTER_S`]; a progress bar with the live ETA follows on a terminal
//! ([`super::progress`], the loop helper [`in_chunks`]).

use super::progress::Progress;
use super::StudyError;
use crate::estimator::{
    check_shapes_memory, shape_nodes, shapes_memory_bytes, PoseModel, SHAPE_BYTES_PER_NODE,
};
use crate::modal::{
    self, hz_to_lambda, ModalParams, ModalSolver, Mode, ModeShapes, ShapeParams, MAX_FRF_MODES,
};
use crate::scene::{Damping, ElementKind, Scene};
use nalgebra::Matrix6;
use num_complex::Complex64;

/// A study whose estimated time is over this is announced on stderr before it starts, s.
pub const ANNOUNCE_AFTER_S: f64 = 10.0;
/// Time per element of one chain evaluated at a complex λ (the damped exact `frf`), s:
/// 0.61 s per frequency on the paper robot at N = 10⁶ (24 chains).
pub const COMPLEX_CHAIN_ELEMENT_S: f64 = 2.5e-8;
/// Time of one frequency that costs O(1) in N (the undamped closed form, a modal sum), s.
pub const FREQUENCY_S: f64 = 2e-6;
/// Time per node and mode of a shape recovery (`modes`, a modal basis), s: 0.94 s for 12
/// modes at N = 10⁵ on the paper robot.
pub const SHAPE_NODE_MODE_S: f64 = 7e-8;
/// Time per node and mode of one basis update of `simulate` (shapes and the mass overlap
/// with the last basis), s: 0.85 s per update for 12 modes at N = 3·10⁴.
pub const SIMULATE_NODE_MODE_S: f64 = 2e-7;
/// Time per row of the mode-shape CSV (formatting and writing), s: 77 s for 9.6·10⁶ rows.
pub const CSV_ROW_S: f64 = 8e-6;
/// Text a mode-shape CSV holds in memory per row (one node of one mode) until it is
/// written, bytes: 124 measured at N = 10⁵ (1.39 GB for 14 modes), with margin.
pub const SHAPES_CSV_BYTES_PER_ROW: u64 = 130;
/// The poses at which `simulate`'s pilot runs (the path's first, middle and last).
pub const PILOT_POSES: f64 = 3.0;
/// What to change when `simulate` is over the memory budget.
pub const SIMULATE_REMEDY: &str = "use fewer elements per cable, or give --modes (choosing K for --tolerance runs a pilot basis of more modes than K) or a larger --tolerance";
/// Memory per path sample of `simulate` (position, command, deviation, time; unshaped and
/// shaped runs), bytes.
const SIMULATE_BYTES_PER_SAMPLE: u64 = 2 * 80;

/// The work of one study, as [`estimate_cost`] takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Work<'a> {
    /// `frf`: `points` frequencies with `damping`; modal damping goes by a basis of
    /// `basis_modes` modes (0 otherwise).
    Frf {
        /// The damping.
        damping: &'a Damping,
        /// Frequencies.
        points: usize,
        /// Modes of the modal basis (modal damping).
        basis_modes: usize,
    },
    /// `simulate`: `samples` path samples, the basis of `modes` modes updated every
    /// `update_every` samples, after the pilot that chose or assessed K with bases of up
    /// to `pilot_modes` modes.
    Simulate {
        /// Path samples (with the settling time).
        samples: usize,
        /// Samples between basis updates.
        update_every: usize,
        /// Modes K.
        modes: usize,
        /// The pilot's largest basis, modes.
        pilot_modes: usize,
    },
    /// The mode shapes (modes, analysis): the shapes of `modes` modes, their CSV when `csv`.
    Modes {
        /// Modes K.
        modes: usize,
        /// Points of a continuous cable.
        continuous_samples: usize,
        /// Whether the shapes are written as CSV (its text is held until written).
        csv: bool,
    },
}

/// The size and estimated cost of a study ([`estimate_cost`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WorkEstimate {
    /// The command, e.g. `frf`.
    pub what: &'static str,
    /// Units of work (frequencies, samples, modes) and their name.
    pub units: u64,
    /// `frequencies`, `samples`, `modes`.
    pub unit: &'static str,
    /// Estimated time, s (from the rates of the module docs).
    pub seconds: f64,
    /// Estimated peak memory of the work, bytes.
    pub memory_bytes: u64,
    /// Elements per cable of the model (for the message).
    pub elements_per_cable: usize,
    /// What to change when the memory is over the budget.
    pub remedy: &'static str,
}

impl WorkEstimate {
    /// Refuse the work when its memory is over the one budget.
    pub fn check_memory(&self) -> Result<(), crate::memory_budget::OverBudget> {
        let (what, units, unit, n) = (self.what, self.units, self.unit, self.elements_per_cable);
        crate::memory_budget::check(
            || format!("{what} ({units} {unit}, {n} elements per cable)"),
            self.memory_bytes,
            self.remedy,
        )
    }

    /// The line the command line prints before a study of more than
    /// [`ANNOUNCE_AFTER_S`], else None.
    pub fn announcement(&self) -> Option<String> {
        (self.seconds >= ANNOUNCE_AFTER_S).then(|| {
            format!(
                "{}: about {} for {} {} at {} elements per cable (estimated from measured rates); Ctrl-C stops it",
                self.what,
                duration_text(self.seconds),
                self.units,
                self.unit,
                self.elements_per_cable
            )
        })
    }
}

/// `s` seconds as `42 s`, `12 min`, `3.4 h` or `2.1 days`.
pub fn duration_text(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 2.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86400.0)
    }
}

/// Chain elements evaluated per complex λ: three chains per cable (and a hidden cable's
/// axial one), N elements each; 0 for the continuous model (closed form).
fn complex_elements(scene: &Scene) -> f64 {
    match scene.model.element {
        ElementKind::Continuous | ElementKind::Massless => 0.0,
        _ => 3.0 * scene.n_cables() as f64 * scene.model.elements_per_cable as f64,
    }
}

/// The size, memory and estimated time of `work` on `scene`'s model (module docs).
pub fn estimate_cost(scene: &Scene, work: &Work<'_>) -> WorkEstimate {
    let n = scene.model.elements_per_cable;
    let samples_default = ShapeParams::default().continuous_samples;
    match *work {
        Work::Frf {
            damping,
            points,
            basis_modes,
        } => {
            let per = match damping {
                Damping::None | Damping::ModalRatio { .. } => FREQUENCY_S,
                _ => FREQUENCY_S + COMPLEX_CHAIN_ELEMENT_S * complex_elements(scene),
            };
            let nodes = shape_nodes(scene, samples_default) as f64;
            let basis_s = basis_modes as f64 * nodes * SHAPE_NODE_MODE_S;
            let memory = if basis_modes > 0 {
                shapes_memory_bytes(scene, basis_modes, samples_default, SHAPE_BYTES_PER_NODE)
            } else {
                0
            };
            WorkEstimate {
                what: "frf",
                units: points as u64,
                unit: "frequencies",
                seconds: basis_s + per * points as f64,
                memory_bytes: memory.saturating_add(points as u64 * 600),
                elements_per_cable: n,
                remedy: crate::estimator::SHAPES_REMEDY,
            }
        }
        Work::Simulate {
            samples,
            update_every,
            modes,
            pilot_modes,
        } => {
            let updates = samples.div_ceil(update_every.max(1)) as f64;
            let nodes = shape_nodes(scene, samples_default) as f64;
            let k = (modes + 6) as f64;
            // The pilot holds one basis at a time (at three poses); the run two at once
            // across an update (the old one for the mass overlap).
            let pilot =
                shapes_memory_bytes(scene, pilot_modes, samples_default, SHAPE_BYTES_PER_NODE);
            let run = shapes_memory_bytes(scene, modes, samples_default, 2 * SHAPE_BYTES_PER_NODE);
            let pilot_s = PILOT_POSES * (pilot_modes + 6) as f64 * nodes * SHAPE_NODE_MODE_S;
            WorkEstimate {
                what: "simulate",
                units: samples as u64,
                unit: "samples",
                seconds: pilot_s + updates * k * nodes * SIMULATE_NODE_MODE_S,
                memory_bytes: pilot
                    .max(run)
                    .saturating_add((samples as u64).saturating_mul(SIMULATE_BYTES_PER_SAMPLE)),
                elements_per_cable: n,
                remedy: SIMULATE_REMEDY,
            }
        }
        Work::Modes {
            modes,
            continuous_samples,
            csv,
        } => {
            let nodes = shape_nodes(scene, continuous_samples);
            let k = (modes + 6) as f64;
            // The CSV's rows: every node of the modes written (a cluster cut by K completed:
            // two more on the paper robot).
            let rows = (modes as u64 + 2).saturating_mul(nodes);
            let (csv_s, csv_bytes) = if csv {
                (
                    rows as f64 * CSV_ROW_S,
                    rows.saturating_mul(SHAPES_CSV_BYTES_PER_ROW),
                )
            } else {
                (0.0, 0)
            };
            WorkEstimate {
                what: "mode shapes",
                units: modes as u64,
                unit: "modes",
                seconds: k * nodes as f64 * SHAPE_NODE_MODE_S + csv_s,
                memory_bytes: shapes_memory_bytes(
                    scene,
                    modes,
                    continuous_samples,
                    SHAPE_BYTES_PER_NODE,
                )
                .saturating_add(csv_bytes),
                elements_per_cable: n,
                remedy: crate::estimator::SHAPES_REMEDY,
            }
        }
    }
}

/// Run `f` over `0..n` frequencies in chunks of `chunk` (the last one shorter),
/// concatenating the results, with a progress bar labelled `label` on a terminal
/// ([`Progress`]); the first error stops the loop.
pub fn in_chunks<T, E>(
    label: Option<&str>,
    n: usize,
    chunk: usize,
    mut f: impl FnMut(std::ops::Range<usize>) -> Result<Vec<T>, E>,
) -> Result<Vec<T>, E> {
    let bar = Progress::counting(label, n, "frequencies");
    let mut out = Vec::with_capacity(n);
    let mut start = 0;
    while start < n {
        let end = (start + chunk.max(1)).min(n);
        let part = f(start..end);
        match part {
            Ok(v) => out.extend(v),
            Err(e) => {
                bar.finish();
                return Err(e);
            }
        }
        bar.advance(end - start);
        start = end;
    }
    bar.finish();
    Ok(out)
}

/// Frequencies per step of a response's progress bar: about `BAR_STEP_S` of work each
/// by the estimate, 1 ..= 256.
pub fn frf_chunk(scene: &Scene, damping: &Damping) -> usize {
    let one = Work::Frf {
        damping,
        points: 1,
        basis_modes: 0,
    };
    let per = estimate_cost(scene, &one).seconds;
    (BAR_STEP_S / per).clamp(1.0, 256.0) as usize
}

/// Work between two steps of a progress bar, s (the bar redraws 4 times a second).
const BAR_STEP_S: f64 = 0.2;

/// The receptance of the loaded `solver` (taut cables: `pose`'s models) at each of
/// `freqs_hz` ([`modal::receptance_over`]), with the cost of the work checked first: modal
/// damping holds the shapes of every mode below `cutoff_hz` (at most
/// [`MAX_FRF_MODES`]), refused past the memory budget; the exact damped forms go in chunks
/// with a progress bar labelled `label` on a terminal. What `cablevib frf` and the Python
/// `frf` compute.
pub fn receptance(
    pose: &PoseModel,
    solver: &mut ModalSolver,
    damping: &Damping,
    freqs_hz: &[f64],
    cutoff_hz: f64,
    label: Option<&str>,
) -> Result<Vec<Matrix6<Complex64>>, StudyError> {
    let frf = StudyError::Frf;
    let (models, arms) = (&pose.models, &pose.geometry.arm_m);
    if let Damping::ModalRatio { .. } = damping {
        let k = (solver.count_below(hz_to_lambda(cutoff_hz)) as usize).clamp(1, MAX_FRF_MODES);
        let samples = ShapeParams::default().continuous_samples;
        check_shapes_memory(&pose.scene, k, samples, SHAPE_BYTES_PER_NODE)?;
        return modal::receptance_over(solver, models, arms, damping, freqs_hz, cutoff_hz)
            .map_err(frf);
    }
    let chunk = frf_chunk(&pose.scene, damping);
    in_chunks(label, freqs_hz.len(), chunk, |r| {
        modal::receptance_over(solver, models, arms, damping, &freqs_hz[r], cutoff_hz).map_err(frf)
    })
}

/// The lowest clusters (λ, multiplicity) of the loaded `solver` covering at least `k` modes
/// (a cluster cut by `k` completed), from the spectrum engine.
fn lowest_clusters(solver: &mut ModalSolver, k: usize) -> Result<Vec<(f64, u32)>, StudyError> {
    let mut modes = vec![Mode::default(); k + modal::MAX_MULTIPLICITY as usize];
    let n = solver
        .modes(modes.len(), &mut modes)
        .map_err(|e| StudyError::Build(e.to_string()))?;
    let mut out = Vec::new();
    let mut covered = 0usize;
    for (i, m) in modes[..n].iter().enumerate() {
        if covered >= k {
            break;
        }
        if m.cluster_start == i {
            out.push((m.lambda, m.multiplicity));
            covered += m.multiplicity as usize;
        }
    }
    Ok(out)
}

/// The lowest `k` modes' shapes of `pose` (clusters completed) from the structured solver,
/// what the mode-shape studies draw and write: refused first when the
/// shapes (and their CSV text, `csv`) would be over the memory budget; the clusters'
/// shapes computed a few at a time with a progress bar labelled `label` on a terminal.
pub fn mode_shapes(
    pose: &PoseModel,
    k: usize,
    params: &ShapeParams,
    csv: bool,
    label: Option<&str>,
) -> Result<ModeShapes, StudyError> {
    let work = Work::Modes {
        modes: k,
        continuous_samples: params.continuous_samples,
        csv,
    };
    estimate_cost(&pose.scene, &work).check_memory()?;
    let mut solver = ModalSolver::new(ModalParams::default());
    pose.load(&mut solver);
    let clusters = lowest_clusters(&mut solver, k)?;
    let err = |e: modal::ShapeError| StudyError::Build(e.to_string());
    let total: usize = clusters.iter().map(|c| c.1 as usize).sum();
    let mut all: Option<ModeShapes> = None;
    let bar = Progress::counting(label, total, "modes");
    // One cluster at a time (a run of near neighbours together, resolved as one when they
    // are not separated): each call recovers its own shapes (no work is shared across
    // clusters), so the bar moves by each run's multiplicity.
    for run in modal::near_runs(&clusters) {
        let c = &clusters[run];
        let part = solver
            .mode_shapes(&pose.models, &pose.geometry.arm_m, c, params)
            .map_err(err);
        let mut part = match part {
            Ok(p) => p,
            Err(e) => {
                bar.finish();
                return Err(e);
            }
        };
        match &mut all {
            None => all = Some(part),
            Some(a) => {
                let offset = a.modes.len();
                for m in &mut part.modes {
                    m.cluster_start += offset;
                }
                a.modes.append(&mut part.modes);
            }
        }
        bar.advance(c.iter().map(|x| x.1 as usize).sum());
    }
    bar.finish();
    Ok(all.unwrap_or_default())
}
