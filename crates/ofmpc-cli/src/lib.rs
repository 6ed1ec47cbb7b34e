//! The `ofmpc` command's library: argument definitions, scenario files,
//! commands, and the output layer (atomic files, figures, HTML report). The
//! binary (`src/main.rs`) only parses the arguments and prints errors.

#![warn(missing_docs)]

pub mod api;
pub mod cli;
pub mod commands;
pub mod errors;
pub mod figures;
pub mod output;
pub mod scenario;
pub mod tables;
