//! The mrsim world: the one process that owns the physics.
//!
//! The world never sees a planner (it borrows only the pure
//! `distance_to_path` helper of the planners crate for the designated-path
//! metrics, the car's `bicycle_step`, and ORCA's half-planes and linear
//! programs, `orca::Walker`, for the people): it enforces each robot's
//! actuator limits whatever the agent asks, moves scripted obstacles and
//! people, detects collisions, and records everything a researcher needs
//! afterwards.
//!
//! The crate is shaped by role, the way rapier shapes its sets and
//! pipelines, so that each part can be read and tested on its own:
//!
//! - [`physics`]: [`World`], data plus a step (apply commands, move the
//!   obstacles ([`motion`]) and the people ([`people`]), step rapier, report contacts). No clock, no
//!   transport.
//! - [`run`](mod@run): the tick loop, driving a `World` through an injected
//!   [`WorldTransport`](mrsim_transport::WorldTransport) so the same loop
//!   serves iceoryx2 processes and in-process threads. Split by role:
//!   [`run::admission`] (joins, tokens, which commands count: verdicts and
//!   events, no side effects), [`run::schedule`] (lockstep waits, realtime
//!   deadlines, on an injectable clock), [`run::recording`] (events,
//!   counts, live statistics, metrics.json); [`run()`] wires them. Its unit
//!   tests run over an in-memory transport and a clock it moves.
//! - Off the tick loop, on their own threads: [`record`] (trajectory.csv,
//!   events.jsonl, fed in [`batch`]es), [`tracking`] (the motion metrics
//!   from the recorded states, with [`clearance`] on the grids of
//!   `mrsim-spatial` and [`path_metrics`], and [`interaction`]: proxemics,
//!   time to collision, encounters), [`timings`] (the commands'
//!   [`histogram`]s), and [`live`] statistics for observers.
//! - [`metrics`]: what the loop accumulates per robot; the schema of
//!   metrics.json is `mrsim-runfolder`'s, which every reader shares.
#![warn(missing_docs)]

pub mod batch;
pub mod clearance;
pub mod histogram;
pub mod interaction;
pub mod live;
pub mod metrics;
pub mod motion;
pub mod names;
pub mod path_metrics;
pub mod people;
pub mod physics;
pub mod record;
pub mod run;
pub mod scan;
pub mod sensed;
pub mod timings;
pub mod tracking;

pub use physics::{Applied, World, WorldError};
pub use run::{Route, RunOptions, RunOutcome, run};
