//! CPU work on the calling thread's own CPU clock.
//!
//! A planner call whose drawn compute time is C ms of CPU work ends when
//! the thread has *used* C ms of CPU since the call began, not when C ms of
//! wall time have passed: a thread that is preempted (by another agent on
//! the same core, by the world, by a throttled reservation) burns no CPU
//! while it waits, so its call's wall time stretches exactly as a real
//! planner's would. This is what LITMUS^RT's `rtspin` does: spin on the
//! thread's CPU clock (`CLOCK_THREAD_CPUTIME_ID`) and stop before the
//! iteration that would overshoot, predicting its length from the one
//! before.

/// The calling thread's CPU time so far, in nanoseconds
/// (`CLOCK_THREAD_CPUTIME_ID`); 0 if the clock cannot be read (it always
/// can on Linux).
pub fn thread_cpu_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: the timespec lives for the call, which only writes into it.
    let r = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if r != 0 {
        return 0;
    }
    (ts.tv_sec as u64)
        .saturating_mul(1_000_000_000)
        .saturating_add(ts.tv_nsec as u64)
}

/// Work between two readings of the clock: about a microsecond on a
/// current core, short against the millisecond calls it makes up, long
/// against the clock's own cost (one system call).
const CHUNK: u32 = 512;

/// One chunk of work the compiler cannot remove.
fn chunk(mut x: u64) -> u64 {
    for _ in 0..CHUNK {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        x = std::hint::black_box(x);
    }
    x
}

/// Burns CPU on the calling thread until it has used `total_ns` of CPU
/// since its CPU clock read `start_ns` (a [`thread_cpu_ns`] taken when the
/// call began, so the CPU the planner itself used counts). Returns the CPU
/// the thread has used since `start_ns` when it stops.
///
/// As `rtspin`, it stops before an iteration that would overshoot, taking
/// the next iteration to be as long as the last: the result falls short
/// of `total_ns` by less than one iteration (about a microsecond), never
/// beyond it by more than the clock's reading. Nothing is burned when the
/// thread already used `total_ns`.
pub fn burn_until(start_ns: u64, total_ns: u64) -> u64 {
    let end = start_ns.saturating_add(total_ns);
    let mut now = thread_cpu_ns();
    let mut last_iteration = 0u64;
    let mut x = now;
    while now.saturating_add(last_iteration) < end {
        x = chunk(x);
        let before = now;
        now = thread_cpu_ns();
        last_iteration = now.saturating_sub(before);
    }
    std::hint::black_box(x);
    now.saturating_sub(start_ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thread_clock_advances_only_with_work() {
        let a = thread_cpu_ns();
        std::thread::sleep(std::time::Duration::from_millis(20));
        let b = thread_cpu_ns();
        // A sleeping thread uses (next to) no CPU: far below the 20 ms slept.
        assert!(b >= a);
        assert!(b - a < 5_000_000, "slept 20 ms, used {} ns", b - a);
    }

    #[test]
    fn a_burn_uses_the_cpu_asked_for_counting_what_was_used_before() {
        let start = thread_cpu_ns();
        // Some CPU used "by the planner" first.
        let used_before = burn_until(start, 2_000_000);
        assert!(used_before <= 2_000_000 + 200_000, "{used_before}");
        let used = burn_until(start, 10_000_000);
        // Within one iteration short of the total (generous: the iteration
        // is about a microsecond, a preemption between the last two
        // readings can make one longer), never far beyond it.
        assert!(used >= 10_000_000 - 1_000_000, "used {used} ns of 10 ms");
        assert!(used <= 10_000_000 + 1_000_000, "used {used} ns of 10 ms");
        let after = thread_cpu_ns() - start;
        assert!(after >= used);
    }

    #[test]
    fn a_call_that_already_used_its_time_burns_nothing_more() {
        let start = thread_cpu_ns();
        burn_until(start, 3_000_000);
        let before = thread_cpu_ns();
        let used = burn_until(start, 1_000_000);
        assert!(used >= 3_000_000 - 1_000_000);
        // Only the clock reading itself.
        assert!(thread_cpu_ns() - before < 500_000);
    }
}
