//! Helpers for the crate's tests.

use std::time::{Duration, Instant};

/// The calling thread's kernel id, for [`wait_until_asleep`].
pub(crate) fn thread_id() -> i32 {
    // SAFETY: gettid takes no arguments and cannot fail.
    unsafe { libc::syscall(libc::SYS_gettid) as i32 }
}

/// Returns once thread `tid` of this process sleeps in the kernel (its
/// `/proc` state is `S`) or has ended. A test calls it to know that
/// another thread has reached a blocking wait, instead of sleeping for
/// long enough and hoping: it depends on no thread's speed. Panics only
/// if neither happens within a minute (the test's guard against hanging).
pub(crate) fn wait_until_asleep(tid: i32) {
    let path = format!("/proc/self/task/{tid}/stat");
    let guard = Instant::now() + Duration::from_secs(60);
    loop {
        let Ok(stat) = std::fs::read_to_string(&path) else {
            return; // the thread has ended
        };
        // "tid (comm) STATE ...": the name may hold spaces and parentheses.
        let state = stat
            .rsplit_once(')')
            .and_then(|(_, r)| r.split_whitespace().next());
        if matches!(state, Some("S") | None) || matches!(state, Some("Z" | "X")) {
            return;
        }
        assert!(Instant::now() < guard, "thread {tid} never blocked");
        std::thread::yield_now();
    }
}
