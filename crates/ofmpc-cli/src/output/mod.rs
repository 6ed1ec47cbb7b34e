//! Output layer of the `ofmpc` binary: atomic files, figures and the HTML report.
//!
//! * [`atomic`]: files and output directories that are never left half-written.
//! * [`plot`]: figures (grids of panels) rendered to PNG and SVG with an embedded font.
//! * [`report`]: one self-contained HTML page with tables and figures.
//! * `run_files`: the one list of what `run`/`reproduce` write (plan, leftovers, writer).

pub mod atomic;
pub mod chart;
pub mod cleanup;
pub(crate) mod compare;
pub mod console;
pub mod mesh;
pub mod plot;
pub mod replay;
pub mod report;
pub(crate) mod run_files;
