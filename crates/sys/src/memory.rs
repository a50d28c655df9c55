//! How much memory the machine can give a new run.

/// `MemAvailable` of /proc/meminfo in bytes: the kernel's estimate of the
/// memory a new workload can have without swapping. `None` where it cannot
/// be read (not Linux, or a kernel before 3.14).
pub fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_available(&text)
}

/// The `MemAvailable:` line of a /proc/meminfo text, in bytes.
fn parse_available(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mem_available_is_read_in_bytes_and_a_missing_line_is_none() {
        let text =
            "MemTotal:       24000000 kB\nMemFree:         1000 kB\nMemAvailable:   22000000 kB\n";
        assert_eq!(parse_available(text), Some(22_000_000 * 1024));
        assert_eq!(parse_available("MemTotal: 5 kB\n"), None);
        assert_eq!(parse_available("MemAvailable: lots kB\n"), None);
    }

    #[test]
    fn this_machine_reports_some_memory_available() {
        assert!(available_bytes().is_some_and(|b| b > 0));
    }
}
