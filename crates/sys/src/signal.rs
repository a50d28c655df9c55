//! Termination signals: a flag that SIGINT and SIGTERM set, and the names
//! of the signals a child can die of.

use std::sync::atomic::{AtomicI32, Ordering};

/// SIGINT.
pub const SIGINT: i32 = libc::SIGINT;
/// SIGTERM.
pub const SIGTERM: i32 = libc::SIGTERM;
/// SIGKILL.
pub const SIGKILL: i32 = libc::SIGKILL;
/// SIGSTOP.
pub const SIGSTOP: i32 = libc::SIGSTOP;

static SIGNALLED: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_signal(sig: libc::c_int) {
    SIGNALLED.store(sig, Ordering::SeqCst);
}

/// From now on SIGINT and SIGTERM do not end the process: they set the
/// flag [`received`] reads, so the caller can stop its children and keep
/// what they recorded.
pub fn catch_termination() {
    // SAFETY: the handler only stores into an atomic, which is
    // async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
}

/// The termination signal received since [`catch_termination`], if any.
pub fn received() -> Option<i32> {
    match SIGNALLED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// A signal's name, for messages about a child that died of it.
pub fn name(sig: i32) -> &'static str {
    match sig {
        libc::SIGKILL => "SIGKILL",
        libc::SIGTERM => "SIGTERM",
        libc::SIGINT => "SIGINT",
        libc::SIGSEGV => "SIGSEGV",
        libc::SIGABRT => "SIGABRT",
        libc::SIGBUS => "SIGBUS",
        libc::SIGFPE => "SIGFPE",
        libc::SIGILL => "SIGILL",
        libc::SIGHUP => "SIGHUP",
        libc::SIGPIPE => "SIGPIPE",
        _ => "see `kill -l`",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn common_signals_have_their_names() {
        assert_eq!(name(SIGKILL), "SIGKILL");
        assert_eq!(name(SIGTERM), "SIGTERM");
        assert_eq!(name(1000), "see `kill -l`");
    }
}
