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

/// SCHED_FIFO priority used by `--rt`: above normal tasks, well below the
/// kernel's own real-time threads (which run at 50 and 99).
pub const RT_PRIORITY: i32 = 10;

/// Parses a CPU list: comma-separated numbers and ranges (`0,2-3`).
pub fn parse_cpus(list: &str) -> Result<Vec<usize>, String> {
    let mut cpus = Vec::new();
    for part in list.split(',').map(str::trim) {
        if part.is_empty() {
            return Err(format!("--cpus {list}: empty entry"));
        }
        let bad = |p: &str| format!("--cpus {list}: `{p}` is not a CPU number or range like 0-3");
        let (a, b) = match part.split_once('-') {
            Some((a, b)) => (
                a.trim().parse::<usize>().map_err(|_| bad(part))?,
                b.trim().parse::<usize>().map_err(|_| bad(part))?,
            ),
            None => {
                let c = part.parse::<usize>().map_err(|_| bad(part))?;
                (c, c)
            }
        };
        if a > b || b >= libc::CPU_SETSIZE as usize {
            return Err(bad(part));
        }
        cpus.extend(a..=b);
    }
    cpus.sort_unstable();
    cpus.dedup();
    let online = online_cpus();
    if let Some(&c) = cpus.iter().find(|&&c| c >= online) {
        return Err(format!(
            "--cpus {list}: CPU {c} does not exist (this machine has {online}: 0-{})",
            online.saturating_sub(1)
        ));
    }
    Ok(cpus)
}

/// Number of CPUs online.
pub fn online_cpus() -> usize {
    // SAFETY: sysconf has no preconditions.
    let n = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
    if n > 0 { n as usize } else { 1 }
}

/// Pins the calling thread (and so everything it starts later) to `cpus`.
pub fn set_affinity(cpus: &[usize]) -> std::io::Result<()> {
    // SAFETY: cpu_set_t is plain data; CPU_ZERO/CPU_SET only write into it
    // (indices were checked against CPU_SETSIZE); sched_setaffinity reads it.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_ZERO(&mut set);
        for &c in cpus {
            libc::CPU_SET(c, &mut set);
        }
        if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// Puts the calling thread under SCHED_FIFO at `priority`.
pub fn set_fifo(priority: i32) -> std::io::Result<()> {
    let param = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: the param struct lives for the call.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

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
