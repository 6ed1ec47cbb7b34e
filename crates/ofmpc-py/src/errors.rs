//! Library errors as Python exceptions: `ofmpc.OfmpcError` (a `ValueError`)
//! carrying the library's own message.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::PyErr;

create_exception!(
    ofmpc,
    OfmpcError,
    PyValueError,
    "An error reported by the ofmpc library (bad model, program, setting or input); the message says where and what to do."
);

/// Any library error (its `Display` is the user-facing message) as an [`OfmpcError`].
pub fn to_py<E: std::fmt::Display>(e: E) -> PyErr {
    OfmpcError::new_err(ofmpc::input::for_reader(&e.to_string()))
}

/// An `anyhow` error with its whole chain (`a: b: c`), as the CLI prints it (a cause the
/// message already holds said once).
pub fn chain_to_py(e: anyhow::Error) -> PyErr {
    OfmpcError::new_err(ofmpc_scenario::chain_text(e.as_ref()))
}
