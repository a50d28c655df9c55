//! How much memory a new run can have: what the machine has free, and the
//! limits this process lives under (its memory cgroup, v1 or v2, and its
//! address-space and data-segment rlimits), each with what is used of it
//! already.
//!
//! [`limits`] lists every one that is set; the smallest room among them is
//! what a run must fit in. A container's limit (docker `--memory`,
//! Kubernetes, Slurm, a Dask worker in any of these) is its memory cgroup:
//! past it the kernel kills the run, as it does past the machine's memory;
//! past an rlimit (`ulimit -v`, `ulimit -d`) an allocation fails and the
//! run aborts.

use std::path::{Path, PathBuf};

/// One bound on the memory a new run can have, and the room it leaves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Limit {
    /// Which bound.
    pub kind: LimitKind,
    /// Bytes the bound allows in all (for [`LimitKind::Available`]: the
    /// available memory itself).
    pub limit: u64,
    /// Bytes of it used already (0 for [`LimitKind::Available`]).
    pub used: u64,
}

/// Which bound a [`Limit`] is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LimitKind {
    /// The machine's available memory: `MemAvailable` of /proc/meminfo.
    /// Applies to every process of a run together.
    Available,
    /// A cgroup v1 memory controller's `memory.limit_in_bytes` of the
    /// cgroup folder `dir` (this process's cgroup or one of its ancestors),
    /// used: its `memory.usage_in_bytes`. Applies to every process of a run
    /// together (children stay in their parent's cgroup).
    CgroupV1 {
        /// The cgroup's folder.
        dir: PathBuf,
    },
    /// A cgroup v2 `memory.max` of the cgroup folder `dir` (this process's
    /// cgroup or one of its ancestors), used: its `memory.current`. Applies
    /// to every process of a run together.
    CgroupV2 {
        /// The cgroup's folder.
        dir: PathBuf,
    },
    /// `RLIMIT_AS` (`ulimit -v`), used: this process's mapped address space
    /// (`VmSize` of /proc/self/status). Applies to each process on its own
    /// (children inherit the limit, not the use).
    AddressSpace,
    /// `RLIMIT_DATA` (`ulimit -d`), used: this process's private writable
    /// mappings (`VmData` of /proc/self/status, what the kernel counts
    /// against the limit). Applies to each process on its own.
    Data,
}

impl LimitKind {
    /// True for a bound of each process on its own (the rlimits); false for
    /// one that every process of a run shares (the machine, a cgroup).
    pub fn per_process(&self) -> bool {
        matches!(self, LimitKind::AddressSpace | LimitKind::Data)
    }
}

impl Limit {
    /// Bytes left: the limit less what is used (never below 0).
    pub fn room(&self) -> u64 {
        self.limit.saturating_sub(self.used)
    }
}

/// `MemAvailable` of /proc/meminfo in bytes: the kernel's estimate of the
/// memory a new workload can have without swapping. `None` where it cannot
/// be read (not Linux, or a kernel before 3.14).
pub fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_available(&text)
}

/// Every bound set on a new run started by this process: the machine's
/// available memory, each memory cgroup limit from this process's cgroup
/// up to its hierarchy's root (v1 and v2, whichever are mounted), and the
/// address-space and data rlimits. Unset ones (`max`, unlimited) and those
/// that cannot be read are left out.
pub fn limits() -> Vec<Limit> {
    let mut out = Vec::new();
    if let Some(a) = available_bytes() {
        out.push(Limit {
            kind: LimitKind::Available,
            limit: a,
            used: 0,
        });
    }
    let cgroups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    let mounts = std::fs::read_to_string("/proc/self/mountinfo").unwrap_or_default();
    out.extend(cgroup_limits(&cgroups, &mounts, Path::new("/")));
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    for (resource, kind, field) in [
        (libc::RLIMIT_AS, LimitKind::AddressSpace, "VmSize:"),
        (libc::RLIMIT_DATA, LimitKind::Data, "VmData:"),
    ] {
        if let Some(limit) = rlimit(resource) {
            out.push(Limit {
                kind,
                limit,
                used: status_kb(&status, field).unwrap_or(0),
            });
        }
    }
    out
}

/// The smallest room among `limits` (the first of equals), if any.
pub fn tightest(limits: &[Limit]) -> Option<&Limit> {
    limits.iter().min_by_key(|l| l.room())
}

/// The soft limit of `resource`, `None` when unlimited or not readable.
fn rlimit(resource: libc::__rlimit_resource_t) -> Option<u64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: `r` is a valid, writable rlimit for the call to fill.
    let ok = unsafe { libc::getrlimit(resource, &mut r) } == 0;
    (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur)
}

/// A `NAME:   N kB` line of /proc/self/status, in bytes.
fn status_kb(text: &str, field: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// The memory cgroup limits of a process whose /proc/self/cgroup is
/// `cgroups` and /proc/self/mountinfo is `mounts`, with the file system
/// read under `root` (`/`; a test's folder in tests): for each mounted
/// hierarchy that has the process's cgroup (the v1 one with the `memory`
/// controller, the v2 one), every level from the cgroup up to the mount's
/// root whose limit is set.
fn cgroup_limits(cgroups: &str, mounts: &str, root: &Path) -> Vec<Limit> {
    let mut out = Vec::new();
    for m in parse_mounts(mounts) {
        let path = cgroups.lines().find_map(|l| {
            let mut f = l.splitn(3, ':');
            let (_, controllers, path) = (f.next()?, f.next()?, f.next()?);
            let wanted = if m.v2 {
                controllers.is_empty()
            } else {
                controllers.split(',').any(|c| c == "memory")
            };
            wanted.then_some(path)
        });
        let Some(path) = path else { continue };
        // The cgroup as seen from the mount: its path less the mount's root
        // (a container sees its own cgroup as the root).
        let Some(rel) = Path::new(path).strip_prefix(&m.root).ok() else {
            continue;
        };
        let (limit_file, used_file) = if m.v2 {
            ("memory.max", "memory.current")
        } else {
            ("memory.limit_in_bytes", "memory.usage_in_bytes")
        };
        let top = root.join(m.point.strip_prefix("/").unwrap_or(&m.point));
        let mut dir = top.join(rel);
        loop {
            let limit = read_number(&dir.join(limit_file));
            // v1 writes "no limit" as the largest page-aligned i64.
            let set = limit.filter(|&l| l < (i64::MAX as u64) & !0xfff);
            if let Some(limit) = set {
                out.push(Limit {
                    kind: if m.v2 {
                        LimitKind::CgroupV2 { dir: dir.clone() }
                    } else {
                        LimitKind::CgroupV1 { dir: dir.clone() }
                    },
                    limit,
                    used: read_number(&dir.join(used_file)).unwrap_or(0),
                });
            }
            if dir == top || !dir.pop() {
                break;
            }
        }
    }
    out
}

/// A file holding one number (`max` or anything else: `None`).
fn read_number(path: &Path) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

/// A mounted cgroup hierarchy that can hold a memory limit.
#[derive(Debug, PartialEq)]
struct Mount {
    /// The cgroup at the mount's root, as /proc/self/cgroup names it.
    root: PathBuf,
    /// Where it is mounted.
    point: PathBuf,
    /// cgroup2 (else v1 with the memory controller).
    v2: bool,
}

/// The v1 memory and the v2 mounts of a /proc/self/mountinfo text: fields
/// `id parent major:minor root point options [optional...] - type source
/// super-options`.
fn parse_mounts(text: &str) -> Vec<Mount> {
    text.lines()
        .filter_map(|line| {
            let (head, tail) = line.split_once(" - ")?;
            let mut h = head.split(' ');
            let root = h.nth(3)?;
            let point = h.next()?;
            let mut t = tail.split(' ');
            let fstype = t.next()?;
            let options = t.nth(1).unwrap_or("");
            let v2 = match fstype {
                "cgroup2" => true,
                "cgroup" if options.split(',').any(|o| o == "memory") => false,
                _ => return None,
            };
            Some(Mount {
                root: PathBuf::from(unescape(root)),
                point: PathBuf::from(unescape(point)),
                v2,
            })
        })
        .collect()
}

/// mountinfo's octal escapes (`\040` a space) undone.
fn unescape(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let oct = b
            .get(i + 1..i + 4)
            .filter(|d| b[i] == b'\\' && d.iter().all(|c| (b'0'..=b'7').contains(c)));
        match oct {
            Some(d) => {
                let v = d.iter().fold(0u32, |v, c| v * 8 + u32::from(c - b'0'));
                out.push(u8::try_from(v).unwrap_or(b'?'));
                i += 4;
            }
            None => {
                out.push(b[i]);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
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
        assert!(
            limits()
                .iter()
                .any(|l| l.kind == LimitKind::Available && l.room() > 0)
        );
    }

    /// A hybrid machine's mounts: v1 controllers, cgroup2 at `unified`.
    const HYBRID: &str = "\
31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755
32 31 0:29 / /sys/fs/cgroup/cpu rw,relatime - cgroup cgroup rw,cpu
35 31 0:32 / /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory
41 31 0:38 / /sys/fs/cgroup/unified rw,relatime shared:9 - cgroup2 cgroup2 rw
";

    fn write(path: &Path, text: &str) {
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("mkdir");
        std::fs::write(path, text).expect("write");
    }

    fn tree(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("mrsim-sys-cg-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn the_mounts_of_the_memory_controller_and_of_cgroup2_are_found_and_others_not() {
        let m = parse_mounts(HYBRID);
        assert_eq!(
            m,
            vec![
                Mount {
                    root: "/".into(),
                    point: "/sys/fs/cgroup/memory".into(),
                    v2: false
                },
                Mount {
                    root: "/".into(),
                    point: "/sys/fs/cgroup/unified".into(),
                    v2: true
                },
            ]
        );
        let spaced = "1 2 0:3 /a /mnt/my\\040cg rw - cgroup2 none rw\n";
        assert_eq!(parse_mounts(spaced)[0].point, PathBuf::from("/mnt/my cg"));
        assert!(parse_mounts("garbage\n\n1 2 3\n").is_empty());
    }

    #[test]
    fn a_v1_limit_and_its_parents_are_read_less_what_each_uses_and_no_limit_is_skipped() {
        let root = tree("v1");
        let cg = root.join("sys/fs/cgroup/memory");
        write(&cg.join("memory.limit_in_bytes"), "9223372036854771712\n");
        write(&cg.join("memory.usage_in_bytes"), "100\n");
        write(&cg.join("job/memory.limit_in_bytes"), "4294967296\n");
        write(&cg.join("job/memory.usage_in_bytes"), "1073741824\n");
        write(&cg.join("job/step/memory.limit_in_bytes"), "8589934592\n");
        write(&cg.join("job/step/memory.usage_in_bytes"), "1048576\n");
        let cgroups = "9:pids:/\n4:memory:/job/step\n0::/\n";
        let got = cgroup_limits(cgroups, HYBRID, &root);
        assert_eq!(
            got,
            vec![
                Limit {
                    kind: LimitKind::CgroupV1 {
                        dir: cg.join("job/step")
                    },
                    limit: 8 << 30,
                    used: 1 << 20
                },
                Limit {
                    kind: LimitKind::CgroupV1 {
                        dir: cg.join("job")
                    },
                    limit: 4 << 30,
                    used: 1 << 30
                },
            ]
        );
        assert_eq!(tightest(&got).map(Limit::room), Some(3 << 30));
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn a_v2_memory_max_is_read_from_the_cgroup_seen_from_its_mount_and_max_is_no_limit() {
        let root = tree("v2");
        // A container: its cgroup namespace's root is /kubepods/pod1.
        let mounts = "30 20 0:26 /kubepods/pod1 /sys/fs/cgroup rw - cgroup2 cgroup2 rw\n";
        let cg = root.join("sys/fs/cgroup");
        write(&cg.join("memory.max"), "max\n");
        write(&cg.join("app/memory.max"), "536870912\n");
        write(&cg.join("app/memory.current"), "12345\n");
        let got = cgroup_limits("0::/kubepods/pod1/app\n", mounts, &root);
        assert_eq!(
            got,
            vec![Limit {
                kind: LimitKind::CgroupV2 {
                    dir: cg.join("app")
                },
                limit: 512 << 20,
                used: 12345
            }]
        );
        // A cgroup outside the mount's root, or no line for it: nothing.
        assert!(cgroup_limits("0::/elsewhere\n", mounts, &root).is_empty());
        assert!(cgroup_limits("4:memory:/app\n", mounts, &root).is_empty());
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn a_used_share_past_the_limit_leaves_no_room_rather_than_wrapping() {
        let l = Limit {
            kind: LimitKind::Data,
            limit: 10,
            used: 20,
        };
        assert_eq!(l.room(), 0);
        assert!(l.kind.per_process() && !LimitKind::Available.per_process());
        assert_eq!(status_kb("VmSize:\t  2048 kB\n", "VmSize:"), Some(2 << 20));
    }
}
