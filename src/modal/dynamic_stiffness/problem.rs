//! [`TautChains`]: the loaded taut problem (uniform chains, their poles in closed form) and
//! its evaluation buffers, as the structured solver sees it ([`Condensed`]).

use super::{EvalScratch, LoadedChains};
use crate::modal::engine::{sealed, Condensed, Coupling, DynEval, PoleCursor, SumRules};
use nalgebra::{Matrix6, Vector6};
use num_complex::Complex64;

/// The taut problem of one pose: the loaded chains (`load` writes them; read-only on the
/// hot path) and what one evaluation of D(λ) writes. The problem of
/// [`ModalSolver`](crate::modal::ModalSolver).
#[derive(Debug, Clone)]
pub struct TautChains {
    pub(in crate::modal) p: LoadedChains,
    pub(in crate::modal) s: EvalScratch,
}

impl TautChains {
    /// Nothing loaded; the pole table's capacity reserved (the only allocation).
    pub(in crate::modal) fn new() -> TautChains {
        TautChains {
            p: LoadedChains::new(),
            s: EvalScratch::new(),
        }
    }
}

impl sealed::Sealed for TautChains {}

impl Condensed for TautChains {
    #[inline]
    fn eval(&mut self, lambda: f64) -> DynEval {
        self.s.eval(&self.p, lambda)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        self.s.eval(&self.p, lambda)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        self.s.eval(&self.p, 0.0)
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        self.s.evaluations
    }
    #[inline]
    fn dim(&self) -> usize {
        self.p.dim
    }
    #[inline]
    fn ee_mass(&self) -> &Matrix6<f64> {
        &self.p.m6
    }
    #[inline]
    fn total_modes(&self) -> usize {
        self.p.total_modes()
    }
    #[inline]
    fn pole_interval(&self, lambda: f64) -> Option<(f64, f64)> {
        Some(self.p.pole_interval(lambda))
    }
    #[inline]
    fn poles_known(&self) -> bool {
        true
    }
    #[inline]
    fn lowest_pole(&self) -> Option<f64> {
        Some(self.p.lowest_pole())
    }
    #[inline]
    fn static_eval(&self) -> DynEval {
        self.p.static_eval()
    }
    #[inline]
    fn last_pole_interval(&self) -> Option<(f64, f64)> {
        Some(self.s.last_pole_interval(&self.p))
    }
    #[inline]
    fn next_pole(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        self.p.next_distinct_pole(cursor, a)
    }
    #[inline]
    fn keyed_pole(&self, c: usize, j: usize) -> Option<f64> {
        (c < self.p.n_chains).then(|| self.p.chain_pole(c, j))
    }
    /// The traces: Σ p_k from the load (the chains' end masses in closed form), no
    /// evaluation.
    fn sum_rules(&mut self, flex0: f64, _evaluate: bool) -> SumRules {
        SumRules::traces(self.p.p_total, flex0)
    }
    fn d_complex(&self, lambda: Complex64) -> Option<Matrix6<Complex64>> {
        Some(self.p.d_complex(lambda))
    }
    #[inline]
    fn ee_stiffness(&self) -> &Matrix6<f64> {
        &self.p.k6
    }
    #[inline]
    fn is_loaded(&self) -> bool {
        true
    }
    #[inline]
    /// The poles in closed form: `share_min` changes nothing.
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>, _share_min: f64) -> Coupling {
        self.s.coupling(&self.p, x, dd, v)
    }
}
