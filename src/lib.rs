//! The `mrsim` launcher: `run` (a whole run: world process, one agent
//! process per robot, outputs, summary), `world` and `agent` (the parts by
//! hand), `sweep` (experiments over many runs), `planners` (what is
//! available).
//!
//! The binary is thin: it parses the command line and calls [`cli::main`];
//! everything else lives in libraries (`mrsim-world`, `mrsim-agents`,
//! `mrsim-transport`, `mrsim-scenario`, `mrsim-planners`), so each part can
//! be tested without processes.
#![warn(missing_docs)]

pub mod baseline;
pub mod bench;
pub mod cli;
pub mod inproc;
pub mod launch;
pub mod progress;
pub mod report_cmd;
pub mod sched;
pub mod sweep;
pub mod table;
pub mod top;
pub mod usage;
pub mod watch;
