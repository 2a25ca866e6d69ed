//! The condensed problem D(λ) behind one trait, and the numerical constants its searches
//! share.
//!
//! The structured solver reduces the free vibration problem to the end-effector's dynamic
//! stiffness D(λ) (3 × 3 or 6 × 6), its derivative D'(λ) = −(a mass matrix) and the blocked
//! count of the chains (Wittrick–Williams). The taut chains
//! ([`TautChains`](super::TautChains): uniform chains, their blocked eigenvalues known in
//! closed form) and the sagged ones ([`SagChains`](super::sagged::SagChains): non-uniform
//! chains, their poles only seen through the count) implement [`Condensed`]; the solver
//! ([`Solver`](super::Solver)), the first root (`first_mode`), the end-effector tracker
//! (`ee_tracker`), the spectrum search (`spectrum`) and the frequency response are written
//! once over it and monomorphised for each (no dynamic dispatch, no allocation). What differs
//! between the models is a method of the trait: the poles in closed form or through the
//! count, the sum rules' terms, D at a complex λ.
//!
//! Also here, shared by every model: one evaluation's result ([`DynEval`]) and its sorted
//! eigen-decomposition ([`EigD`]), and the pole-removed Newton function ([`pole_free`]).

use crate::eig3::eig3;
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector6};
use num_complex::Complex64;

/// Largest number of chains (a taut cable model has up to three).
pub(in crate::modal) const MAX_CHAINS: usize = 3 * MAX_CABLES;

/// (row, column) of the six distinct entries of a symmetric 3 × 3 matrix, in the order
/// both problems store a point mass's D and D' while summing the chains.
///
/// Why: a point mass's D is a symmetric 3 × 3 block; summing its six distinct entries
/// instead of nine (or 36 in a 6 × 6) is what keeps one evaluation cheap, and the two
/// problems must agree on the order to share the assembly's conventions.
pub(in crate::modal) const SYM3: [(usize, usize); 6] =
    [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// D(λ), D'(λ) and the blocked count at one λ. D is 3 × 3 (point mass, in the top-left
/// block) or 6 × 6 (rigid body: translation then rotation).
#[derive(Debug, Clone, Copy)]
pub struct DynEval {
    /// Dynamic stiffness D(λ), N/m (N·m/rad in the rotational block).
    pub d: Matrix6<f64>,
    /// dD/dλ, kg (kg·m² in the rotational block).
    pub dd: Matrix6<f64>,
    /// Σ mult · blocked eigenvalues below λ.
    pub below: u32,
    /// 3 or 6.
    pub dim: usize,
}

impl DynEval {
    /// Sorted eigen-decomposition of D.
    pub fn eig(&self) -> EigD {
        if self.dim == 3 {
            let e = eig3(&self.d.fixed_view::<3, 3>(0, 0).into_owned());
            let mut out = EigD {
                values: [f64::INFINITY; 6],
                vectors: [Vector6::zeros(); 6],
                n: 3,
            };
            for k in 0..3 {
                out.values[k] = e.values[k];
                out.vectors[k]
                    .fixed_rows_mut::<3>(0)
                    .copy_from(&e.vectors[k]);
            }
            out
        } else {
            let e = SymmetricEigen::new(self.d);
            let mut idx = [0usize, 1, 2, 3, 4, 5];
            idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
            let mut out = EigD {
                values: [0.0; 6],
                vectors: [Vector6::zeros(); 6],
                n: 6,
            };
            for (k, &i) in idx.iter().enumerate() {
                out.values[k] = e.eigenvalues[i];
                out.vectors[k] = e.eigenvectors.column(i).into_owned();
            }
            out
        }
    }
}

/// Sorted eigen-decomposition of D (3 or 6 valid entries).
#[derive(Debug, Clone, Copy)]
pub struct EigD {
    /// Eigenvalues ascending (entries ≥ n are +∞ or unused).
    pub values: [f64; 6],
    /// Matching unit eigenvectors.
    pub vectors: [Vector6<f64>; 6],
    /// Number of valid entries.
    pub n: usize,
}

impl EigD {
    /// Number of negative eigenvalues.
    pub fn negatives(&self) -> usize {
        self.values[..self.n].iter().filter(|&&v| v < 0.0).count()
    }
}

/// vᵀ A v for a symmetric A, over the leading `dim` × `dim` block (3 or 6).
#[inline]
pub(in crate::modal) fn quad(a: &Matrix6<f64>, v: &Vector6<f64>, dim: usize) -> f64 {
    if dim == 3 {
        let (x, y, z) = (v[0], v[1], v[2]);
        x * x * a[(0, 0)]
            + y * y * a[(1, 1)]
            + z * z * a[(2, 2)]
            + 2.0 * (x * y * a[(0, 1)] + x * z * a[(0, 2)] + y * z * a[(1, 2)])
    } else {
        (v.transpose() * a * v)[(0, 0)]
    }
}

/// g = μ(λ)(λ − pa)(pb − λ) and dg/dλ at x, from μ = μ(x) and dμ/dλ: the branch μ with the
/// poles bounding its interval removed (pa = 0 and pb = ∞ add nothing), which Newton can
/// follow across the interval without being thrown by a pole.
pub(in crate::modal) fn pole_free(mu: f64, dmu: f64, x: f64, pa: f64, pb: f64) -> (f64, f64) {
    let (mut g, mut dg) = (mu, dmu);
    if pb.is_finite() {
        let w = pb - x;
        (g, dg) = (g * w, dg * w - g);
    }
    if pa > 0.0 {
        let w = x - pa;
        (g, dg) = (g * w, dg * w + g);
    }
    (g, dg)
}

/// A mode's coupling to one chain ([`Condensed::coupling`]): (the chain's share of the
/// mode's kinetic-energy norm, its pole nearest the mode in rad²/s², whether that pole is
/// above, the pole's key chain << 16 | number).
pub type Coupling = (f64, f64, bool, u32);

/// [`Condensed::coupling`]'s answer for chain i holding `share` of a mode at x, where the
/// chain's count is j (its poles j and j + 1 are `lo` and `hi`): (share, the pole nearer
/// x, whether it is above x, its key i << 16 | number).
pub(in crate::modal) fn nearest_keyed_pole(
    share: f64,
    x: f64,
    i: usize,
    j: usize,
    lo: f64,
    hi: f64,
) -> Coupling {
    let up = j == 0 || hi - x < x - lo;
    let jp = if up { j + 1 } else { j };
    (
        share,
        if up { hi } else { lo },
        up,
        (i as u32) << 16 | jp as u32,
    )
}

/// The first upper bracket of a search starts here when no better scale is known,
/// rad²/s² (and a cold first root's Rayleigh guess is at least this).
///
/// Why: the Rayleigh scale μ₁(0)/(−μ₁'(0)) is the natural start, but when D'(0) vanishes
/// (massless chains, a degenerate end-effector) it is 0 or infinite; a bracket must start
/// at a positive λ, and 1e-12 rad²/s² (≈ 1.6e-7 Hz) is below any frequency a robot has,
/// so growth ([`BRACKET_GROWTH`]) reaches the first mode from below without skipping it.
pub(in crate::modal) const BRACKET_MIN: f64 = 1e-12;

/// An upper bracket grows by this factor per count probe (and a sagged first-root iterate
/// with no upper bound yet doubles).
///
/// Why: doubling keeps the bracket within a factor 2 of the mode (bisection then needs
/// ~52 halvings at worst to reach ε, Newton far fewer), while reaching any finite λ from
/// [`BRACKET_MIN`] in at most ~1100 probes; a larger factor saves probes only on a cold
/// start, at the cost of wider brackets every time.
pub(in crate::modal) const BRACKET_GROWTH: f64 = 2.0;

/// A bracket counts as collapsed when it is narrower than this many ε relative to λ.
///
/// Why: below a few ulps the bracket's ends are consecutive (or nearly) floating-point
/// numbers; μ's sign there is rounding, so no further evaluation can narrow it. Four ulps
/// leaves room for the rounding of (lo + hi)/2 and of the relative comparison itself.
pub(in crate::modal) const COLLAPSE_ULPS: f64 = 4.0;

/// A Newton step below this (relative) that also shows superlinear convergence (below
/// [`SUPERLINEAR_RATIO`] times the previous step; for a warm sagged first root, at any
/// rate) is accepted.
///
/// Why: the eigenvalue μ of D(λ) carries rounding noise of ~1e-13..1e-12 of λ on stiff,
/// heavy robots, so Newton steps of that size do not shrink: a stopping rule of 1e-14
/// alone would bounce until the evaluation budget ran out. A step of 1e-10 after a much
/// larger one means quadratic convergence: the next iterate is within ~(1e-10)² of the
/// root, far below the target.
pub(in crate::modal) const NOISE_STEP: f64 = 1e-10;

/// See [`NOISE_STEP`]: a step at most this fraction of the previous one shows
/// superlinear convergence.
///
/// Why: a linearly converging iteration (a multiple root, a bad start) shrinks its step
/// by a roughly constant factor, rarely below 1/10; quadratic convergence shrinks it by
/// orders of magnitude per step. 1e-2 separates the two with room on both sides.
pub(in crate::modal) const SUPERLINEAR_RATIO: f64 = 1e-2;

/// The condensed problem of one loaded pose: what the searches need of D(λ).
///
/// Every evaluation is counted ([`Self::evaluations`]), so the callers can hold a search
/// to a budget; none allocates.
pub trait Condensed: sealed::Sealed {
    /// D(λ), D'(λ) and the blocked count (one evaluation).
    fn eval(&mut self, lambda: f64) -> DynEval;
    /// An evaluation for the count only: D' may be left out (one evaluation).
    fn count_eval(&mut self, lambda: f64) -> DynEval;
    /// D(0) and D'(0) to start a search (the taut problem evaluates them, the sagged one
    /// reads its cached static evaluation).
    fn zero_eval(&mut self) -> DynEval;
    /// Evaluations so far (a wrapping counter; differences give a search's cost).
    fn evaluations(&self) -> u32;
    /// 3 (point mass) or 6 (rigid body).
    fn dim(&self) -> usize;
    /// The end-effector's mass matrix diag(m I, I), kg and kg·m² (rotational block zero
    /// for a point mass).
    fn ee_mass(&self) -> &Matrix6<f64>;
    /// Number of natural frequencies of the loaded pose (large for continuous chains).
    fn total_modes(&self) -> usize;
    /// The pole-free interval (a, b) of D around λ (0 and ∞ when there is no pole below or
    /// above), when the chains' blocked eigenvalues are known in closed form; None when
    /// only the count shows them (the searches then bisect on the blocked count).
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)>;
    /// Whether [`Self::pole_interval`] knows the poles (else the count alone shows them).
    fn poles_known(&self) -> bool;
    /// Where the count alone shows the poles to [`Self::pole_interval`]: whether each chain's
    /// poles can be found one by one ([`Self::next_pole`], [`Self::keyed_pole`]: each by its
    /// chain's own count, to ~1e-10 relative, within the cycle's budget), so that a scan can
    /// walk the pole intervals, each checked pole-free by the blocked count at its ends.
    fn poles_searched(&self) -> bool {
        false
    }
    /// The lowest pole of D, rad²/s² (∞: none), when the poles are known.
    fn lowest_pole(&self) -> Option<f64>;
    /// D(0) without a counted evaluation: from the chains' static end stiffness (D'(0) is
    /// left zero where that needs an evaluation of the chains).
    fn static_eval(&self) -> DynEval;

    /// The pole-free interval around the λ of the last evaluation (the chains' blocked
    /// counts there), when the poles are known.
    fn last_pole_interval(&self) -> Option<(f64, f64)>;
    /// The next distinct pole above `a` over all chains, advancing each chain's pole cursor
    /// past `a` (and first moving it back to the first pole above `a`: the poles move
    /// between the cycles of a scan), with its identity (chain, number); (∞, 0, 0) where
    /// the poles are seen only through the count (one interval holds the whole spectrum);
    /// where they are searched ([`Self::poles_searched`]), NaN when the cycle's budget ended
    /// before it was found.
    fn next_pole(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        let _ = (cursor, a);
        (f64::INFINITY, 0, 0)
    }
    /// Pole `j` of chain `c` of the loaded problem (the identity [`Self::next_pole`] gave),
    /// rad²/s²; None when there is no such chain (or the poles are not known).
    fn keyed_pole(&self, c: usize, j: usize) -> Option<f64> {
        let _ = (c, j);
        None
    }
    /// The sum rules of the loaded pose ([`SumRules`]): Σ p_k over all modes and the
    /// weighted Σ p_k/λ_k = `flex0` (tr(M_ee D(0)⁻¹), known from the first root), and
    /// where the problem has them, their matrix forms. `evaluate`: one more evaluation of
    /// D may be spent on them (the sagged problem's total comes from one far below zero;
    /// without it, the traces alone with an unknown total).
    fn sum_rules(&mut self, flex0: f64, evaluate: bool) -> SumRules;
    /// D(λ) at a complex λ (the damped frequency response), N/m: None where the chains
    /// have no complex form (the sagged continuous chains) or before a load. Point mass:
    /// the leading 3 × 3 block. Not counted as an evaluation.
    fn d_complex(&self, lambda: Complex64) -> Option<Matrix6<Complex64>>;
    /// The end-effector's constant stiffness besides the chains (a rigid body's rotational
    /// geometric stiffness, the swivel pulleys' term), its leading `dim` block.
    fn ee_stiffness(&self) -> &Matrix6<f64>;
    /// A pose is loaded (the queries of an unloaded problem answer `NotLoaded`).
    fn is_loaded(&self) -> bool;
    /// The chain holding the largest share of the kinetic-energy norm of mode shape v at
    /// the last evaluation (at x, D' = `dd`): (share, its pole nearest x, whether above,
    /// the pole's key); (0, NaN, false, `u32::MAX`) where the poles are not known. Where
    /// each pole is found by a search (the sagged chains), the pole is given only where the
    /// share reaches `share_min` (else NaN, key `u32::MAX`), and may be an earlier
    /// load's value (the poles move little between cycles; [`Self::keyed_pole`] gives this
    /// load's).
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>, share_min: f64) -> Coupling {
        let _ = (x, dd, v, share_min);
        (0.0, f64::NAN, false, u32::MAX)
    }

    /// The end-effector tracker runs with `Some(left)` evaluations left in the cycle's
    /// budget (`u32::MAX`: unlimited), or has stopped (None): a problem whose poles are
    /// found by search (the sagged chains, each by its own count) shows the tracker a
    /// mode's coupling to one chain and that chain's poles ([`Self::coupling`],
    /// [`Self::keyed_pole`]) only meanwhile, its pole searches counted in
    /// [`Self::evaluations`] and stopped where the budget ends (a pole not found then is
    /// NaN, and the partner search that needs it waits). Nothing for a problem whose
    /// poles are in closed form.
    fn follow_poles(&mut self, left: Option<u32>) {
        let _ = left;
    }

    /// The end-effector participation of the mode with unit null vector v at a root where
    /// D' = `dd`: the end-effector's share vᵀ M_ee v / vᵀ(−D')v of the mode's kinetic-energy
    /// norm (0 when that norm is not positive).
    #[inline]
    fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        let dim = self.dim();
        let kin = -quad(dd, v, dim);
        let own = quad(self.ee_mass(), v, dim);
        if kin > 0.0 {
            (own / kin).min(1.0)
        } else {
            0.0
        }
    }

    /// Number of natural frequencies strictly below λ (Wittrick–Williams), with the
    /// blocked count: (J(λ), blocked).
    #[inline]
    fn count(&mut self, lambda: f64) -> (u32, u32) {
        let e = self.count_eval(lambda);
        (e.below + e.eig().negatives() as u32, e.below)
    }
}

/// A borrowed problem is the problem (a search may run on a view it does not own).
impl<C: Condensed> sealed::Sealed for &mut C {}

impl<C: Condensed> Condensed for &mut C {
    #[inline]
    fn eval(&mut self, lambda: f64) -> DynEval {
        (**self).eval(lambda)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        (**self).count_eval(lambda)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        (**self).zero_eval()
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        (**self).evaluations()
    }
    #[inline]
    fn dim(&self) -> usize {
        (**self).dim()
    }
    #[inline]
    fn ee_mass(&self) -> &Matrix6<f64> {
        (**self).ee_mass()
    }
    #[inline]
    fn total_modes(&self) -> usize {
        (**self).total_modes()
    }
    #[inline]
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)> {
        (**self).pole_interval(lambda)
    }
    #[inline]
    fn poles_known(&self) -> bool {
        (**self).poles_known()
    }
    #[inline]
    fn poles_searched(&self) -> bool {
        (**self).poles_searched()
    }
    #[inline]
    fn lowest_pole(&self) -> Option<f64> {
        (**self).lowest_pole()
    }
    #[inline]
    fn static_eval(&self) -> DynEval {
        (**self).static_eval()
    }
    #[inline]
    fn last_pole_interval(&self) -> Option<(f64, f64)> {
        (**self).last_pole_interval()
    }
    #[inline]
    fn next_pole(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        (**self).next_pole(cursor, a)
    }
    #[inline]
    fn keyed_pole(&self, c: usize, j: usize) -> Option<f64> {
        (**self).keyed_pole(c, j)
    }
    fn sum_rules(&mut self, flex0: f64, evaluate: bool) -> SumRules {
        (**self).sum_rules(flex0, evaluate)
    }
    fn d_complex(&self, lambda: Complex64) -> Option<Matrix6<Complex64>> {
        (**self).d_complex(lambda)
    }
    #[inline]
    fn ee_stiffness(&self) -> &Matrix6<f64> {
        (**self).ee_stiffness()
    }
    #[inline]
    fn is_loaded(&self) -> bool {
        (**self).is_loaded()
    }
    fn follow_poles(&mut self, left: Option<u32>) {
        (**self).follow_poles(left)
    }
    #[inline]
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>, share_min: f64) -> Coupling {
        (**self).coupling(x, dd, v, share_min)
    }
}

/// Each chain's next pole number: the cursor of a scan over the pole intervals
/// ([`Condensed::next_pole`]).
pub type PoleCursor = [usize; MAX_CHAINS];

/// The trait is implemented by this crate's loaded problems only.
pub(in crate::modal) mod sealed {
    /// The seal.
    pub trait Sealed {}
}

/// The sum rules of the loaded pose that bound the unwatched modes' participation (the
/// end-effector tracker's certificate, `ee_tracker::bound`).
#[derive(Debug, Clone, Copy)]
pub struct SumRules {
    /// Σ_k p_k over all modes.
    pub(in crate::modal) total: f64,
    /// Σ_k p_k/λ_k over all modes, s²/rad² (from the first root; NaN when unknown).
    pub(in crate::modal) over_lambda: f64,
    /// The matrix forms (None: the trace form only).
    pub(in crate::modal) matrices: Option<SumMatrices>,
}

impl SumRules {
    /// The trace forms only: Σ p_k and Σ p_k/λ_k.
    pub(in crate::modal) fn traces(total: f64, over_lambda: f64) -> SumRules {
        SumRules {
            total,
            over_lambda,
            matrices: None,
        }
    }
}

/// The matrix forms of the sum rules (`ee_tracker::bound`'s docs), their leading `dim`
/// blocks.
#[derive(Debug, Clone, Copy)]
pub struct SumMatrices {
    /// M_∞⁻¹ = Σ_k φ_k φ_kᵀ, 1/kg (1/(kg·m²) in the rotational block).
    pub(in crate::modal) m_inf_inv: Matrix6<f64>,
    /// D(0)⁻¹ = Σ_k φ_k φ_kᵀ/λ_k, m/N (rad/(N·m) in the rotational block); NaN entries when
    /// unknown (the weighted form is then not used).
    pub(in crate::modal) flex: Matrix6<f64>,
    /// M_ee^{1/2}, √kg (√(kg·m²) in the rotational block).
    pub(in crate::modal) m_sqrt: Matrix6<f64>,
    /// 3 (point mass) or 6 (rigid body).
    pub(in crate::modal) dim: usize,
}

impl SumMatrices {
    /// λ_max(M_ee^{1/2} r M_ee^{1/2}) over the leading `dim` block (no allocation).
    pub(in crate::modal) fn top(&self, r: &Matrix6<f64>) -> f64 {
        let s = self.m_sqrt * r * self.m_sqrt;
        if self.dim == 3 {
            let b: Matrix3<f64> = s.fixed_view::<3, 3>(0, 0).into_owned();
            SymmetricEigen::new(b).eigenvalues.max()
        } else {
            SymmetricEigen::new(s).eigenvalues.max()
        }
    }
}
