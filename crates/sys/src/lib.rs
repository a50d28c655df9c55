//! The operating system in one place.
//!
//! Everything mrsim asks Linux directly, other than the transport's own
//! primitives (the doorbell's futex and mapping, the listener's `ppoll`),
//! lives here: whether a process runs and when it started, CPU time and
//! peak memory, CPU work on the thread's own clock, CPU affinity and the
//! scheduling policies (SCHED_OTHER, SCHED_FIFO, SCHED_DEADLINE and its
//! admission limit and overruns), and termination signals. The
//! rest of the workspace calls these safe functions and holds no `unsafe`
//! for them, so a port to another OS (or a review of every `unsafe` that
//! touches the process) starts and ends in this crate.
//!
//! Every function is best effort where the OS may refuse (a refused
//! priority changes only timing) and says so in its result where the caller
//! must know.
#![warn(missing_docs)]

pub mod cpu;
pub mod memory;
pub mod policy;
pub mod process;
pub mod sched;
pub mod signal;
pub mod usage;
