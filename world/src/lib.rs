//! The mrsim world: the one process that owns the physics.
//!
//! Shaped like rapier's own sets and pipelines: [`World`] is data plus a
//! step (read commands, step, publish), and [`run::run`] is the tick loop
//! that drives a `World` through an injected
//! [`WorldTransport`](mrsim_transport::WorldTransport), so the same loop
//! serves iceoryx2 processes and in-process threads. The world never sees a
//! planner (it borrows only the pure `distance_to_path` helper of the
//! planners crate for the designated-path metrics): it enforces each robot's actuator limits whatever the agent
//! asks, moves scripted obstacles, detects collisions, and records
//! everything a researcher needs afterwards ([`record`]).
#![warn(missing_docs)]

pub mod batch;
pub mod clearance;
pub mod histogram;
pub mod live;
pub mod metrics;
pub mod motion;
pub mod names;
pub mod path_metrics;
pub mod physics;
pub mod record;
pub mod run;
pub mod timings;
pub mod tracking;

pub use physics::{Applied, World, WorldError};
pub use run::{RunOptions, RunOutcome, run};
