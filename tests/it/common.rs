//! Helpers for the end-to-end tests: run the real `mrsim` binary in fresh
//! folders, read its outputs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The binary under test.
pub fn mrsim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mrsim"))
}

/// A fresh, empty folder for one test.
pub fn fresh_dir(tag: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "mrsim-test-{}-{}-{}",
        tag,
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create test dir");
    d
}

/// The repository root (for scenario files).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `mrsim run SCENARIO --out DIR --run ID [extra]` and returns its output.
pub fn run(scenario: &Path, out: &Path, run_id: &str, extra: &[&str]) -> Output {
    mrsim()
        .arg("run")
        .arg(scenario)
        .arg("--out")
        .arg(out)
        .args(["--run", run_id])
        .args(extra)
        .output()
        .expect("start mrsim")
}

/// Asserts a successful exit, showing stderr otherwise.
pub fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "mrsim failed: {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// metrics.json of a run folder.
pub fn metrics(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("metrics.json")).expect("metrics.json");
    serde_json::from_str(&text).expect("metrics.json parses")
}

/// events.jsonl of a run folder.
pub fn events(dir: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("events.jsonl"))
        .expect("events.jsonl")
        .lines()
        .map(|l| serde_json::from_str(l).expect("event line parses"))
        .collect()
}

/// One trajectory row.
#[derive(Debug, Clone)]
pub struct Row {
    pub tick: u64,
    pub time: f64,
    pub body: String,
    pub kind: String,
    pub x: f64,
    pub y: f64,
    pub vx: f64,
    pub vy: f64,
}

/// trajectory.csv of a run folder.
pub fn trajectory(dir: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(dir.join("trajectory.csv")).expect("trajectory.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("tick,time,body,kind,x,y,vx,vy"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 8, "bad row {l}");
            let n = |i: usize| f[i].parse::<f64>().expect("number");
            Row {
                tick: f[0].parse().expect("tick"),
                time: n(1),
                body: f[2].to_string(),
                kind: f[3].to_string(),
                x: n(4),
                y: n(5),
                vx: n(6),
                vy: n(7),
            }
        })
        .collect()
}

/// The rows of one body, in tick order.
pub fn track<'a>(rows: &'a [Row], body: &str) -> Vec<&'a Row> {
    rows.iter().filter(|r| r.body == body).collect()
}

/// Entries this run left in /dev/shm (its iceoryx2 prefix).
pub fn shm_leftovers(run_id: &str) -> Vec<String> {
    let prefix = format!("mrsim_{run_id}_");
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default()
}

/// Asserts the run left nothing behind: no shared memory, no root path.
pub fn assert_clean(run_id: &str) {
    assert!(
        shm_leftovers(run_id).is_empty(),
        "left in /dev/shm: {:?}",
        shm_leftovers(run_id)
    );
    let root = PathBuf::from(format!("/tmp/mrsim/{run_id}"));
    assert!(!root.exists(), "root path {} left behind", root.display());
}

/// A unique run id for a test.
pub fn run_id(tag: &str) -> String {
    static N: AtomicUsize = AtomicUsize::new(0);
    // A run id is at most 24 characters: `t`, the tag's first 12, and up
    // to 11 for the process id and the count, whatever the process id is
    // (the two alone make it unique).
    let tag: String = tag.chars().take(12).collect();
    format!(
        "t{}-{}-{}",
        tag.trim_end_matches('-'),
        std::process::id() % 100000,
        N.fetch_add(1, Ordering::SeqCst)
    )
}

/// Waits up to `secs` for `child`; kills it if it is still running then.
/// Returns its status (None if it could not be waited for).
pub fn wait_timeout(
    child: &mut std::process::Child,
    secs: u64,
) -> Option<std::process::ExitStatus> {
    let start = std::time::Instant::now();
    while start.elapsed() < std::time::Duration::from_secs(secs) {
        if let Ok(Some(s)) = child.try_wait() {
            return Some(s);
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let _ = child.kill();
    child.wait().ok()
}

/// Sends signal `sig` to process `pid`.
pub fn send_signal(pid: u32, sig: i32) {
    // SAFETY: kill(2) on a process this test started.
    let r = unsafe { libc::kill(pid as libc::pid_t, sig) };
    assert_eq!(r, 0, "kill({pid}, {sig}) failed");
}

/// The state letter of process `pid` from /proc (R, S, T, Z, ...), None if
/// it does not exist.
pub fn process_state(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit_once(") ")?.1.chars().next()
}

/// True once process `pid` is gone (or only a zombie).
pub fn process_gone(pid: u32) -> bool {
    matches!(process_state(pid), None | Some('Z') | Some('X'))
}

/// The live `mrsim` processes whose command line contains `args` in a row.
pub fn find_processes(args: &[&str]) -> Vec<u32> {
    let mut found = Vec::new();
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return found;
    };
    for e in dir.flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(cmd) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
            continue;
        };
        let parts: Vec<String> = cmd
            .split(|b| *b == 0)
            .map(|p| String::from_utf8_lossy(p).into_owned())
            .collect();
        let is_mrsim = parts.first().is_some_and(|p| p.ends_with("mrsim"));
        let has = parts
            .windows(args.len())
            .any(|w| w.iter().zip(args).all(|(a, b)| a == b));
        if is_mrsim && has && !process_gone(pid) {
            found.push(pid);
        }
    }
    found
}

/// Waits up to `secs` for exactly one live `mrsim` process with `args`
/// (other than those in `except`) and returns its pid.
pub fn wait_for_process(args: &[&str], except: &[u32], secs: u64) -> u32 {
    let start = std::time::Instant::now();
    loop {
        let found: Vec<u32> = find_processes(args)
            .into_iter()
            .filter(|p| !except.contains(p))
            .collect();
        if let [pid] = found[..] {
            return pid;
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(secs),
            "no single process with {args:?} after {secs} s (found {found:?})"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Removes what a run left in /dev/shm and its root path (after a test
/// killed its world on purpose).
pub fn remove_leftovers(run_id: &str) {
    for name in shm_leftovers(run_id) {
        let _ = std::fs::remove_file(Path::new("/dev/shm").join(name));
    }
    let _ = std::fs::remove_dir_all(format!("/tmp/mrsim/{run_id}"));
}

/// The length of (x, y).
pub fn norm(x: f64, y: f64) -> f64 {
    x.hypot(y)
}

/// Ko & Choi cases 1-3: where the robot first crosses the obstacle's line
/// (its offset along the obstacle's motion from the obstacle's centre, > 0
/// in front of it), the reversals of its along-track velocity before that,
/// and the smallest centre distance minus the obstacle's radius over the run.
pub struct Crossing {
    pub offset: f64,
    pub reversals: usize,
    pub min_gap: f64,
}

pub fn ko_choi_crossing(dir: &Path) -> Crossing {
    let rows = trajectory(dir);
    let (robot, obstacle) = (track(&rows, "robot"), track(&rows, "obstacle"));
    assert_eq!(robot.len(), obstacle.len());
    let o = obstacle[0];
    let d = {
        let n = norm(o.vx, o.vy);
        (o.vx / n, o.vy / n)
    };
    let n = (-d.1, d.0);
    let track_dir = (80.0 / norm(80.0, -42.0), -42.0 / norm(80.0, -42.0));
    let mut offset = f64::NAN;
    let mut reversals = 0;
    let mut min_gap = f64::INFINITY;
    let (mut side_prev, mut along_prev) = (f64::NAN, 0.0);
    for (r, o) in robot.iter().zip(&obstacle) {
        assert_eq!(r.tick, o.tick);
        let rel = (r.x - o.x, r.y - o.y);
        min_gap = min_gap.min(norm(rel.0, rel.1) - 5.0);
        if offset.is_nan() {
            let side = rel.0 * n.0 + rel.1 * n.1;
            if side_prev.is_finite() && side * side_prev < 0.0 {
                offset = rel.0 * d.0 + rel.1 * d.1;
            } else {
                let along = r.vx * track_dir.0 + r.vy * track_dir.1;
                if along != 0.0 {
                    if along * along_prev < 0.0 {
                        reversals += 1;
                    }
                    along_prev = along;
                }
            }
            side_prev = side;
        }
    }
    assert!(
        offset.is_finite(),
        "the robot never crossed the obstacle's line"
    );
    Crossing {
        offset,
        reversals,
        min_gap,
    }
}

/// Two social-force robots side by side, 4 m apart, 3 m to go, a 1 s
/// stall timeout: the smallest run whose agents can be stopped, killed or
/// refused one at a time.
pub const TWO: &str = r#"name = "two"
[world]
dt = 0.1
duration = 20.0
stall_timeout = 1.0

[[robot]]
name = "a"
start = [0.0, 0.0]
goal = [3.0, 0.0]
planner = "social-force"

[[robot]]
name = "b"
start = [0.0, 4.0]
goal = [3.0, 4.0]
planner = "social-force"
"#;

/// The events of `kind` about `robot` in `ev` (events.jsonl's lines).
pub fn events_of<'a>(
    ev: &'a [serde_json::Value],
    kind: &str,
    robot: &str,
) -> Vec<&'a serde_json::Value> {
    ev.iter()
        .filter(|e| e["type"] == kind && e["robot"] == robot)
        .collect()
}

/// Starts `mrsim run file` quietly into `out` as run `id` with `extra`
/// arguments, its stdout going to `stdout` and its stderr piped.
pub fn launcher(file: &Path, out: &Path, id: &str, extra: &[&str], stdout: Stdio) -> Child {
    mrsim()
        .arg("run")
        .arg(file)
        .arg("--out")
        .arg(out)
        .args(["--run", id, "--quiet"])
        .args(extra)
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .expect("start launcher")
}

/// Starts a world started by hand (`mrsim world`) for `scenario` as run
/// `id` into `out`, waiting up to `start_timeout` seconds for its agents;
/// its output goes nowhere.
pub fn hand_started_world(scenario: &Path, out: &Path, id: &str, start_timeout: u32) -> Child {
    mrsim()
        .arg("world")
        .arg(scenario)
        .args([
            "--run",
            id,
            "--start-timeout",
            &start_timeout.to_string(),
            "--out",
        ])
        .arg(out)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start world")
}

/// Says that `test` could not run and why, where it is seen: on the
/// terminal (written to stderr directly, past libtest's capture of a passing
/// test's output) and as a line of `target/tmp/skipped.txt`, which CI prints
/// at its end. When the environment variable `require` is `1` (CI sets
/// `MRSIM_REQUIRE_NETNS=1`, where it runs as root with iproute2) the skip is
/// a failure instead.
pub fn skip(test: &str, require: &str, why: &str) {
    use std::io::Write;
    assert!(
        std::env::var(require).as_deref() != Ok("1"),
        "{test} cannot run ({why}), and {require}=1 requires it"
    );
    let line = format!("skipped: {test}: {why}\n");
    let _ = std::io::stderr().write_all(line.as_bytes());
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::create_dir_all(&dir);
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(dir.join("skipped.txt"))
    {
        let _ = f.write_all(line.as_bytes());
    }
}

/// Held by a test whose assertions need the machine's cores to themselves
/// (realtime runs of many agents, a link cut and its lease): such tests run
/// one at a time, whatever their module (every end-to-end test is in this
/// one binary). A test that failed while holding it does not block the
/// others.
pub fn heavy() -> std::sync::MutexGuard<'static, ()> {
    static HEAVY: std::sync::Mutex<()> = std::sync::Mutex::new(());
    HEAVY.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs `mrsim run FILE --out DIR/out` (DIR the file's folder) for a file
/// that must be refused: asserts exit status 2 and that nothing ran (no
/// metrics.json); returns stderr.
pub fn run_refused(file: &Path) -> String {
    let out = file.parent().expect("a folder").join("out");
    let o = mrsim()
        .arg("run")
        .arg(file)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("start mrsim");
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        !out.join("metrics.json").exists(),
        "nothing may run: {stderr}"
    );
    stderr
}

/// Distance from `p` to the segment `[a, b]`.
pub fn segment_distance(p: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0);
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// The four robots r0..r3 of the timing tests, crossing in pairs (orca,
/// radius 0.3, 1 m/s) at 10 Hz: a scenario named `name` whose `[world]`
/// table ends with `world` (extra lines), followed by `tables` (a
/// `[world.cpus]` or `[defaults.timing]`, say) and, if `obstacle`, one
/// randomly moving obstacle o1.
pub fn four_crossing(name: &str, world: &str, tables: &str, obstacle: bool) -> String {
    let obstacle = if obstacle {
        r#"
[[obstacle]]
name = "o1"
start = [1.5, 2.0]
radius = 0.3
motion = { model = "random", accel_sigma = 0.5, alpha1 = 0.8, beta1 = 0.5, max_speed = 0.4 }
"#
    } else {
        ""
    };
    format!(
        r#"name = "{name}"
[world]
dt = 0.1
substeps = 10
seed = 7
{world}

[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 4.0
planner = "orca"

{tables}

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [6.0, 0.0]

[[robot]]
name = "r1"
start = [6.0, 0.3]
goal = [0.0, 0.3]

[[robot]]
name = "r2"
start = [3.0, -3.0]
goal = [3.0, 3.0]

[[robot]]
name = "r3"
start = [3.2, 3.0]
goal = [3.2, -3.0]
{obstacle}"#
    )
}

/// Writes `text` as `dir/tag.toml` and runs it into `dir/tag` (quiet, no
/// report) with `extra` arguments, asserting it succeeds; the run folder.
pub fn run_quietly(dir: &Path, text: &str, tag: &str, extra: &[&str]) -> PathBuf {
    let f = dir.join(format!("{tag}.toml"));
    std::fs::write(&f, text).expect("write scenario");
    let out = dir.join(tag);
    let mut args = vec!["--quiet", "--no-report"];
    args.extend(extra);
    assert_ok(&run(&f, &out, &run_id(tag), &args));
    out
}

/// The bytes of the run folder `dir`'s file `name`.
pub fn file_bytes(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()))
}

/// Per robot r0..r(n-1) of metrics.json: (deadline_misses, commands_late).
pub fn misses_of(dir: &Path, n: usize) -> Vec<(u64, u64)> {
    let m = metrics(dir);
    (0..n)
        .map(|i| {
            let r = &m["robots"][format!("r{i}")];
            (
                r["deadline_misses"].as_u64().expect("misses"),
                r["commands_late"].as_u64().expect("late"),
            )
        })
        .collect()
}

/// One row of timing.csv: (tick, robot, sent_ns, status, cpu_ns).
pub type CallRow = (u64, String, u64, String, u64);

/// timing.csv's rows in file order (its header checked).
pub fn timing_rows(dir: &Path) -> Vec<CallRow> {
    let text = std::fs::read_to_string(dir.join("timing.csv")).expect("timing.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("tick,robot,sent_ns,status,cpu_ns"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 5, "{l}");
            (
                f[0].parse().expect("tick"),
                f[1].to_string(),
                f[2].parse().expect("sent_ns"),
                f[3].to_string(),
                f[4].parse().expect("cpu_ns"),
            )
        })
        .collect()
}

/// Runs the shipped `scenario` (relative to the root; `(demo)`: the
/// built-in demo) in lockstep in-process with `extra` arguments and
/// returns its folder.
pub fn run_shipped(scenario: &str, extra: &[&str]) -> PathBuf {
    let out = fresh_dir("shipped");
    let mut cmd = mrsim();
    cmd.arg("run");
    if scenario != "(demo)" {
        cmd.arg(root().join(scenario));
    }
    let o = cmd
        .args([
            "--mode",
            "lockstep",
            "--transport",
            "inproc",
            "--quiet",
            "--no-report",
        ])
        .args(extra)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("start mrsim");
    assert_ok(&o);
    out
}
