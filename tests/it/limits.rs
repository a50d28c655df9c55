//! A run too big for the limits it lives under (a memory cgroup, v1 or v2,
//! as a container gives a job; an address-space rlimit, `ulimit -v`) is
//! refused before it starts, with exit status 2, naming the limit; a run
//! that fits them runs.
//!
//! The cgroup tests make their own cgroup (they need root) and move the
//! child `mrsim` into it before it executes; they are skipped where no
//! memory cgroup can be made, and fail instead when
//! `MRSIM_REQUIRE_CGROUP=1` (CI). A machine's memory controller is bound to
//! one hierarchy (v1 on a hybrid machine, v2 on a unified one), so the test
//! of the other one is always a skip: the one of the hierarchy that has it
//! is the one required.

use crate::common::{assert_ok, fresh_dir, mrsim, skip};
use std::ffi::CString;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Output;

/// 40,000 robots that sense only their neighbours, in-process: about
/// 0.8 GiB by the estimate (64 MB + 40,000 x 20 KB).
const CROWD: &str = "name = \"crowd\"
[world]
dt = 0.1
duration = 1.0
mode = \"lockstep\"
[defaults]
sensing_range = 1.0
[generate]
kind = \"random\"
count = 40000
radius = 2000.0
planner = \"homing\"
";

/// Ten robots: a few MB.
const FEW: &str = "name = \"few\"
[world]
dt = 0.1
duration = 0.5
mode = \"lockstep\"
[defaults]
sensing_range = 1.0
[generate]
kind = \"random\"
count = 10
radius = 20.0
planner = \"homing\"
";

/// Why a cgroup could not be made.
enum Cannot {
    /// The memory controller is on the other hierarchy: never required.
    OtherHierarchy(String),
    /// Anything else (not root, no memory controller at all).
    Here(String),
}

/// A memory cgroup made for one test, removed when dropped.
struct Cgroup {
    dir: PathBuf,
    /// `cgroup.procs` of it, for the child to write itself into.
    procs: CString,
}

/// The mount point and the root of the first mount in /proc/self/mountinfo
/// of file-system type `fstype` whose super options hold `option` (any:
/// `None`).
fn mount(fstype: &str, option: Option<&str>) -> Option<(PathBuf, PathBuf)> {
    let text = std::fs::read_to_string("/proc/self/mountinfo").ok()?;
    text.lines().find_map(|line| {
        let (head, tail) = line.split_once(" - ")?;
        let mut h = head.split(' ');
        let root = h.nth(3)?;
        let point = h.next()?;
        let mut t = tail.split(' ');
        let ok = t.next()? == fstype
            && option.is_none_or(|o| t.nth(1).is_some_and(|s| s.split(',').any(|x| x == o)));
        ok.then(|| (PathBuf::from(point), PathBuf::from(root)))
    })
}

/// This process's cgroup folder under `point` (mounted with root `root`)
/// for the /proc/self/cgroup line whose controllers satisfy `wanted`.
fn own_cgroup(point: &Path, root: &Path, wanted: impl Fn(&str) -> bool) -> Option<PathBuf> {
    let text = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = text.lines().find_map(|l| {
        let mut f = l.splitn(3, ':');
        let (_, c, p) = (f.next()?, f.next()?, f.next()?);
        wanted(c).then(|| p.to_string())
    })?;
    let rel = Path::new(&path).strip_prefix(root).ok()?;
    Some(point.join(rel))
}

/// The memory controller is enabled on the cgroup2 mount.
fn v2_has_memory() -> bool {
    mount("cgroup2", None).is_some_and(|(p, _)| {
        std::fs::read_to_string(p.join("cgroup.controllers"))
            .is_ok_and(|c| c.split_whitespace().any(|x| x == "memory"))
    })
}

fn fresh_name() -> String {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    format!(
        "mrsim-test-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    )
}

impl Cgroup {
    /// A cgroup v1 memory cgroup under this process's, limited to `limit`
    /// bytes.
    fn v1(limit: u64) -> Result<Cgroup, Cannot> {
        let Some((point, root)) = mount("cgroup", Some("memory")) else {
            let why = "no cgroup v1 memory hierarchy is mounted".to_string();
            return Err(if v2_has_memory() {
                Cannot::OtherHierarchy(format!("{why} (the memory controller is on cgroup2)"))
            } else {
                Cannot::Here(why)
            });
        };
        let own = own_cgroup(&point, &root, |c| c.split(',').any(|x| x == "memory"))
            .ok_or_else(|| Cannot::Here("this process has no v1 memory cgroup".into()))?;
        Cgroup::make(own.join(fresh_name()), "memory.limit_in_bytes", limit)
    }

    /// A cgroup v2 cgroup with `memory.max` = `limit`: a child of this
    /// process's cgroup where that one delegates the memory controller, a
    /// sibling where only its parent does (a cgroup with processes cannot
    /// delegate), a child of the root otherwise (which may).
    fn v2(limit: u64) -> Result<Cgroup, Cannot> {
        let Some((point, root)) = mount("cgroup2", None) else {
            return Err(Cannot::Here("no cgroup2 hierarchy is mounted".into()));
        };
        if !v2_has_memory() {
            let why = format!(
                "the cgroup2 hierarchy at {} has no memory controller",
                point.display()
            );
            return Err(if mount("cgroup", Some("memory")).is_some() {
                Cannot::OtherHierarchy(format!("{why} (it is bound to cgroup v1 here)"))
            } else {
                Cannot::Here(why)
            });
        }
        let own = own_cgroup(&point, &root, str::is_empty)
            .ok_or_else(|| Cannot::Here("this process has no cgroup2 cgroup".into()))?;
        let delegates = |d: &Path| {
            std::fs::read_to_string(d.join("cgroup.subtree_control"))
                .is_ok_and(|c| c.split_whitespace().any(|x| x == "memory"))
        };
        let parent = if delegates(&own) {
            own
        } else if own.parent().is_some_and(delegates) && own != point {
            own.parent().map(Path::to_path_buf).unwrap_or(point.clone())
        } else {
            std::fs::write(point.join("cgroup.subtree_control"), "+memory").map_err(|e| {
                Cannot::Here(format!(
                    "cannot delegate the memory controller at {}: {e}",
                    point.display()
                ))
            })?;
            point
        };
        Cgroup::make(parent.join(fresh_name()), "memory.max", limit)
    }

    fn make(dir: PathBuf, limit_file: &str, limit: u64) -> Result<Cgroup, Cannot> {
        std::fs::create_dir(&dir)
            .map_err(|e| Cannot::Here(format!("cannot make {}: {e}", dir.display())))?;
        let cg = Cgroup {
            procs: CString::new(dir.join("cgroup.procs").as_os_str().as_encoded_bytes())
                .map_err(|e| Cannot::Here(e.to_string()))?,
            dir,
        };
        std::fs::write(cg.dir.join(limit_file), limit.to_string()).map_err(|e| {
            Cannot::Here(format!(
                "cannot set {limit_file} of {}: {e}",
                cg.dir.display()
            ))
        })?;
        Ok(cg)
    }

    /// `mrsim ARGS` run inside the cgroup: the child writes itself into
    /// `cgroup.procs` between fork and exec.
    fn run(&self, args: &[&std::ffi::OsStr]) -> Output {
        let procs = self.procs.clone();
        let mut cmd = mrsim();
        cmd.args(args);
        // SAFETY: between fork and exec only async-signal-safe calls
        // (open, write, close) on memory made before the fork.
        unsafe {
            cmd.pre_exec(move || {
                let fd = libc::open(procs.as_ptr(), libc::O_WRONLY | libc::O_CLOEXEC);
                if fd < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                let n = libc::write(fd, b"0".as_ptr().cast(), 1);
                let e = std::io::Error::last_os_error();
                libc::close(fd);
                if n != 1 {
                    return Err(e);
                }
                Ok(())
            });
        }
        cmd.output().expect("start mrsim in the cgroup")
    }
}

impl Drop for Cgroup {
    fn drop(&mut self) {
        // Empty once its one child has been waited for; the kernel may
        // take a moment to let go of it.
        for _ in 0..50 {
            if std::fs::remove_dir(&self.dir).is_ok() || !self.dir.exists() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }
}

/// A cgroup of the `version`, or the test's skip recorded (`None`).
fn cgroup_or_skip(test: &str, version: u8, limit: u64) -> Option<Cgroup> {
    let made = if version == 1 {
        Cgroup::v1(limit)
    } else {
        Cgroup::v2(limit)
    };
    match made {
        Ok(cg) => Some(cg),
        Err(Cannot::OtherHierarchy(why)) => {
            // Never required: the other hierarchy's test runs instead.
            skip(test, "MRSIM_NEVER_REQUIRED", &why);
            None
        }
        Err(Cannot::Here(why)) => {
            skip(test, "MRSIM_REQUIRE_CGROUP", &why);
            None
        }
    }
}

/// `mrsim run FILE --out DIR/out --transport inproc --quiet` as arguments.
fn run_args(file: &Path, out: &Path) -> Vec<std::ffi::OsString> {
    let mut a: Vec<std::ffi::OsString> = vec!["run".into(), file.into(), "--out".into()];
    a.push(out.into());
    a.extend(["--transport", "inproc", "--quiet"].map(Into::into));
    a
}

fn refused_by_cgroup(test: &str, version: u8, limit_file: &str) {
    let Some(cg) = cgroup_or_skip(test, version, 256 << 20) else {
        return;
    };
    let dir = fresh_dir(&format!("cgroup-v{version}"));
    let file = dir.join("crowd.toml");
    std::fs::write(&file, CROWD).expect("write");
    let out = dir.join("out");
    let args = run_args(&file, &out);
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let o = cg.run(&refs);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    for words in [
        "crowd.toml: this run needs about 0.8 GiB of memory (40000 robots x 20 KB",
        "its memory cgroup leaves",
        &format!(
            "cgroup v{version} {limit_file} 0.2 GiB of {}",
            cg.dir.display()
        ),
        "the kernel would kill it part-way",
        "To make it fit: run fewer robots",
        "docker --memory",
    ] {
        assert!(stderr.contains(words), "`{words}` in: {stderr}");
    }
    assert!(!out.join("metrics.json").exists(), "nothing ran");
    // A run that fits the same cgroup runs.
    let few = dir.join("few.toml");
    std::fs::write(&few, FEW).expect("write");
    let args = run_args(&few, &dir.join("few"));
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let o = cg.run(&refs);
    assert_ok(&o);
    assert!(dir.join("few/metrics.json").exists());
}

#[test]
fn a_run_bigger_than_its_cgroup_v1_memory_limit_is_refused_naming_the_limit() {
    refused_by_cgroup(
        "a_run_bigger_than_its_cgroup_v1_memory_limit_is_refused_naming_the_limit",
        1,
        "memory.limit_in_bytes",
    );
}

#[test]
fn a_run_bigger_than_its_cgroup_v2_memory_max_is_refused_naming_the_limit() {
    refused_by_cgroup(
        "a_run_bigger_than_its_cgroup_v2_memory_max_is_refused_naming_the_limit",
        2,
        "memory.max",
    );
}

/// `mrsim ARGS` under an address-space limit of `bytes`.
fn under_rlimit_as(args: &[std::ffi::OsString], bytes: u64) -> Output {
    let mut cmd = mrsim();
    cmd.args(args);
    // SAFETY: setrlimit is async-signal-safe; its argument is on the stack.
    unsafe {
        cmd.pre_exec(move || {
            let r = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &r) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.output().expect("start mrsim under RLIMIT_AS")
}

#[test]
fn a_run_bigger_than_its_address_space_limit_is_refused_naming_rlimit_as() {
    let dir = fresh_dir("rlimit-as");
    let file = dir.join("crowd.toml");
    // 100,000 robots: about 2 GiB by the estimate, under a 1 GiB limit.
    std::fs::write(&file, CROWD.replace("40000", "100000")).expect("write");
    let out = dir.join("out");
    let o = under_rlimit_as(&run_args(&file, &out), 1 << 30);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    for words in [
        "crowd.toml: this run needs about 2.0 GiB of memory (100000 robots x 20 KB",
        "its address-space limit leaves (RLIMIT_AS, `ulimit -v`: 1.0 GiB, less",
        "an allocation past it would fail",
        "To make it fit: run fewer robots",
        "ulimit -v unlimited",
    ] {
        assert!(stderr.contains(words), "`{words}` in: {stderr}");
    }
    assert!(!out.join("metrics.json").exists(), "nothing ran");
    // A run that fits the same limit runs.
    let few = dir.join("few.toml");
    std::fs::write(&few, FEW).expect("write");
    let o = under_rlimit_as(&run_args(&few, &dir.join("few")), 1 << 30);
    assert_ok(&o);
}

#[test]
fn a_sweep_whose_runs_at_once_exceed_its_cgroup_is_refused_naming_how_many_fit() {
    let test = "a_sweep_whose_runs_at_once_exceed_its_cgroup_is_refused_naming_how_many_fit";
    // Whichever hierarchy holds the memory controller here.
    let made = match Cgroup::v1(768 << 20) {
        Ok(cg) => Ok(cg),
        Err(_) => Cgroup::v2(768 << 20),
    };
    let cg = match made {
        Ok(cg) => cg,
        Err(Cannot::OtherHierarchy(why) | Cannot::Here(why)) => {
            skip(test, "MRSIM_REQUIRE_CGROUP", &why);
            return;
        }
    };
    let dir = fresh_dir("sweep-limit");
    let file = dir.join("crowd.toml");
    // 10,000 robots over shared memory in groups of 1,000: about 0.3 GiB a
    // run (64 MB + 10,000 x 20 KB + 10 x 4 MB), four at once 1.2 GiB, two
    // 0.6 GiB, under a 0.75 GiB cgroup.
    let text = CROWD
        .replace("40000", "10000")
        .replace("[world]\n", "[world]\nrobots_per_agent = 1000\n");
    std::fs::write(&file, text).expect("write");
    let mut args: Vec<std::ffi::OsString> = vec!["sweep".into(), file.into()];
    args.extend(
        [
            "--set",
            "robot.*.max_speed=0.5,1.5",
            "--seeds",
            "2",
            "--jobs",
            "4",
            "--out",
        ]
        .map(Into::into),
    );
    args.push(dir.join("sweep").into());
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let o = cg.run(&refs);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    for words in [
        "crowd.toml: 4 runs at once need about 1.2 GiB of memory (the largest run: 10000 \
         robots x 20 KB, 10 agent processes x 4 MB, plus 64 MB)",
        "its memory cgroup leaves",
        "To make it fit: run 2 at once (--jobs 2)",
    ] {
        assert!(stderr.contains(words), "`{words}` in: {stderr}");
    }
    assert!(!dir.join("sweep/runs").exists(), "nothing ran");
}
