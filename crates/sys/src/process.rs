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

#[cfg(test)]
mod tests {
    use super::*;

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
        let mut child = std::process::Command::new("true")
            .spawn()
            .expect("spawn true");
        let pid = child.id();
        child.wait().expect("wait");
        assert!(!pid_alive(pid), "a reaped child is gone");
    }
}
