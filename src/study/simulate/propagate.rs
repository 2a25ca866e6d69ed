//! The modal time response along a path: one implementation of the loop every
//! time-domain study runs (module docs of [`super`] for the model).
//!
//! [`run`] chooses K ([`super::pilot`], or takes it), installs the first pose's basis,
//! and then, interval by interval, solves the next update pose's basis, predicts the
//! interval's error ([`super::updates`]; shortening it while the prediction is over its
//! budget, when the interval is chosen), steps the K modes across the interval under the
//! force linear between samples with the static flexibility interpolated between the two
//! poses ([`ModalResponse::displacement_with`]), and installs the new basis, the state
//! carried by the mass overlap of the whole shapes. The force at sample k is the inertial
//! load of the quasi-static motion −M_ee [a_k; 0], taken by each mode through the basis's
//! load shapes (the whole robot's quasi-static inertia, [`crate::modal::quasi_static`]);
//! the convective load of a sagging robot's path and the caller's `external_n(k)` on the
//! end-effector (through the end-effector's shapes φ and flexibility F) are responses of
//! their own on the same modes, added ([`super::added_load`]); the caller sees the state at
//! every sample (`on_sample`).
//!
//! Each update's basis is made by Rayleigh–Ritz from the held one where the model has
//! that update and every kept mode's residual is within
//! [`updates::RITZ_RESIDUAL_PER_TOLERANCE`] of the tolerance
//! ([`crate::estimator::RitzBasis`]), else by the structured shapes (with
//! [`updates::ritz_guard`] guard modes above K for the next update's start block).

use super::added_load::{AddedLoads, SampleState};
use super::{pilot, solve_pose, updates, Accuracy, SampledPath, SimulateConfig, SimulateResult};
use crate::estimator::{EeModalBasis, Estimator};
use crate::modal::response::{ModalResponse, MAX_RESPONSE_MODES};
use crate::modal::ritz::RitzSchedule;
use crate::modal::ModeShapes;
use crate::scene::{Damping, Scene};
use crate::study::StudyError;
use nalgebra::{Matrix6, Vector3, Vector6};

/// The basis of the estimator's pose for `modes` (a cluster cut completed).
fn basis_at(
    est: &mut Estimator,
    scene: &Scene,
    p: &Vector3<f64>,
    t: f64,
    modes: usize,
) -> Result<Update, StudyError> {
    shapes_at(est, scene, p, t, modes, None)?
        .map_err(|e| StudyError::Build(format!("t = {t:.4} s: {e}")))
}

/// A basis update: the basis, the start block of the next Rayleigh–Ritz update (the kept
/// modes and the guards above them), and the largest residual when Rayleigh–Ritz made it.
struct Update {
    basis: EeModalBasis,
    space: Option<ModeShapes>,
    ritz_residual: Option<f64>,
}

/// What a Rayleigh–Ritz update starts from: the held basis's whole shapes, the largest
/// relative residual it may leave ([`updates`]) and the schedule of its checks, learned
/// along the path.
struct RitzStart<'a> {
    space: &'a ModeShapes,
    max_residual: f64,
    schedule: &'a mut RitzSchedule,
}

/// [`basis_at`] with the shapes' own refusal kept apart (the inner error): a near-cluster
/// the shape engine cannot resolve at this pose (not the memory budget, not the pose).
/// By Rayleigh–Ritz from `ritz` when every kept mode's relative residual is within its
/// bound, else the structured shapes of `modes` and [`updates::ritz_guard`] more (where
/// the model has the Rayleigh–Ritz update).
fn shapes_at(
    est: &mut Estimator,
    scene: &Scene,
    p: &Vector3<f64>,
    t: f64,
    modes: usize,
    ritz: Option<RitzStart<'_>>,
) -> Result<Result<Update, crate::estimator::BasisError>, StudyError> {
    solve_pose(est, scene, p, t)?;
    if let Some(RitzStart {
        space: start,
        max_residual,
        schedule,
    }) = ritz
    {
        match est.ee_modal_basis_ritz(start, modes, max_residual, schedule) {
            Ok(Some(r)) => {
                return Ok(Ok(Update {
                    basis: r.basis,
                    space: Some(r.space),
                    ritz_residual: Some(r.residual),
                }))
            }
            Err(crate::estimator::BasisError::Memory(over)) => return Err(over.into()),
            // Not met, or not made: the structured shapes.
            _ => {}
        }
    }
    let guard = if est.ritz_update_applies() {
        updates::ritz_guard(modes)
    } else {
        0
    };
    match est.ee_modal_basis(modes + guard) {
        Err(crate::estimator::BasisError::Memory(over)) => Err(over.into()),
        Ok(b) => Ok(Ok(split_guard(b, modes, guard > 0))),
        Err(e) => Ok(Err(e)),
    }
}

/// The first `modes` of `basis` (a cluster cut completed) and, when `keep_space`, its
/// whole shapes as the next Rayleigh–Ritz start block.
fn split_guard(mut basis: EeModalBasis, modes: usize, keep_space: bool) -> Update {
    let q = basis.lambda.len();
    let mut kept = modes.clamp(1, q.max(1)).min(q);
    let same = |b: &EeModalBasis, k: usize| match &b.shapes {
        Some(s) => s.modes[k].cluster_start < k,
        None => (b.lambda[k] - b.lambda[k - 1]).abs() <= 1e-9 * b.lambda[k],
    };
    while kept < q && same(&basis, kept) {
        kept += 1;
    }
    let space = match &basis.shapes {
        Some(s) if keep_space && kept < q => Some(s.clone()),
        _ => None,
    };
    basis.lambda.truncate(kept);
    basis.phi_ee.truncate(kept);
    basis.load_ee.truncate(kept);
    if let Some(s) = basis.shapes.as_mut() {
        s.modes.truncate(kept);
    }
    Update {
        basis,
        space,
        ritz_residual: None,
    }
}

/// Poses tried before an update pose whose shapes the engine cannot resolve is refused:
/// the update moves back one sample at a time (within its interval).
const UNRESOLVED_RETRIES: usize = 4;

/// The mass overlap of `basis`'s whole shapes (rows) with `previous`'s (columns), when both
/// have them ([`crate::modal::ModeShapes::mass_overlap`]).
fn overlap_of(basis: &EeModalBasis, previous: &EeModalBasis) -> Option<Vec<f64>> {
    match (&basis.shapes, &previous.shapes) {
        (Some(new), Some(old)) => new.mass_overlap(old, &basis.ee_mass),
        _ => None,
    }
}

/// Install `basis` in `resp`, carrying the state across: the whole state by the mass
/// overlap with the previous basis's whole shapes (`overlap`) when both have them, else the
/// end-effector's; the modes loaded by the whole robot's quasi-static inertia (the basis's
/// load shapes).
fn install(
    resp: &mut ModalResponse,
    basis: &EeModalBasis,
    overlap: Option<&[f64]>,
    damping: &Damping,
    t: f64,
) -> Result<(), StudyError> {
    match overlap {
        Some(o) => {
            resp.set_basis_projected(&basis.lambda, &basis.phi_ee, damping, &basis.flexibility, o)
        }
        None => resp.set_basis(
            &basis.lambda,
            &basis.phi_ee,
            damping,
            &basis.flexibility,
            &basis.ee_mass,
        ),
    }
    .and_then(|()| resp.set_load_shapes(&basis.load_ee, &basis.load_flexibility))
    .map_err(|e| StudyError::Build(format!("t = {t:.4} s: {e}")))
}

/// The forces at each sample: the inertial load −M_ee [a_k; 0], the convective load's and
/// the external force (`added_load`).
struct Loads<'a, F: Fn(usize) -> Vector6<f64>> {
    path: &'a SampledPath,
    ee_mass: Matrix6<f64>,
    external_n: F,
}

impl<F: Fn(usize) -> Vector6<f64>> Loads<'_, F> {
    /// The inertial load's force.
    fn at(&self, k: usize) -> Vector6<f64> {
        let mut a6 = Vector6::zeros();
        a6.fixed_rows_mut::<3>(0)
            .copy_from(&self.path.acceleration(k));
        -(self.ee_mass * a6)
    }

    /// The added loads' forces ([`AddedLoads::forces`]).
    fn added(&self, k: usize) -> [Vector6<f64>; 2] {
        AddedLoads::forces(&self.path.velocity(k), &(self.external_n)(k))
    }

    /// The inertial load and the external force, as the mode choice's pilot takes them
    /// (through the load shapes: an estimate of the external force's share).
    fn total(&self, k: usize) -> Vector6<f64> {
        self.at(k) + (self.external_n)(k)
    }
}

/// What the mode choice found: K, the pilot's largest basis, K's truncation estimate
/// relative to the peak, whether it met the tolerance, the peak, m.
struct ModesChosen {
    modes: usize,
    pilot_modes: usize,
    estimate: f64,
    met: bool,
    peak_m: f64,
}

/// K for `cfg` along the path: given, or the largest the pilot chooses at the path's
/// first, middle and last poses (the whole path's force at each), with the estimate and
/// the peak.
fn choose_modes<F: Fn(usize) -> Vector6<f64>>(
    est: &mut Estimator,
    scene: &Scene,
    loads: &Loads<'_, F>,
    cfg: &SimulateConfig,
) -> Result<ModesChosen, StudyError> {
    let path = loads.path;
    let n = path.positions_m.len();
    let mut samples = vec![0, n / 2, n - 1];
    samples.dedup_by(|a, b| path.positions_m[*a] == path.positions_m[*b]);
    // Each pilot basis's memory checked before it is built (with the run's samples), and
    // the pilot's progress in modes run.
    let check = |pilot_modes: usize| {
        crate::study::cost::estimate_cost(
            scene,
            &crate::study::cost::Work::Simulate {
                samples: n,
                update_every: cfg.update_every.unwrap_or(updates::FIRST_INTERVAL),
                modes: cfg.modes.unwrap_or(0),
                pilot_modes,
            },
        )
        .check_memory()
    };
    let per_pose: usize = pilot::pilot_sizes(cfg.modes.unwrap_or(0)).iter().sum();
    let bar = crate::study::progress::Progress::counting(
        cfg.progress,
        per_pose * samples.len(),
        "pilot modes",
    );
    let growth = pilot::Growth {
        check: &check,
        bar: &bar,
    };
    let chosen = pilot_poses(est, scene, loads, cfg, &samples, Some(&growth));
    bar.finish();
    chosen
}

/// [`choose_modes`] at the path's `samples`, watched by `growth`.
fn pilot_poses<F: Fn(usize) -> Vector6<f64>>(
    est: &mut Estimator,
    scene: &Scene,
    loads: &Loads<'_, F>,
    cfg: &SimulateConfig,
    samples: &[usize],
    growth: Option<&pilot::Growth<'_>>,
) -> Result<ModesChosen, StudyError> {
    let path = loads.path;
    let n = path.positions_m.len();
    let all: Vec<Vector6<f64>> = (0..n).map(|k| loads.total(k)).collect();
    let mut chosen = ModesChosen {
        modes: 0,
        pilot_modes: 0,
        estimate: 0.0,
        met: true,
        peak_m: 0.0,
    };
    for &k in samples {
        let t = k as f64 * path.dt_s;
        solve_pose(est, scene, &path.positions_m[k], t)?;
        let (damping, dt, tol) = (&scene.damping, path.dt_s, cfg.tolerance);
        let c = match cfg.modes {
            None => pilot::choose(est, damping, &all, dt, tol, growth)?,
            Some(given) => pilot::assess(est, given, damping, &all, dt, tol, growth)?,
        };
        chosen.modes = chosen.modes.max(c.modes);
        chosen.pilot_modes = chosen.pilot_modes.max(c.pilot_modes);
        chosen.estimate = chosen.estimate.max(c.estimate);
        chosen.met &= c.met;
        chosen.peak_m = chosen.peak_m.max(c.peak_m);
    }
    Ok(chosen)
}

/// The response along `path` (module docs) into `out` (its accuracy, samples, updates,
/// modes, f1 range and structured flag); `est` is the scene's estimator. The force at
/// sample k is the inertial load plus `external_n(k)` on the end-effector (N, and N·m on a
/// rigid body); `on_sample(k, state)` is called after each sample's state is reached.
pub(super) fn run(
    est: &mut Estimator,
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
    external_n: impl Fn(usize) -> Vector6<f64>,
    mut on_sample: impl FnMut(usize, &SampleState<'_>),
    out: &mut SimulateResult,
) -> Result<(), StudyError> {
    let n = path.positions_m.len();
    let damping = scene.damping;
    // The end-effector's mass matrix is the scene's, the same at every pose.
    let loads = Loads {
        path,
        ee_mass: basis_at(est, scene, &path.positions_m[0], 0.0, 1)?
            .basis
            .ee_mass,
        external_n,
    };
    let chosen = choose_modes(est, scene, &loads, cfg)?;
    // Each pilot basis was checked before it was built; with K now known, the run's own
    // two bases and path are checked against the budget before they are built.
    crate::study::cost::estimate_cost(
        scene,
        &crate::study::cost::Work::Simulate {
            samples: n,
            update_every: cfg.update_every.unwrap_or(updates::FIRST_INTERVAL),
            modes: chosen.modes,
            pilot_modes: 0,
        },
    )
    .check_memory()?;
    out.accuracy = Accuracy {
        tolerance: cfg.tolerance,
        modes_chosen: cfg.modes.is_none(),
        modes_estimate: chosen.estimate,
        modes_met: chosen.met,
        peak_m: chosen.peak_m,
        pilot_modes: chosen.pilot_modes,
        updates_chosen: cfg.update_every.is_none(),
        interval_estimate: 0.0,
        interval_estimate_sum: 0.0,
        ritz_updates: 0,
        ritz_residual: 0.0,
    };
    let max_residual = updates::RITZ_RESIDUAL_PER_TOLERANCE * cfg.tolerance;
    let modes = chosen.modes;
    let peak_m = chosen.peak_m;
    let f1_seen = |est: &Estimator, out: &mut SimulateResult| {
        let f1 = est.estimate().f1_hz;
        out.f1_range_hz = (out.f1_range_hz.0.min(f1), out.f1_range_hz.1.max(f1));
    };
    let dim = if scene.rigid { 6 } else { 3 };
    let mut resp = ModalResponse::new(dim);
    let budget = updates::BUDGET_SHARE * cfg.tolerance * peak_m;
    let planned_m = updates::PLAN_SHARE * budget;
    let max_interval = ((updates::MAX_INTERVAL_S / path.dt_s).round() as usize).max(1);
    let mut interval = cfg
        .update_every
        .unwrap_or(updates::FIRST_INTERVAL.min(max_interval));
    let first = basis_at(est, scene, &path.positions_m[0], 0.0, modes)?;
    let mut held = first.basis;
    let mut space = first.space;
    // When each Rayleigh–Ritz update is first checked, learned along the path.
    let mut schedule = RitzSchedule::default();
    f1_seen(est, out);
    install(&mut resp, &held, None, &damping, 0.0)?;
    // The convective load and the external force, each on the same modes (`added_load`).
    let mut added = AddedLoads::new();
    let added_err = |e| StudyError::Build(format!("the added loads: {e}"));
    added.install(&held, None, &damping).map_err(added_err)?;
    added.start(loads.added(0));
    out.updates = 1;
    // The previous update's flexibility and how many samples before the held pose.
    let mut previous: Option<(Matrix6<f64>, usize)> = None;
    let mut k0 = 0usize;
    let mut held_modes = vec![updates::HeldMode::default(); MAX_RESPONSE_MODES];
    let mut free = vec![0.0; MAX_RESPONSE_MODES];
    let mut forced = vec![0.0; MAX_RESPONSE_MODES];
    let mut omega0 = vec![0.0; MAX_RESPONSE_MODES];
    let mut omega1 = vec![0.0; MAX_RESPONSE_MODES];
    let mut f_prev = loads.at(0);
    // Each held mode's frequency drift a sample (rad/s) over the last interval, once one
    // was run; the last F''; the load's rate change and |F'' f| over the intervals a plan
    // weighs ([`updates::longest_within`]).
    let mut drift = vec![0.0; MAX_RESPONSE_MODES];
    let mut drift_known = false;
    let mut d2_last = Matrix6::zeros();
    let mut rate_changes = Vec::new();
    let mut statics = Vec::new();
    let mut omega_back = vec![0.0; MAX_RESPONSE_MODES];
    let push = |out: &mut SimulateResult, k: usize, u: &Vector6<f64>| {
        out.t_s.push(k as f64 * path.dt_s);
        out.command_m.push(path.positions_m[k]);
        out.deviation_m.push(u.fixed_rows::<3>(0).into_owned());
    };
    // The load's rate over the step ending at sample k (the first step's at sample 0), N/s.
    let rate = |k: usize| {
        let (a, b) = if k == 0 {
            (0, 1.min(n - 1))
        } else {
            (k - 1, k)
        };
        (loads.at(b) - loads.at(a)) / path.dt_s
    };
    let u0 = resp.displacement(&f_prev) + added.displacement(&held, &held, 0.0);
    push(out, 0, &u0);
    on_sample(0, &added.state(&resp, &f_prev));
    while k0 + 1 < n {
        // The next update's pose and basis; the interval shortened until its predicted
        // error is within the budget (when the interval is chosen).
        let nm = resp.modes();
        let rate0 = rate(k0);
        resp.ringing_amplitudes(&f_prev, &rate0, &mut free[..nm], &mut forced[..nm]);
        let rest_s = ((n - 1 - k0) as f64 * path.dt_s).min(updates::MAX_MEMORY_S);
        for (j, m) in held_modes.iter_mut().enumerate().take(nm) {
            let omega = resp.lambda(j).sqrt();
            let zeta = damping.modal_ratio(omega);
            *m = updates::HeldMode {
                free_m: free[j],
                forced_m: forced[j],
                // |φ_j| |ψ_j|/ω³: what a change of the load's rate starts ringing.
                start_m_s_per_n: resp.phi(j).norm() * resp.load_shape(j).norm() / omega.powi(3),
                omega_rad_s: omega,
                memory_s: if zeta > 0.0 {
                    (1.0 / (zeta * omega)).min(rest_s)
                } else {
                    rest_s
                },
            };
            omega0[j] = omega;
        }
        // The longest interval of at most `cap` samples from the held pose whose error
        // predicted with the drifts a sample `drift` and F'' `d2` is within the plan
        // ([`updates::longest_within`]), the load's rate change and |F'' f| over each
        // length into `rc` and `st`.
        let plan =
            |cap: usize, d2: &Matrix6<f64>, drift: &[f64], rc: &mut Vec<f64>, st: &mut Vec<f64>| {
                rc.clear();
                st.clear();
                let (mut r, mut s) = (0.0f64, 0.0f64);
                for k in k0 + 1..=(k0 + cap).min(n - 1) {
                    r = r.max((rate(k) - rate0).norm());
                    s = s.max((d2 * loads.at(k)).fixed_rows::<3>(0).norm());
                    rc.push(r);
                    st.push(s);
                }
                if rc.is_empty() {
                    return cap.max(1);
                }
                updates::longest_within(
                    &held_modes[..nm],
                    &drift[..nm],
                    rc,
                    st,
                    path.dt_s,
                    planned_m,
                )
            };
        // The interval planned from the held modes' amplitudes now and their drift over the
        // last interval (at most `interval`, the last one × MAX_GROWTH).
        if cfg.update_every.is_none() && drift_known {
            interval = plan(interval, &d2_last, &drift, &mut rate_changes, &mut statics);
        }
        let (k1, next, overlap, error, next_space, ritz_residual) = loop {
            let planned = (k0 + interval).min(n - 1);
            // A pose whose shapes the engine cannot resolve (a near-cluster on a sagging
            // cable) is stepped over: the update moves a sample back or on, a few times at
            // most ([`UNRESOLVED_RETRIES`]), the first refusal kept when none resolves.
            let mut tried = 0usize;
            let mut first_refusal = None;
            let (k1, next) = loop {
                let k1 = match tried {
                    0 => Some(planned),
                    i if i % 2 == 1 => planned.checked_sub(i.div_ceil(2)).filter(|&k| k > k0),
                    i => Some(planned + i / 2).filter(|&k| k < n),
                };
                tried += 1;
                let Some(k1) = k1 else {
                    if tried <= UNRESOLVED_RETRIES {
                        continue;
                    }
                    return Err(
                        first_refusal.unwrap_or_else(|| StudyError::Build("no update pose".into()))
                    );
                };
                let t1 = k1 as f64 * path.dt_s;
                let start = space.as_ref();
                match shapes_at(
                    est,
                    scene,
                    &path.positions_m[k1],
                    t1,
                    modes,
                    start.map(|space| RitzStart {
                        space,
                        max_residual,
                        schedule: &mut schedule,
                    }),
                )? {
                    Ok(b) => break (k1, b),
                    Err(e) => {
                        let refusal = StudyError::Build(format!("t = {t1:.4} s: {e}"));
                        let unresolved = matches!(e, crate::estimator::BasisError::Shapes(_));
                        if !unresolved || tried > UNRESOLVED_RETRIES {
                            return Err(first_refusal.unwrap_or(refusal));
                        }
                        first_refusal.get_or_insert(refusal);
                    }
                }
            };
            let Update {
                basis: next,
                space: next_space,
                ritz_residual,
            } = next;
            let overlap = overlap_of(&next, &held);
            updates::followed(
                &next.lambda,
                overlap.as_deref(),
                &omega0[..nm],
                &mut omega1[..nm],
            );
            let u = k1 - k0;
            let rate_change = (k0 + 1..=k1).fold(0.0f64, |m, k| m.max((rate(k) - rate0).norm()));
            let dynamic_m = updates::dynamic_error(
                &held_modes[..nm],
                &omega1[..nm],
                rate_change,
                u as f64 * path.dt_s,
                path.dt_s,
            );
            let d2 = match previous {
                Some((fp, back)) => updates::second_difference(
                    &fp,
                    &held.load_flexibility,
                    &next.load_flexibility,
                    back,
                    u,
                ),
                None => Matrix6::zeros(),
            };
            let static_m = updates::static_error(&d2, (k0 + 1..=k1).map(|k| loads.at(k)), u);
            let norms = match (&next.shapes, &held.shapes) {
                (Some(a), Some(b)) => a.mass_norms_of(b, &next.ee_mass),
                _ => None,
            };
            let leak_m = updates::leak_error(
                &held_modes[..nm],
                overlap.as_deref(),
                norms.as_deref(),
                u as f64 * path.dt_s,
                path.dt_s,
            );
            let error = updates::IntervalError {
                dynamic_m,
                static_m,
                leak_m,
            };
            if cfg.update_every.is_none() && error.total_m() > budget && u > 1 {
                // Shortened by the drift this interval measured, with its F''.
                for j in 0..nm {
                    drift[j] = (omega1[j] - omega0[j]).abs() / u as f64;
                }
                interval =
                    plan(u - 1, &d2, &drift, &mut rate_changes, &mut statics).clamp(1, u - 1);
                continue;
            }
            d2_last = d2;
            break (k1, next, overlap, error, next_space, ritz_residual);
        };
        if let Some(r) = ritz_residual {
            out.accuracy.ritz_updates += 1;
            out.accuracy.ritz_residual = out.accuracy.ritz_residual.max(r);
        }
        f1_seen(est, out);
        let u = k1 - k0;

        for k in k0 + 1..=k1 {
            let f = loads.at(k);
            resp.step(&f_prev, &f, path.dt_s);
            f_prev = f;
            let w = (k - k0) as f64 / u as f64;
            let flex = held.load_flexibility * (1.0 - w) + next.load_flexibility * w;
            added.step(loads.added(k), path.dt_s);
            let u = resp.displacement_with(&f, &flex) + added.displacement(&held, &next, w);
            push(out, k, &u);
            on_sample(k, &added.state(&resp, &f));
        }
        // Each new mode's drift a sample over this interval: its frequency at the held pose
        // followed back by its shape.
        let nn = next.lambda.len().min(MAX_RESPONSE_MODES);
        for (w, l) in omega1.iter_mut().zip(&next.lambda).take(nn) {
            *w = l.sqrt();
        }
        updates::followed_back(
            &held.lambda,
            overlap.as_deref(),
            &omega1[..nn],
            &mut omega_back[..nn],
        );
        for i in 0..nn {
            drift[i] = (omega1[i] - omega_back[i]).abs() / u as f64;
        }
        drift_known = true;
        install(
            &mut resp,
            &next,
            overlap.as_deref(),
            &damping,
            k1 as f64 * path.dt_s,
        )?;
        added
            .install(&next, overlap.as_deref(), &damping)
            .map_err(added_err)?;
        out.updates += 1;
        let rel = if peak_m > 0.0 {
            error.total_m() / peak_m
        } else {
            0.0
        };
        out.accuracy.interval_estimate = out.accuracy.interval_estimate.max(rel);
        out.accuracy.interval_estimate_sum += rel;
        previous = Some((held.load_flexibility, u));
        held = next;
        space = next_space;
        k0 = k1;
        if cfg.update_every.is_none() {
            interval = (updates::MAX_GROWTH * u).min(max_interval);
        }
    }
    out.structured = held.structured;
    out.modes = held.lambda.len();
    Ok(())
}
