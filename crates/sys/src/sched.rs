//! Scheduling: CPU affinity (of this thread, of a process to start),
//! SCHED_FIFO, and background threads.
//!
//! Children inherit the affinity mask and the scheduling policy across fork
//! and exec, and threads inherit them from the thread that spawns them, so
//! a launcher that sets them once covers the world and every agent.

/// SCHED_FIFO priority used by `--rt`: above normal tasks, well below the
/// kernel's own real-time threads (which run at 50 and 99).
pub const RT_PRIORITY: i32 = 10;

/// SCHED_FIFO priority of the world in a realtime run under
/// `[world.cpus]`: above every agent's level (theirs are 98 and below).
pub const WORLD_PRIORITY: u8 = 99;

/// Number of CPUs online.
pub fn online_cpus() -> usize {
    // SAFETY: sysconf has no preconditions.
    let n = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
    if n > 0 { n as usize } else { 1 }
}

/// The largest CPU number an affinity mask can hold, plus one.
pub fn max_cpus() -> usize {
    libc::CPU_SETSIZE as usize
}

/// Parses a CPU list: comma-separated numbers and ranges (`0,2-3`), each
/// a CPU that is online. The error names the list and the bad entry.
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
        if a > b || b >= max_cpus() {
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

/// Pins the calling thread (and so everything it starts later) to `cpus`
/// (each below [`max_cpus`]).
pub fn set_affinity(cpus: &[usize]) -> std::io::Result<()> {
    if let Some(&c) = cpus.iter().find(|&&c| c >= max_cpus()) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("CPU {c} is beyond the affinity mask"),
        ));
    }
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

/// Makes the process `command` starts run on `cpus` only (each below
/// [`max_cpus`]): its affinity is set in the child between fork and exec,
/// so neither the caller nor the other processes it starts change.
pub fn pin_command(command: &mut std::process::Command, cpus: &[usize]) -> std::io::Result<()> {
    use std::os::unix::process::CommandExt;
    if let Some(&c) = cpus.iter().find(|&&c| c >= max_cpus()) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("CPU {c} is beyond the affinity mask"),
        ));
    }
    // Built before the fork: the child only makes the system call.
    // SAFETY: cpu_set_t is plain data; CPU_ZERO/CPU_SET only write into it
    // (indices were checked against CPU_SETSIZE).
    let set = unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_ZERO(&mut set);
        for &c in cpus {
            libc::CPU_SET(c, &mut set);
        }
        set
    };
    // SAFETY: the closure runs in the forked child before exec and only
    // makes one async-signal-safe system call on memory it owns (no
    // allocation, no locks).
    unsafe {
        command.pre_exec(move || {
            if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    Ok(())
}

/// The CPUs the calling thread may run on; `None` if it cannot be read.
pub fn affinity() -> Option<Vec<usize>> {
    // SAFETY: a zeroed cpu_set_t is a valid empty set; the call fills it.
    let mut set: libc::cpu_set_t = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::sched_getaffinity(0, std::mem::size_of_val(&set), &mut set) };
    if r != 0 {
        return None;
    }
    // SAFETY: CPU_ISSET reads the set we own, for indices it can hold.
    Some(
        (0..max_cpus())
            .filter(|&c| unsafe { libc::CPU_ISSET(c, &set) })
            .collect(),
    )
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

/// The calling thread's SCHED_FIFO priority, if it runs under SCHED_FIFO.
pub fn fifo_priority() -> Option<i32> {
    let mut param = libc::sched_param { sched_priority: 0 };
    // SAFETY: both only read the calling thread's policy, the second into
    // the struct we own.
    let fifo = unsafe { libc::sched_getscheduler(0) } == libc::SCHED_FIFO
        && unsafe { libc::sched_getparam(0, &mut param) } == 0;
    fifo.then_some(param.sched_priority)
}

/// Moves the calling thread into the background: normal (not real-time)
/// scheduling at nice 10, so that it runs on time the tick loop and the
/// planners leave idle rather than delaying them. For the threads that only
/// write files (trajectory, diagnostics): in a lockstep run a writer that
/// preempts one planner thread delays the whole tick. Best effort: lowering
/// a thread's own priority is always allowed, and a refusal changes
/// nothing but timing.
pub fn background_thread() {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: the param struct lives for the call; 0 = the calling thread.
    unsafe {
        libc::sched_setscheduler(0, libc::SCHED_OTHER, &param);
        // With PRIO_PROCESS a thread id names just that thread on Linux.
        libc::setpriority(libc::PRIO_PROCESS, libc::gettid() as libc::id_t, 10);
    }
}

/// Burns CPU under normal scheduling (SCHED_OTHER, nice 0, whatever policy
/// the parent passed down) until process `parent` is no longer this
/// process's parent, i.e. it has exited, however it ended: the load of
/// `mrsim bench --stress`, a CPU-bound neighbour as another program on the
/// same cores would be. The parent is checked every few milliseconds, so a
/// killed bench leaves no load behind.
pub fn spin_while_child_of(parent: u32) {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: the param struct lives for the call; 0 = the calling thread,
    // the process's only one.
    unsafe {
        libc::sched_setscheduler(0, libc::SCHED_OTHER, &param);
        libc::setpriority(libc::PRIO_PROCESS, 0, 0);
    }
    let mut x: u64 = 1;
    while std::os::unix::process::parent_id() == parent {
        for _ in 0..1_000_000 {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            std::hint::black_box(x);
        }
    }
}

/// The world's place under SCHED_FIFO (`--rt`) while it ticks: one level
/// below its agents. An agent woken by the tick's doorbell then runs at
/// once, instead of waiting on the world's CPU until the world has woken
/// every other agent. Only while it ticks: before, hundreds of agents
/// retrying to connect at the higher level would keep the world from ever
/// creating what they wait for.
#[derive(Debug)]
pub struct BelowAgents {
    /// The level to go back to when dropped.
    restore: Option<i32>,
}

impl BelowAgents {
    /// Under SCHED_FIFO at priority p > 1, moves the calling thread to
    /// p - 1 until the guard is dropped; otherwise does nothing.
    pub fn enter() -> Self {
        let restore = fifo_priority()
            .filter(|&p| p > 1)
            .filter(|&p| set_fifo(p - 1).is_ok());
        Self { restore }
    }

    /// A guard that moved nothing (the world ticks where it is).
    pub fn inactive() -> Self {
        Self { restore: None }
    }

    /// True if the thread was moved (it runs under SCHED_FIFO below its
    /// agents).
    pub fn active(&self) -> bool {
        self.restore.is_some()
    }
}

impl Drop for BelowAgents {
    fn drop(&mut self) {
        if let Some(p) = self.restore {
            let _ = set_fifo(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_lists_with_numbers_and_ranges_parse_sorted_and_deduplicated() {
        assert_eq!(parse_cpus("0"), Ok(vec![0]));
        assert_eq!(parse_cpus("0,0"), Ok(vec![0]));
        if online_cpus() >= 2 {
            assert_eq!(parse_cpus("1,0-1"), Ok(vec![0, 1]));
        }
    }

    #[test]
    fn bad_cpu_lists_are_refused_with_the_entry_named() {
        for bad in ["", "a", "1-0", "0,,1", "-1", "99999"] {
            let e = parse_cpus(bad).expect_err(bad);
            assert!(e.contains("--cpus"), "{bad}: {e}");
        }
        let e = parse_cpus("4096").unwrap_err();
        assert!(e.contains("4096"), "{e}");
        let beyond = format!("{}", online_cpus());
        let e = parse_cpus(&beyond).expect_err("beyond the machine");
        assert!(e.contains("does not exist"), "{e}");
    }

    #[test]
    fn the_world_ticks_one_fifo_level_below_its_agents_and_goes_back_after() {
        // Not under SCHED_FIFO: nothing moves.
        assert_eq!(fifo_priority(), None);
        assert!(!BelowAgents::enter().active());
        if let Err(e) = set_fifo(10) {
            // Said, not passed in silence: without root, CAP_SYS_NICE or
            // RLIMIT_RTPRIO `--rt` runs with normal scheduling.
            eprintln!("skipped: SCHED_FIFO is not permitted here ({e})");
            return;
        }
        let below = BelowAgents::enter();
        let during = fifo_priority();
        drop(below);
        let after = fifo_priority();
        // Back to normal scheduling before asserting.
        let normal = libc::sched_param { sched_priority: 0 };
        // SAFETY: the param struct lives for the call.
        unsafe { libc::sched_setscheduler(0, libc::SCHED_OTHER, &normal) };
        assert_eq!(during, Some(9));
        assert_eq!(after, Some(10));
        assert_eq!(fifo_priority(), None);
    }

    #[test]
    fn a_pinned_command_runs_on_its_cpus_and_the_caller_keeps_its_own() {
        let before = affinity().expect("affinity");
        let mut cmd = std::process::Command::new("sh");
        cmd.args(["-c", "grep Cpus_allowed_list /proc/self/status"]);
        pin_command(&mut cmd, &[0]).expect("pin");
        let out = cmd.output().expect("run sh");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.trim().ends_with("\t0"), "{text}");
        assert_eq!(affinity().expect("affinity"), before);
    }

    #[test]
    fn the_calling_thread_may_run_on_some_online_cpu() {
        let cpus = affinity().expect("affinity");
        assert!(!cpus.is_empty());
        assert!(cpus.iter().all(|&c| c < max_cpus()));
    }
}
