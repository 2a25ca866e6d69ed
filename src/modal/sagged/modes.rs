//! The first K modes of the sagged problem: the spectrum search of `modal::spectrum`
//! (count brackets, bisection while the blocked count differs at the bracket's ends,
//! safeguarded Newton on one branch of D once it is pole-free, clusters from the count),
//! on the sagged problem, through the solvers' shared `modes` and `modes_with`.

use super::problem::SagView;
use super::SagModalSolver;
use crate::modal::spectrum::spectrum_modes;
use crate::modal::ModalError;

impl SagModalSolver {
    /// The loaded sagged problem (the spectrum search's view); NotLoaded before a load.
    fn condensed(&mut self) -> Result<SagView<'_>, ModalError> {
        self.require_loaded()?;
        Ok(SagView {
            p: &self.problem,
            evals: &mut self.evaluations,
        })
    }

    spectrum_modes!();
}
