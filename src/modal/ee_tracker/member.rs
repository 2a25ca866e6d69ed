//! One watched mode ([`Member`]), a root found by a search ([`Tracked`]), the predictor,
//! and the watch list's insertion and removal.

use super::{EeTracker, MAX_MEMBERS};
use crate::modal::Root;
use nalgebra::Vector6;

/// The predictor of a watched mode: quadratic through its last three λ (linear with two).
pub(super) fn predict(m: &Member) -> f64 {
    if m.age > 1 {
        // Not followed for a while: linear extrapolation over the gap.
        let x = if m.prev.is_finite() {
            m.lambda + m.age as f64 * (m.lambda - m.prev)
        } else {
            m.lambda
        };
        return if x > 0.0 { x } else { m.lambda };
    }
    if m.prev.is_finite() {
        let x = if m.prev2.is_finite() {
            // Quadratic through the last three cycles.
            3.0 * (m.lambda - m.prev) + m.prev2
        } else {
            2.0 * m.lambda - m.prev
        };
        if x > 0.0 {
            return x;
        }
    }
    m.lambda
}

/// The side of a watched mode's last neighbour search.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) enum SearchSide {
    /// Not searched yet.
    #[default]
    None,
    /// The neighbour below (index − 1).
    Below,
    /// The neighbour above (index + 1).
    Above,
}

/// One watched mode.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Member {
    /// λ, rad²/s².
    pub(super) lambda: f64,
    /// λ one and two cycles earlier (NaN when unknown): the predictor.
    pub(super) prev: f64,
    pub(super) prev2: f64,
    /// End-effector participation.
    pub(super) p: f64,
    /// Participation when the mode's neighbours were last searched (NaN: never).
    pub(super) p_ref: f64,
    /// Participation when its neighbours were last searched by the count (`gap`; at first
    /// its participation when found).
    pub(super) gap_ref: f64,
    /// When its neighbours were last searched (count of searches).
    pub(super) searched: u64,
    /// Side of the last neighbour search.
    pub(super) last_side: SearchSide,
    /// Position in the spectrum: modes below it, counted with multiplicity.
    pub(super) index: u32,
    /// Branch of D (eigenvalue number) that vanishes at the mode.
    pub(super) branch: usize,
    /// The pole interval that contains it, rad²/s².
    pub(super) a: f64,
    pub(super) b: f64,
    /// The chain that holds the largest share of the mode's kinetic-energy norm (after the
    /// end-effector): that share, and the chain's pole nearest the mode (rad²/s²) and
    /// whether it lies above.
    pub(super) share: f64,
    pub(super) pole: f64,
    pub(super) pole_up: bool,
    /// That pole's identity (chain << 16 | pole number).
    pub(super) pole_key: u32,
    /// The pole whose partner was searched last, and the share then.
    pub(super) partner_key: u32,
    pub(super) partner_share: f64,
    /// Relative size of the last Newton step and the residual there.
    pub(super) step: f64,
    pub(super) residual: f64,
    /// Cycles since it was last followed (0: this cycle). Only members followed this cycle
    /// count in the certificate.
    pub(super) age: u32,
    /// The end-effector part of the mass-normalised mode shape where it was last followed
    /// (the sum rules' matrix form, `bound`); None where the search that found it gave no
    /// shape (a scan).
    pub(super) phi: Option<Vector6<f64>>,
}

impl Member {
    /// A newly watched mode (no history yet).
    pub(super) fn new(lambda: f64, p: f64, index: u32, branch: usize, a: f64, b: f64) -> Member {
        Member {
            lambda,
            prev: f64::NAN,
            prev2: f64::NAN,
            p,
            p_ref: p,
            gap_ref: p,
            searched: 0,
            last_side: SearchSide::None,
            index,
            branch,
            a,
            b,
            share: 0.0,
            pole: f64::NAN,
            pole_up: false,
            pole_key: u32::MAX,
            partner_key: u32::MAX,
            partner_share: 0.0,
            step: f64::INFINITY,
            residual: f64::NAN,
            age: 0,
            phi: None,
        }
    }
}

/// A root found by the search's `track_root` or a neighbour search.
#[derive(Debug, Clone, Copy)]
pub(super) struct Tracked {
    pub(super) root: Root,
    pub(super) branch: usize,
    pub(super) index: u32,
    pub(super) a: f64,
    pub(super) b: f64,
    /// [`Member::share`], [`Member::pole`], [`Member::pole_up`], [`Member::pole_key`].
    pub(super) share: f64,
    pub(super) pole: f64,
    pub(super) pole_up: bool,
    pub(super) pole_key: u32,
    /// Relative size of the last Newton step (the root's error is of its square).
    pub(super) step: f64,
    /// [`Member::phi`].
    pub(super) phi: Option<Vector6<f64>>,
}

impl Tracked {
    /// A newly watched mode at this root; `prev` is its λ one cycle earlier (NaN: none).
    pub(super) fn member(&self, prev: f64) -> Member {
        let r = &self.root;
        let mut m = Member::new(
            r.lambda,
            r.ee_participation,
            self.index,
            self.branch,
            self.a,
            self.b,
        );
        m.prev = prev;
        m.share = self.share;
        m.pole = self.pole;
        m.pole_up = self.pole_up;
        m.pole_key = self.pole_key;
        m.step = self.step;
        m.residual = r.residual;
        m.phi = self.phi;
        m
    }
}

impl EeTracker {
    /// Insert a watched mode in index order; a mode already watched (same index) is
    /// replaced. When full, the weakest watched mode gives way to a stronger one.
    pub(super) fn insert_member(&mut self, m: Member) {
        let n = self.n_members;
        let pos = self.members[..n].partition_point(|x| x.index < m.index);
        if pos < n && self.members[pos].index == m.index {
            self.members[pos] = m;
            return;
        }
        if n == MAX_MEMBERS {
            let (weak, wp) =
                self.members[..n]
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |acc, (i, x)| {
                            if x.p < acc.1 {
                                (i, x.p)
                            } else {
                                acc
                            }
                        },
                    );
            if wp >= m.p {
                return;
            }
            self.remove_member(weak);
            self.insert_member(m);
            return;
        }
        let mut i = n;
        while i > pos {
            self.members[i] = self.members[i - 1];
            i -= 1;
        }
        self.members[pos] = m;
        self.n_members += 1;
    }

    pub(super) fn remove_member(&mut self, i: usize) {
        for k in i..self.n_members - 1 {
            self.members[k] = self.members[k + 1];
        }
        self.n_members -= 1;
    }
}
