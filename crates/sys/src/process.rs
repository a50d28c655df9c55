//! Processes on this machine: does one exist, is it alive, when did it
//! start (to tell a process from a later one that reuses its pid).

/// True if process `pid` exists (same machine), zombie or not: one
/// syscall.
pub fn pid_exists(pid: u32) -> bool {
    if pid == 0 {
        return false;
    }
    // SAFETY: kill with signal 0 only checks for existence and permission.
    let r = unsafe { libc::kill(pid as libc::pid_t, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

/// True if process `pid` exists and is not a zombie (same machine).
pub fn pid_alive(pid: u32) -> bool {
    if !pid_exists(pid) {
        return false;
    }
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(stat) => stat
            .rsplit_once(") ")
            .and_then(|(_, rest)| rest.chars().next())
            .is_none_or(|state| state != 'Z' && state != 'X'),
        Err(_) => false,
    }
}

/// When process `pid` started: field 22 of /proc/PID/stat (clock ticks
/// since boot). `None` if it cannot be read.
pub fn start_time(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces), from field 3.
    let (_, rest) = stat.rsplit_once(") ")?;
    rest.split_whitespace().nth(22 - 3)?.parse().ok()
}

/// Sends signal `sig` to process `pid`; false if it could not be sent.
pub fn kill(pid: u32, sig: i32) -> bool {
    if pid == 0 || pid > i32::MAX as u32 {
        return false;
    }
    // SAFETY: sending a signal to a process; no memory is involved.
    unsafe { libc::kill(pid as libc::pid_t, sig) == 0 }
}

/// True if a child of this process has ended and not been reaped yet (it
/// is left to be reaped): one system call, where asking each child is one
/// each. True also if the question cannot be asked, so that a caller then
/// asks each child.
pub fn a_child_ended() -> bool {
    // SAFETY: a zeroed siginfo_t is a valid output buffer for waitid.
    let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
    // SAFETY: waitid writes only into `info`; WNOWAIT leaves the child to
    // be reaped by whoever waits for it.
    let r = unsafe {
        libc::waitid(
            libc::P_ALL,
            0,
            &mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        )
    };
    if r != 0 {
        // No children at all, or the call failed: nothing is known.
        return std::io::Error::last_os_error().raw_os_error() != Some(libc::ECHILD);
    }
    // SAFETY: filled by a successful waitid (0 when no child has ended).
    unsafe { info.si_pid() != 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Held by the tests that start children: `a_child_ended` asks about
    /// every child of the test process.
    static CHILDREN: std::sync::Mutex<()> = std::sync::Mutex::new(());

    #[test]
    fn a_child_that_ended_is_seen_and_left_to_be_reaped() {
        let _one_at_a_time = CHILDREN.lock().unwrap_or_else(|e| e.into_inner());
        let mut child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .expect("spawn sleep");
        assert!(!a_child_ended(), "a running child has not ended");
        assert!(kill(child.id(), libc::SIGKILL));
        let start = std::time::Instant::now();
        while !a_child_ended() {
            assert!(
                start.elapsed() < std::time::Duration::from_secs(20),
                "the killed child was never seen"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        // Left to be reaped: its own wait still sees how it ended.
        let status = child.wait().expect("wait");
        assert!(!status.success());
        assert!(!a_child_ended(), "once reaped, nothing has ended");
    }

    #[test]
    fn this_process_is_alive_and_has_a_start_time() {
        let me = std::process::id();
        assert!(pid_exists(me));
        assert!(pid_alive(me));
        assert!(start_time(me).is_some());
    }

    #[test]
    fn pid_zero_names_no_process() {
        assert!(!pid_exists(0));
        assert!(!pid_alive(0));
    }

    #[test]
    fn an_ended_child_is_not_alive() {
        let _one_at_a_time = CHILDREN.lock().unwrap_or_else(|e| e.into_inner());
        let mut child = std::process::Command::new("true")
            .spawn()
            .expect("spawn true");
        let pid = child.id();
        child.wait().expect("wait");
        assert!(!pid_alive(pid), "a reaped child is gone");
    }
}
