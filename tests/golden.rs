//! Every shipped scenario, run in lockstep, writes the trajectory.csv it wrote
//! when its hash was recorded in `tests/golden/trajectories.txt`: a refactor
//! that changes what the world computes (order of bodies, a float's rounding,
//! a formatting detail) fails here, byte for byte.
//!
//! The hashes were recorded from the tree before the structural split of the
//! runtime; a change that is meant to alter trajectories re-records them with
//! `MRSIM_BLESS=1 cargo test --release --test golden` and says why in its
//! commit. The runs are in-process (`--transport inproc`), which the spine
//! tests already show gives the same bytes as one process per robot.

mod common;
use common::*;
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

/// Every scenario file under scenarios/, relative to the repository root,
/// sorted; "(demo)" stands for the built-in demo (no file).
fn scenarios() -> Vec<String> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .expect("read scenarios/")
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
    out
}

fn golden_file() -> PathBuf {
    root().join("tests/golden/trajectories.txt")
}

fn read_golden() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(golden_file()).unwrap_or_default();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .filter_map(|l| {
            let (name, hash) = l.split_once(' ')?;
            Some((name.to_string(), hash.trim().to_string()))
        })
        .collect()
}

/// Runs one scenario in lockstep in-process and returns its trajectory's
/// hash and length.
fn trajectory_hash(scenario: &str) -> String {
    let out = fresh_dir("golden");
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
        .arg("--out")
        .arg(&out)
        .output()
        .expect("start mrsim");
    assert_ok(&o);
    let bytes = std::fs::read(out.join("trajectory.csv")).expect("trajectory.csv");
    let _ = std::fs::remove_dir_all(&out);
    format!("{:016x}:{}", fnv1a64(&bytes), bytes.len())
}

#[test]
fn every_shipped_scenario_in_lockstep_writes_the_recorded_trajectory_byte_for_byte() {
    let bless = std::env::var_os("MRSIM_BLESS").is_some();
    let golden = read_golden();
    let mut now = BTreeMap::new();
    for s in scenarios() {
        now.insert(s.clone(), trajectory_hash(&s));
    }
    if bless {
        let mut text = String::from(
            "# scenario fnv1a64:bytes of its lockstep trajectory.csv (tests/golden.rs)\n",
        );
        for (name, hash) in &now {
            text.push_str(&format!("{name} {hash}\n"));
        }
        std::fs::create_dir_all(root().join("tests/golden")).expect("mkdir");
        std::fs::write(golden_file(), text).expect("write golden");
        return;
    }
    let mut wrong = Vec::new();
    for (name, hash) in &now {
        match golden.get(name) {
            Some(g) if g == hash => {}
            Some(g) => wrong.push(format!("{name}: recorded {g}, now {hash}")),
            None => wrong.push(format!(
                "{name}: no recorded hash (a new scenario: record it with MRSIM_BLESS=1)"
            )),
        }
    }
    for name in golden.keys() {
        if !now.contains_key(name) {
            wrong.push(format!("{name}: recorded, but the file is gone"));
        }
    }
    assert!(
        wrong.is_empty(),
        "trajectories changed:\n{}",
        wrong.join("\n")
    );
}
