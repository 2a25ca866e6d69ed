//! Pairing measured modes with model modes, at the nominal parameters (and again at the
//! fitted ones, for the rows paired by frequency).
//!
//! - A row with `mode = K` is the model's K-th mode at its pose; `mode = eeK` the K-th mode
//!   whose end-effector participation reaches the scene's threshold (the modes a sensor on
//!   the platform sees), in ascending frequency.
//! - A row without `mode` is paired by frequency among the model's end-effector modes at
//!   its pose: the nearest in |ln(f_measured/f_model)|. It is **ambiguous** (reported, left
//!   out) when the next end-effector mode is not clearly farther — its distance below
//!   `ambiguity_ratio` × the nearest's plus 3σ/f — or when another row at the pose picks
//!   the same mode; **unpaired** when no end-effector mode lies within `max_gap_rel`. A
//!   pair found becomes the rule `eeK` (its rank among the end-effector modes), which the
//!   fit follows as the parameters move.

use super::data::{ModeLabel, ModeRow};
use super::evaluate::{resolve, PoseOut, Rule};
use crate::modal::lambda_to_hz;

/// Settings of the pairing by frequency (finite, > 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairingParams {
    /// The second-nearest end-effector mode must be farther than this × the nearest's log
    /// distance (plus 3σ/f) for a pair to be taken (default 2).
    pub ambiguity_ratio: f64,
    /// Largest relative distance |f_model/f_measured − 1| of a pair (default 0.5).
    pub max_gap_rel: f64,
    /// Modes are computed up to this × the highest unlabelled frequency at a pose (default 1.5).
    pub band_factor: f64,
}

impl Default for PairingParams {
    fn default() -> Self {
        PairingParams {
            ambiguity_ratio: 2.0,
            max_gap_rel: 0.5,
            band_factor: 1.5,
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
    // Chosen (pose, rank) → row, to find two rows picking one mode.
    let mut chosen: std::collections::HashMap<(usize, usize), usize> = Default::default();
    let mut conflicts: Vec<usize> = Vec::new();
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
            ModeLabel::Unlabelled => {
                let cand = ee_candidates(out, threshold);
                let f = row.frequency_hz;
                let mut d: Vec<(f64, usize, f64)> = cand
                    .iter()
                    .map(|&(rank, l)| ((f / lambda_to_hz(l)).ln().abs(), rank, lambda_to_hz(l)))
                    .collect();
                d.sort_by(|a, b| a.0.total_cmp(&b.0));
                let Some(&(d1, rank, f1)) = d.first() else {
                    unpaired.push(Unpaired {
                        line: row.line,
                        reason: "no end-effector mode in the model at this pose".into(),
                    });
                    continue;
                };
                if d1 > (1.0 + params.max_gap_rel).ln() {
                    unpaired.push(Unpaired {
                        line: row.line,
                        reason: format!(
                            "the nearest end-effector mode ({f1:.4} Hz) is more than {:.0} % away",
                            100.0 * params.max_gap_rel
                        ),
                    });
                    continue;
                }
                if let Some(&(d2, _, f2)) = d.get(1) {
                    if d2 < params.ambiguity_ratio * d1 + 3.0 * row.sigma_hz / f {
                        unpaired.push(Unpaired {
                            line: row.line,
                            reason: format!(
                                "ambiguous: end-effector modes at {f1:.4} Hz and {f2:.4} Hz are both near {f:.4} Hz"
                            ),
                        });
                        continue;
                    }
                }
                if let Some(&other) = chosen.get(&(pose_of[r], rank)) {
                    conflicts.push(other);
                    conflicts.push(r);
                    continue;
                }
                chosen.insert((pose_of[r], rank), r);
                rules[r] = Some(Rule::Ee(rank));
            }
        }
    }
    conflicts.sort_unstable();
    conflicts.dedup();
    for &r in &conflicts {
        rules[r] = None;
        let others: Vec<String> = conflicts
            .iter()
            .filter(|&&o| o != r && pose_of[o] == pose_of[r])
            .map(|&o| rows[o].line.to_string())
            .collect();
        unpaired.push(Unpaired {
            line: rows[r].line,
            reason: format!(
                "ambiguous: line {} pairs with the same end-effector mode",
                others.join(", ")
            ),
        });
    }
    unpaired.sort_by_key(|u| u.line);
    (rules, unpaired)
}
