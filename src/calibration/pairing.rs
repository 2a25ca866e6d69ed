//! Pairing measured modes with model modes, at the nominal parameters (and again at the
//! fitted ones, for the rows paired by frequency).
//!
//! - A row with `mode = K` is the model's K-th mode at its pose; `mode = eeK` the K-th mode
//!   whose end-effector participation reaches the scene's threshold (the modes a sensor on
//!   the platform sees), in ascending frequency.
//! - The rows without `mode` at one pose are paired by frequency with the model's
//!   end-effector modes there: measured ascending with model ascending, each model mode at
//!   most once, the order-preserving assignment of least Σ ln²(f_measured/f_model) (so a
//!   model uniformly off by 20 % still pairs its three end-effector modes with the three
//!   measured ones). A row is **ambiguous** (reported, left out) when the second-best
//!   assignment pairs it otherwise and is not clearly worse — its RMS log distance below
//!   `ambiguity_ratio` × the best's plus 3σ/f; **unpaired** when its mode is more than
//!   `max_gap_rel` away or the model has fewer end-effector modes than were measured. A
//!   pair found becomes the rule `eeK` (its rank among the end-effector modes), which the
//!   fit follows as the parameters move.

use super::data::{ModeLabel, ModeRow};
use super::evaluate::{resolve, PoseOut, Rule};
use crate::modal::lambda_to_hz;

/// Settings of the pairing by frequency (finite, > 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairingParams {
    /// The second-best assignment's RMS log distance must exceed this × the best's (plus
    /// 3σ/f) for the rows it pairs otherwise to be taken (default 2).
    pub ambiguity_ratio: f64,
    /// Largest relative distance |f_model/f_measured − 1| of a pair (default 0.5).
    pub max_gap_rel: f64,
    /// Modes are computed up to this × the highest unlabelled frequency at a pose (default 1.5).
    pub band_factor: f64,
    /// A rule's mode is looked for up to this × the highest measured frequency at its pose
    /// (default 3): beyond, the rule is unresolved (a pairing error, or a failed step).
    pub search_factor: f64,
}

impl Default for PairingParams {
    fn default() -> Self {
        PairingParams {
            ambiguity_ratio: 2.0,
            max_gap_rel: 0.5,
            band_factor: 1.5,
            search_factor: 3.0,
        }
    }
}

/// A measured mode left out of the fit by the pairing, with the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct Unpaired {
    /// Line in the data file.
    pub line: usize,
    /// Why (ambiguous, no such mode, too far).
    pub reason: String,
}

/// The end-effector modes at a pose: (rank of the first of its cluster, λ), one per cluster.
fn ee_candidates(out: &PoseOut, threshold: f64) -> Vec<(usize, f64)> {
    let mut rank = 0;
    let mut c: Vec<(usize, f64)> = Vec::new();
    let mut last_start = usize::MAX;
    for m in &out.modes {
        if m.ee_participation >= threshold {
            rank += 1;
            if m.cluster_start != last_start {
                c.push((rank, m.lambda));
                last_start = m.cluster_start;
            }
        }
    }
    c
}

/// The rule of every row (None: left out, with its reason in the second list). `pose_of`:
/// each row's pose index into `outs` (the model at those poses).
pub fn pair(
    rows: &[ModeRow],
    pose_of: &[usize],
    outs: &[PoseOut],
    threshold: f64,
    params: &PairingParams,
) -> (Vec<Option<Rule>>, Vec<Unpaired>) {
    let mut rules: Vec<Option<Rule>> = vec![None; rows.len()];
    let mut unpaired = Vec::new();
    let mut by_pose: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for (r, row) in rows.iter().enumerate() {
        let out = &outs[pose_of[r]];
        match row.label {
            ModeLabel::Order(k) => match resolve(&out.modes, Rule::Order(k), threshold) {
                Some(_) => rules[r] = Some(Rule::Order(k)),
                None => unpaired.push(Unpaired {
                    line: row.line,
                    reason: format!("mode {k}: the model has {} modes at this pose", out.modes.len()),
                }),
            },
            ModeLabel::Ee(k) => match resolve(&out.modes, Rule::Ee(k), threshold) {
                Some(_) => rules[r] = Some(Rule::Ee(k)),
                None => unpaired.push(Unpaired {
                    line: row.line,
                    reason: format!(
                        "mode ee{k}: the model has fewer end-effector modes (participation ≥ {threshold}) at this pose"
                    ),
                }),
            },
            ModeLabel::Unlabelled => by_pose.entry(pose_of[r]).or_default().push(r),
        }
    }
    for (pose, group) in by_pose {
        pair_pose(
            rows,
            &group,
            &outs[pose],
            threshold,
            params,
            &mut rules,
            &mut unpaired,
        );
    }
    unpaired.sort_by_key(|u| u.line);
    (rules, unpaired)
}

/// Largest number of order-preserving assignments compared at one pose; beyond, each row
/// is paired with its nearest mode alone.
const MAX_ASSIGNMENTS: usize = 100_000;

/// The unlabelled rows `group` of one pose, paired with the model's end-effector modes
/// there by the order-preserving assignment of least Σ ln²(f_measured/f_model): the
/// measured modes ascending take end-effector modes ascending (each at most once). Rows on
/// which the best and the second-best assignment differ are ambiguous unless the second is
/// clearly worse (its RMS log distance above `ambiguity_ratio` × the best's plus 3σ/f).
fn pair_pose(
    rows: &[ModeRow],
    group: &[usize],
    out: &PoseOut,
    threshold: f64,
    params: &PairingParams,
    rules: &mut [Option<Rule>],
    unpaired: &mut Vec<Unpaired>,
) {
    let cand = ee_candidates(out, threshold);
    let mut g: Vec<usize> = group.to_vec();
    g.sort_by(|&a, &b| rows[a].frequency_hz.total_cmp(&rows[b].frequency_hz));
    let max_gap = (1.0 + params.max_gap_rel).ln();
    let dist = |r: usize, c: usize| (rows[r].frequency_hz / lambda_to_hz(cand[c].1)).ln();
    let fhz = |c: usize| lambda_to_hz(cand[c].1);
    if cand.len() < g.len() {
        for &r in &g {
            unpaired.push(Unpaired {
                line: rows[r].line,
                reason: format!(
                    "{} unlabelled measured modes at this pose, the model has {} end-effector modes up to {:.4} Hz",
                    g.len(),
                    cand.len(),
                    params.band_factor * rows[*g.last().unwrap()].frequency_hz
                ),
            });
        }
        return;
    }
    // Every order-preserving assignment (indices into `cand`), with its cost.
    let mut best: Vec<(f64, Vec<usize>)> = Vec::new();
    let mut count = 0usize;
    let mut pick = vec![0usize; g.len()];
    fn walk(
        i: usize,
        from: usize,
        pick: &mut Vec<usize>,
        n_cand: usize,
        cost: &dyn Fn(&[usize]) -> f64,
        best: &mut Vec<(f64, Vec<usize>)>,
        count: &mut usize,
    ) {
        if *count >= MAX_ASSIGNMENTS {
            return;
        }
        if i == pick.len() {
            *count += 1;
            let c = cost(pick);
            best.push((c, pick.clone()));
            best.sort_by(|a, b| a.0.total_cmp(&b.0));
            best.truncate(2);
            return;
        }
        let left = pick.len() - i - 1;
        for c in from..n_cand.saturating_sub(left) {
            pick[i] = c;
            walk(i + 1, c + 1, pick, n_cand, cost, best, count);
        }
    }
    let cost = |p: &[usize]| {
        p.iter()
            .enumerate()
            .map(|(i, &c)| dist(g[i], c).powi(2))
            .sum::<f64>()
    };
    walk(0, 0, &mut pick, cand.len(), &cost, &mut best, &mut count);
    let Some((b_cost, b)) = best.first().cloned() else {
        return;
    };
    let sigma_rel = g
        .iter()
        .map(|&r| rows[r].sigma_hz / rows[r].frequency_hz)
        .fold(0.0, f64::max);
    let rms = |c: f64| (c / g.len() as f64).sqrt();
    let second = best.get(1).filter(|(s_cost, _)| {
        rms(*s_cost) < params.ambiguity_ratio * rms(b_cost) + 3.0 * sigma_rel
    });
    for (i, &r) in g.iter().enumerate() {
        let c = b[i];
        let f = rows[r].frequency_hz;
        if dist(r, c).abs() > max_gap {
            unpaired.push(Unpaired {
                line: rows[r].line,
                reason: format!(
                    "the end-effector mode it would pair with ({:.4} Hz) is more than {:.0} % away",
                    fhz(c),
                    100.0 * params.max_gap_rel
                ),
            });
            continue;
        }
        if let Some((_, s)) = second {
            if s[i] != c {
                unpaired.push(Unpaired {
                    line: rows[r].line,
                    reason: format!(
                        "ambiguous: end-effector modes at {:.4} Hz and {:.4} Hz fit {f:.4} Hz almost equally well",
                        fhz(c),
                        fhz(s[i])
                    ),
                });
                continue;
            }
        }
        rules[r] = Some(Rule::Ee(cand[c].0));
    }
}
