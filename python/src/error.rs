//! `cablevib.CablevibError`: every error of the library, with the command line's message.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;

create_exception!(
    cablevib,
    CablevibError,
    PyValueError,
    "An error of cablevib (bad scene, infeasible pose, unreachable requirement, …), with the \
     same one-line message the command line prints after `cablevib: `. A subclass of \
     ValueError: every such error is caused by the values given."
);
