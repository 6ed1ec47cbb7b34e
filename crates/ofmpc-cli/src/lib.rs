//! The `ofmpc` command's library: argument definitions, commands, and the
//! output layer (atomic files, figures, HTML report). Scenario files, the job
//! runner and the analyses live in the `ofmpc_scenario` crate; this one parses
//! arguments, prints and writes. The binary (`src/main.rs`) only parses the
//! arguments and prints errors.

#![warn(missing_docs)]

pub mod args;
pub mod chain_sets;
pub mod cli;
pub mod commands;
pub mod errors;
pub(crate) mod figures;
pub mod init_choice;
pub mod output;
pub(crate) mod tables;
pub mod verdict;
