//! The first K modes of the sagged problem: the spectrum search of `modal::spectrum`
//! (count brackets, bisection while the blocked count differs at the bracket's ends,
//! safeguarded Newton on one branch of D once it is pole-free, clusters from the count),
//! on the sagged problem.

use super::problem::SagView;
use super::SagModalSolver;
use crate::modal::spectrum::modes_into;
use crate::modal::{ModalError, Mode, SpectrumParams};

impl SagModalSolver {
    /// The first `k` natural frequencies (ascending) into `out`, [`SpectrumParams::default`].
    /// Returns how many were written: min(k, out.len(), [`Self::total_modes`]).
    pub fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, ModalError> {
        self.modes_with(k, &SpectrumParams::default(), out)
    }

    /// [`Self::modes`] with explicit parameters (`pole_probe` is the relative width at
    /// which a bisection across a pole stops and reports the mode at the pole).
    pub fn modes_with(
        &mut self,
        k: usize,
        params: &SpectrumParams,
        out: &mut [Mode],
    ) -> Result<usize, ModalError> {
        self.require_loaded()?;
        let view = SagView {
            p: &self.problem,
            evals: &mut self.evaluations,
        };
        modes_into(view, k, params, out)
    }
}
