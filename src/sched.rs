//! Scheduling controls shared by `run` and `bench`: CPU affinity
//! (`--cpus LIST`) and real-time priority (`--rt`, SCHED_FIFO).
//!
//! Both are applied to the calling process before it starts anything;
//! children inherit the affinity mask and the scheduling policy across
//! fork and exec, and threads inherit them from the thread that spawns them,
//! so setting them once in the launcher covers the world and every agent.

use clap::Args;

/// `--cpus` and `--rt`.
#[derive(Debug, Clone, Default, Args)]
pub struct SchedArgs {
    /// Pin every process of the run to these CPUs (e.g. `0,1` or `0-3`).
    #[arg(long, value_name = "LIST")]
    pub cpus: Option<String>,
    /// Run the world and the agents under SCHED_FIFO where permitted (a
    /// warning and normal scheduling where not).
    #[arg(long)]
    pub rt: bool,
}

pub use mrsim_sys::sched::{RT_PRIORITY, online_cpus, parse_cpus, set_affinity, set_fifo};

/// What [`apply`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Applied {
    /// The CPUs everything is pinned to (empty: not pinned).
    pub cpus: Vec<usize>,
    /// True if SCHED_FIFO is in force.
    pub rt: bool,
}

/// Applies `--cpus` and `--rt` to the calling process. A bad CPU list is an
/// error; a refused SCHED_FIFO (EPERM, no CAP_SYS_NICE or RLIMIT_RTPRIO) is
/// a warning on stderr and the run goes on with normal scheduling.
pub fn apply(args: &SchedArgs) -> Result<Applied, String> {
    let mut applied = Applied::default();
    if let Some(list) = &args.cpus {
        let cpus = parse_cpus(list)?;
        set_affinity(&cpus).map_err(|e| format!("--cpus {list}: sched_setaffinity: {e}"))?;
        applied.cpus = cpus;
    }
    if args.rt {
        match set_fifo(RT_PRIORITY) {
            Ok(()) => applied.rt = true,
            Err(e) => eprintln!(
                "warning: --rt: cannot use SCHED_FIFO ({e}); running with normal scheduling \
                 (needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO of at least {RT_PRIORITY})"
            ),
        }
    }
    Ok(applied)
}

/// Command-line arguments that pass `args` on to another `mrsim` process.
pub fn to_args(args: &SchedArgs) -> Vec<String> {
    let mut v = Vec::new();
    if let Some(c) = &args.cpus {
        v.push("--cpus".to_string());
        v.push(c.clone());
    }
    if args.rt {
        v.push("--rt".to_string());
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_lists_with_numbers_and_ranges_parse_sorted_and_deduplicated() {
        assert_eq!(parse_cpus("0"), Ok(vec![0]));
        if online_cpus() >= 2 {
            assert_eq!(parse_cpus("1,0-1"), Ok(vec![0, 1]));
        }
    }

    #[test]
    fn bad_cpu_lists_are_refused_with_the_entry_named() {
        for bad in ["", "a", "1-0", "0,,1", "99999"] {
            assert!(parse_cpus(bad).is_err(), "{bad}");
        }
        let e = parse_cpus("4096").unwrap_err();
        assert!(e.contains("4096"), "{e}");
    }
}
