//! Every shipped scenario, run in lockstep, writes the trajectory.csv it wrote
//! when its hash was recorded in `tests/golden/trajectories.txt`: a refactor
//! that changes what the world computes (order of bodies, a float's rounding,
//! a formatting detail) fails here, byte for byte. The same runs' outcome
//! (`metrics.json`'s keys that lockstep makes exact), the lidar demo's
//! scan.csv, the crossing's Parquet trajectory (its decoded rows, so a writer
//! upgrade that keeps the values passes) and the Python package's bundled
//! scenario are held the same way in `tests/golden/outputs.txt`.
//!
//! The hashes were recorded from the tree before the structural split of the
//! runtime; a change that is meant to alter them re-records them with
//! `MRSIM_BLESS=1 cargo test --release --test it golden::` (only the value `1`
//! blesses), which prints every entry it changes, and says why in its
//! commit. The runs are in-process (`--transport inproc`), which the spine
//! tests already show gives the same bytes as one process per robot.

use crate::common::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// FNV-1a, 64 bits: a stable hash with no dependency (std's `DefaultHasher`
/// may change between Rust releases).
fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Every scenario file under scenarios/ and the Python package's bundled
/// ones, relative to the repository root, sorted; "(demo)" stands for the
/// built-in demo (no file).
fn scenarios() -> Vec<String> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .expect("read a scenario folder")
            .map(|e| e.expect("entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, root, out);
            } else if p.extension().is_some_and(|e| e == "toml") {
                let rel = p.strip_prefix(root).expect("under root");
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let root = root();
    let mut out = vec!["(demo)".to_string()];
    walk(&root.join("scenarios"), &root, &mut out);
    walk(&root.join("python/mrsim/scenarios"), &root, &mut out);
    out
}

/// `name hash` lines of a golden file (comments and blank lines skipped).
fn read_golden(file: &Path) -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(file).unwrap_or_default();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .filter_map(|l| {
            let (name, hash) = l.rsplit_once(' ')?;
            Some((name.to_string(), hash.trim().to_string()))
        })
        .collect()
}

/// `fnv1a64:length` of `bytes`.
fn hash_of(bytes: &[u8]) -> String {
    format!("{:016x}:{}", fnv1a64(bytes), bytes.len())
}

/// The keys of metrics.json a lockstep run makes exact (no wall clock, no
/// pid), as one canonical JSON text (keys sorted).
fn exact_metrics(dir: &Path) -> String {
    let m = metrics(dir);
    let pick = |v: &serde_json::Value, keys: &[&str]| -> serde_json::Value {
        keys.iter()
            .map(|k| (k.to_string(), v[*k].clone()))
            .collect::<serde_json::Map<_, _>>()
            .into()
    };
    let mut run = pick(
        &m,
        &[
            "ticks",
            "sim_time",
            "success_rate",
            "collisions_total",
            "agents_lost",
            "commands_rejected",
            "mode",
        ],
    );
    let robots: serde_json::Map<_, _> = m["robots"]
        .as_object()
        .expect("robots")
        .iter()
        .map(|(name, r)| {
            let keep = pick(
                r,
                &[
                    "planner",
                    "reached_goal",
                    "time_to_goal",
                    "path_length",
                    "collisions",
                    "min_clearance",
                    "max_speed",
                    "commands_rejected",
                    "path_deviation",
                    "boundary_violations",
                ],
            );
            (name.clone(), keep)
        })
        .collect();
    run["robots"] = robots.into();
    run.to_string()
}

/// The rows of a Parquet trajectory, every number by its bits.
fn parquet_rows(dir: &Path) -> Vec<u8> {
    let table =
        mrsim_runfolder::trajectory::read_parquet_trajectory(&dir.join("trajectory.parquet"))
            .expect("trajectory.parquet reads back");
    let mut text = String::new();
    for r in table.rows() {
        text.push_str(&format!(
            "{} {:x} {} {} {:x} {:x} {:x} {:x} {:?}\n",
            r.tick,
            r.time.to_bits(),
            r.body,
            r.kind,
            r.x.to_bits(),
            r.y.to_bits(),
            r.vx.to_bits(),
            r.vy.to_bits(),
            r.theta.map(f64::to_bits)
        ));
    }
    text.into_bytes()
}

/// Whether this run re-records the golden files: only `MRSIM_BLESS=1`.
fn blessing() -> bool {
    std::env::var("MRSIM_BLESS").as_deref() == Ok("1")
}

/// What differs between the recorded entries and the ones computed now,
/// one line each.
fn differences(recorded: &BTreeMap<String, String>, now: &BTreeMap<String, String>) -> Vec<String> {
    let mut wrong = Vec::new();
    for (name, hash) in now {
        match recorded.get(name) {
            Some(g) if g == hash => {}
            Some(g) => wrong.push(format!("{name}: recorded {g}, now {hash}")),
            None => wrong.push(format!(
                "{name}: no recorded hash (new: record it with MRSIM_BLESS=1), now {hash}"
            )),
        }
    }
    for name in recorded.keys() {
        if !now.contains_key(name) {
            wrong.push(format!("{name}: recorded, but it is gone"));
        }
    }
    wrong
}

/// Compares `now` with `file` and returns what differs, or, when blessing,
/// writes it there (under `header`), prints what changed on stderr, where it
/// is seen, and returns nothing.
fn check_or_bless(file: &Path, header: &str, now: &BTreeMap<String, String>) -> Vec<String> {
    let recorded = read_golden(file);
    let wrong = differences(&recorded, now);
    if blessing() {
        use std::io::Write;
        let mut text = format!("{header}\n");
        for (name, hash) in now {
            text.push_str(&format!("{name} {hash}\n"));
        }
        std::fs::create_dir_all(root().join("tests/golden")).expect("mkdir");
        std::fs::write(file, text).expect("write golden");
        let mut said = format!(
            "MRSIM_BLESS=1: {} entries of {} changed\n",
            wrong.len(),
            file.display()
        );
        for w in &wrong {
            said.push_str(&format!("  {w}\n"));
        }
        let _ = std::io::stderr().write_all(said.as_bytes());
        return Vec::new();
    }
    wrong
        .into_iter()
        .map(|w| format!("{}: {w}", file.display()))
        .collect()
}

#[test]
fn every_shipped_scenario_in_lockstep_writes_the_recorded_trajectory_and_outcome() {
    let mut trajectories = BTreeMap::new();
    let mut outputs = BTreeMap::new();
    for s in scenarios() {
        let out = run_shipped(&s, &[]);
        let bytes = std::fs::read(out.join("trajectory.csv")).expect("trajectory.csv");
        trajectories.insert(s.clone(), hash_of(&bytes));
        outputs.insert(
            format!("{s} metrics.json"),
            hash_of(exact_metrics(&out).as_bytes()),
        );
        if out.join("scan.csv").exists() {
            let scans = std::fs::read(out.join("scan.csv")).expect("scan.csv");
            outputs.insert(format!("{s} scan.csv"), hash_of(&scans));
        }
        let _ = std::fs::remove_dir_all(&out);
    }
    assert!(
        outputs.contains_key("scenarios/lidar-demo.toml scan.csv"),
        "the lidar demo records scans"
    );
    let pq = run_shipped(
        "scenarios/crossing.toml",
        &["--set", "output.trajectory=parquet"],
    );
    outputs.insert(
        "scenarios/crossing.toml trajectory.parquet rows".into(),
        hash_of(&parquet_rows(&pq)),
    );
    let _ = std::fs::remove_dir_all(&pq);
    let mut wrong = check_or_bless(
        &root().join("tests/golden/trajectories.txt"),
        "# scenario fnv1a64:bytes of its lockstep trajectory.csv (tests/it/golden.rs)",
        &trajectories,
    );
    wrong.extend(check_or_bless(
        &root().join("tests/golden/outputs.txt"),
        "# scenario and output, fnv1a64:bytes of it (tests/it/golden.rs: metrics.json's exact keys, scan.csv, Parquet rows)",
        &outputs,
    ));
    assert!(
        wrong.is_empty(),
        "outputs changed (`MRSIM_BLESS=1 cargo test --release --test it golden::` re-records them):\n{}",
        wrong.join("\n")
    );
}
