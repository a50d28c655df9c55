//! The `mrsim` command line: `run` (a whole run: world process, one agent
//! process per robot, outputs, summary), `world` and `agent` (the parts by
//! hand), `sweep` and `bench` (experiments over many runs), `top` (a live
//! view), `report`, `check` and `planners`.
//!
//! It is thin: [`cli`] holds the clap types, each subcommand's file turns
//! them into the runtime's requests, calls `mrsim-runtime` and prints what
//! comes back. Everything a run does lives in the libraries, so each part
//! can be tested without processes.
#![warn(missing_docs)]

pub mod agent;
pub mod bench;
pub mod check;
pub mod cli;
pub mod exit;
pub mod outcome;
pub mod planners;
pub mod progress;
pub mod report;
pub mod run;
pub mod sweep;
pub mod table;
pub mod top;
pub mod watch;
pub mod world;
