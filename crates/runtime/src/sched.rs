//! Scheduling of a run: CPU affinity and real-time priority (SCHED_FIFO).
//!
//! Both are applied to the calling process before it starts anything;
//! children inherit the affinity mask and the scheduling policy across
//! fork and exec, and threads inherit them from the thread that spawns them,
//! so setting them once in the launcher covers the world and every agent.

use crate::error::Invalid;

use mrsim_sys::sched::{RT_PRIORITY, parse_cpus, set_affinity, set_fifo};

/// How to schedule a run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Sched {
    /// Pin every process of the run to these CPUs (a list such as `0,1` or
    /// `0-3`); `None`: not pinned.
    pub cpus: Option<String>,
    /// Run under SCHED_FIFO where permitted.
    pub rt: bool,
}

/// What [`apply`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Applied {
    /// The CPUs everything is pinned to (empty: not pinned).
    pub cpus: Vec<usize>,
    /// True if SCHED_FIFO is in force.
    pub rt: bool,
    /// SCHED_FIFO was asked for and refused: why, and that the run goes on
    /// with normal scheduling.
    pub rt_refused: Option<String>,
}

/// Applies `sched` to the calling process. A bad CPU list is refused; a
/// refused SCHED_FIFO (EPERM: no CAP_SYS_NICE or RLIMIT_RTPRIO) is not an
/// error: [`Applied::rt_refused`] says so and the run goes on with normal
/// scheduling.
pub fn apply(sched: &Sched) -> Result<Applied, Invalid> {
    let mut applied = Applied::default();
    if let Some(list) = &sched.cpus {
        let cpus = parse_cpus(list).map_err(Invalid)?;
        set_affinity(&cpus)
            .map_err(|e| Invalid(format!("--cpus {list}: sched_setaffinity: {e}")))?;
        applied.cpus = cpus;
    }
    if sched.rt {
        match set_fifo(RT_PRIORITY) {
            Ok(()) => applied.rt = true,
            Err(e) => {
                applied.rt_refused = Some(format!(
                    "--rt: cannot use SCHED_FIFO ({e}); running with normal scheduling \
                     (needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO of at least {RT_PRIORITY})"
                ))
            }
        }
    }
    Ok(applied)
}
