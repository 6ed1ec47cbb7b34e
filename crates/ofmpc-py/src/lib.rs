//! Python bindings of `ofmpc` (the extension module `ofmpc._ofmpc`; the
//! package `ofmpc` in `python/ofmpc` re-exports it with docstrings and stubs).
//!
//! A thin layer over the public Rust API, one file per concept: `errors.rs`
//! (library errors → Python exceptions), `arrays.rs` (numpy in and out),
//! `robot.rs` (model and rigid-body algorithms), `plan.rs` (program → joint
//! reference), `controller.rs` (one predictive controller, step by step), `supervised.rs`
//! (the controller behind its guard, with the safe stop's command) and
//! `run.rs` (a whole scenario, as `ofmpc run` runs it).

use pyo3::prelude::*;

mod arrays;
mod controller;
mod errors;
mod plan;
mod robot;
mod run;
mod supervised;

/// The extension module `ofmpc._ofmpc`.
#[pymodule]
fn _ofmpc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("OfmpcError", m.py().get_type::<errors::OfmpcError>())?;
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<plan::PyReference>()?;
    m.add_class::<controller::PyController>()?;
    m.add_class::<supervised::PySupervised>()?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    m.add_function(wrap_pyfunction!(plan::read_program, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_file, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_json, m)?)?;
    m.add("STANDARD_GRAVITY", ofmpc::robot::STANDARD_GRAVITY)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
