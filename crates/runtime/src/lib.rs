//! The library behind `mrsim run`: everything between a parsed command line
//! and the run's outcome.
//!
//! - `validate`: a scenario file and its overrides are checked once (the
//!   file, every robot's planner and parameters, the obstacles' motion
//!   models) into a [`Validated`] value that everything else takes, so no
//!   step validates again and the world is built once per process.
//! - `launch`: a whole run, as processes (one world, one agent per robot,
//!   over iceoryx2) or in one process (`inproc`: the world in the calling
//!   thread and a pool of worker threads driving every robot); signals to
//!   the launcher stop the run as they stop a world.
//! - [`world`] and [`agent`]: the two halves a user starts by hand.
//! - `finish`: one ending for every path (diagnostics merged, usage
//!   written, metrics read, plots and replay drawn) that returns an
//!   [`Outcome`].
//! - [`bench`] and [`sweep`]: experiments made of many runs.
//! - [`rerun`]: a recorded run again, in lockstep, with the timing it
//!   recorded (byte-identical, or a counterfactual with overrides).
//!
//! It is shaped so because more than the command line starts runs (tests
//! and the Python bindings): what a run does lives here once,
//! and each caller only turns its own input into the request types and
//! presents the outcome.
//! Hence the one rule of this crate: it prints nothing. Whatever a caller
//! might show (warnings, notes, progress, restarts) comes back as a value
//! or through an event callback. Errors are one enum per operation; the
//! variant [`Invalid`] (reachable through [`Refusal`]) marks input refused
//! before anything started, which the command line reports with exit
//! status 2.
#![warn(missing_docs)]
//!
//! **Its surface.** One public module per way into a run that a caller
//! takes whole: [`agent`], [`world`] and [`ros2`] (a process started by
//! hand), [`bench`], [`sweep`] and [`rerun`] (experiments of many runs, or
//! one again), [`sim`] (the stepping engine of the learning environments).
//! Everything they share (validation, the launch of a run, its finish, the
//! errors, the scheduler and the transports named on a command line) lives
//! in private modules and is re-exported here by name, as rapier exports
//! its sets and pipelines, so a module can be split or moved without a
//! caller noticing.

pub mod agent;
pub mod bench;
mod cores;
mod error;
mod finish;
mod inproc;
mod launch;
mod memory;
mod namespace;
mod out;
pub mod rerun;
pub mod ros2;
mod routes;
mod sched;
pub mod sim;
pub mod sweep;
mod transport;
mod usage;
mod validate;
pub mod world;

pub use error::{Invalid, Refusal, in_words};
pub use finish::{AgentFailure, FinishError, Outcome};
pub use inproc::{InprocError, WorldRunError};
pub use launch::{
    Event, InProcess, InProcessError, LaunchError, MAX_RESTARTS, Prepared, ProcessSpec, Ros2Side,
    RunRequest, RunResult, Starter, prepare, run_in_process,
};
pub use memory::{BASE, PER_ROBOT, SENSED};
pub use sched::Sched;
pub use transport::Transport;
pub use validate::{ScenarioSource, Validated, mode_name};
