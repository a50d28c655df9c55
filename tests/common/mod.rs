//! Helpers for the end-to-end tests: run the real `mrsim` binary in fresh
//! folders, read its outputs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
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
    format!(
        "t{}-{}-{}",
        tag,
        std::process::id() % 100000,
        N.fetch_add(1, Ordering::SeqCst)
    )
}
