//! CPU time and peak memory (getrusage), and the time stolen from this
//! machine's CPUs by its hypervisor (/proc/stat).

/// Whose counters: the whole process or the calling thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// The whole process.
    Process,
    /// The calling thread (its CPU time; the peak memory is the process's).
    Thread,
}

/// CPU seconds (user + system) and the process's peak resident set size
/// (KiB) now: the same counters as /proc/PID/stat's utime + stime and
/// /proc/PID/status's VmHWM. `(0.0, 0)` if getrusage fails.
pub fn rusage(scope: Scope) -> (f64, u64) {
    let who = match scope {
        Scope::Process => libc::RUSAGE_SELF,
        Scope::Thread => libc::RUSAGE_THREAD,
    };
    // SAFETY: getrusage writes into the struct we own.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(who, &mut ru) } != 0 {
        return (0.0, 0);
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    (
        secs(ru.ru_utime) + secs(ru.ru_stime),
        ru.ru_maxrss.max(0) as u64,
    )
}

/// CPU seconds and peak RSS (KiB) of this process so far.
pub fn process_usage() -> (f64, u64) {
    rusage(Scope::Process)
}

/// CPU seconds of the calling thread so far, and the process's peak RSS
/// (KiB).
pub fn thread_usage() -> (f64, u64) {
    rusage(Scope::Thread)
}

/// Stolen time of a set of CPUs so far, from /proc/stat. (Its busy
/// columns are not here: they are sampled at the timer tick, and counted
/// a third less than getrusage for agents that run in short bursts at
/// 100 Hz, too coarse to tell what else ran.)
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CpusTime {
    /// steal, s.
    pub steal_s: f64,
}

impl CpusTime {
    /// The CPUs this thread may run on (its affinity), now; `None` if
    /// /proc/stat or the affinity cannot be read.
    pub fn now() -> Option<Self> {
        let allowed = crate::sched::affinity()?;
        // SAFETY: sysconf has no preconditions.
        let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        Self::parse(
            &stat,
            |cpu| allowed.contains(&cpu),
            if hz > 0 { hz as f64 } else { 100.0 },
        )
    }

    /// Sums the `cpuN` lines of a /proc/stat text for which `allowed(N)`.
    pub fn parse(stat: &str, allowed: impl Fn(usize) -> bool, hz: f64) -> Option<Self> {
        let mut t = Self::default();
        let mut any = false;
        for line in stat.lines() {
            let mut f = line.split_ascii_whitespace();
            let Some(cpu) = f.next().and_then(|n| n.strip_prefix("cpu")) else {
                continue;
            };
            let Ok(cpu) = cpu.parse::<usize>() else {
                continue; // the "cpu" total line
            };
            if !allowed(cpu) {
                continue;
            }
            // user nice system idle iowait irq softirq steal ...
            let steal: u64 = f.nth(7).and_then(|x| x.parse().ok()).unwrap_or(0);
            t.steal_s += steal as f64 / hz;
            any = true;
        }
        any.then_some(t)
    }

    /// What was spent since `earlier`.
    pub fn since(self, earlier: Self) -> Self {
        Self {
            steal_s: (self.steal_s - earlier.steal_s).max(0.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stolen_time_sums_only_the_allowed_cpus() {
        let stat = "cpu  900 9 900 9000 90 9 9 90 0 0\n\
                    cpu0 100 2 30 5000 40 4 6 7 0 0\n\
                    cpu1 200 0 50 4000 50 5 3 83 0 0\n\
                    cpu2 600 7 820 0 0 0 0 0 0 0\n\
                    intr 12345\n";
        // cpu0 7 + cpu1 83 jiffies; not cpu2, not the total line.
        let t = CpusTime::parse(stat, |c| c < 2, 100.0).expect("two cpus");
        assert!((t.steal_s - 0.90).abs() < 1e-9, "{t:?}");
        assert_eq!(CpusTime::parse(stat, |c| c == 9, 100.0), None);
        let later = CpusTime { steal_s: 1.0 };
        assert!((later.since(t).steal_s - 0.1).abs() < 1e-9);
        assert_eq!(t.since(later).steal_s, 0.0);
    }

    #[test]
    fn burning_cpu_raises_the_thread_s_cpu_time() {
        let (a, _) = thread_usage();
        let mut x = 0u64;
        let mut i = 0u64;
        while thread_usage().0 <= a {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
            i += 1;
        }
        assert!(thread_usage().0 > a, "{x}");
        assert!(process_usage().1 > 0, "a process has a resident set");
    }
}
