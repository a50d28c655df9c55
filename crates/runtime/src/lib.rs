//! The library behind `mrsim run`: everything between a parsed command line
//! and the run's outcome.
//!
//! - [`validate`]: a scenario file and its overrides are checked once (the
//!   file, every robot's planner and parameters, the obstacles' motion
//!   models) into a [`Validated`] value that everything else takes, so no
//!   step validates again and the world is built once per process.
//! - [`launch`]: a whole run, as processes (one world, one agent per robot,
//!   over iceoryx2) or in one process ([`inproc`]: the world in the calling
//!   thread and a pool of worker threads driving every robot); signals to
//!   the launcher stop the run as they stop a world.
//! - [`world`] and [`agent`]: the two halves a user starts by hand.
//! - [`finish`]: one ending for every path (diagnostics merged, usage
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

pub mod agent;
pub mod bench;
pub mod cores;
pub mod error;
pub mod finish;
pub mod inproc;
pub mod launch;
pub mod memory;
mod namespace;
pub mod out;
pub mod rerun;
pub mod ros2;
pub mod routes;
pub mod sched;
pub mod sim;
pub mod sweep;
pub mod transport;
pub mod usage;
pub mod validate;
pub mod world;

pub use error::{Invalid, Refusal};
pub use finish::Outcome;
pub use validate::{ScenarioSource, Validated};
