//! The typed schemas against files written by real runs.

use mrsim_runfolder::usage::Usage;
use mrsim_runfolder::{FileError, METRICS_FILE, RunMetrics, read_json, read_metrics};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).expect("fixture readable")
}

/// Asserts that `a` and `b` have the same keys at every level and the same
/// values (numbers compared as written).
fn same_tree(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let kx: Vec<&String> = x.keys().collect();
            let ky: Vec<&String> = y.keys().collect();
            assert_eq!(kx, ky, "keys at {at}");
            for (k, v) in x {
                same_tree(v, &y[k], &format!("{at}.{k}"));
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "length at {at}");
            for (i, (v, w)) in x.iter().zip(y).enumerate() {
                same_tree(v, w, &format!("{at}[{i}]"));
            }
        }
        _ => assert_eq!(a, b, "value at {at}"),
    }
}

#[test]
fn a_real_runs_metrics_read_into_the_types_and_write_back_the_same_keys_and_values() {
    for name in ["crossing-metrics.json", "yamada-front-metrics.json"] {
        let original = text(name);
        let typed: RunMetrics = serde_json::from_str(&original).expect("reads into the types");
        let again = serde_json::to_string_pretty(&typed).expect("writes");
        let (a, b): (Value, Value) = (
            serde_json::from_str(&original).expect("json"),
            serde_json::from_str(&again).expect("json"),
        );
        same_tree(&a, &b, name);
        // And the same layout line by line: key order, nulls, nesting,
        // numbers (serde_json parses floats exactly: `float_roundtrip`,
        // set for the whole workspace).
        assert_eq!(
            original.lines().collect::<Vec<_>>(),
            again.lines().collect::<Vec<_>>(),
            "{name}"
        );
    }
}

#[test]
fn the_fixture_has_what_the_world_measures() {
    let m: RunMetrics = serde_json::from_str(&text("crossing-metrics.json")).expect("reads");
    assert_eq!(m.scenario, "crossing");
    assert_eq!(m.robots.len(), 8);
    assert_eq!(m.mode, "lockstep");
    assert!(m.robots.values().all(|r| r.planner == "homing"));
    assert!(m.robots.values().all(|r| r.latency_us.count == m.ticks));
    assert!(m.robots.values().all(|r| r.path_deviation.is_none()));
    let y: RunMetrics = serde_json::from_str(&text("yamada-front-metrics.json")).expect("reads");
    assert!(y.robots.values().any(|r| r.path_deviation.is_some()));
}

#[test]
fn a_real_runs_usage_reads_and_writes_back_the_same() {
    let original = text("crossing-usage.json");
    let u: Usage = serde_json::from_str(&original).expect("reads");
    assert_eq!(u.transport, "shm");
    assert_eq!(u.agents_reported, 8);
    let again = serde_json::to_value(&u).expect("writes");
    same_tree(
        &serde_json::from_str(&original).expect("json"),
        &again,
        "usage",
    );
}

#[test]
fn a_partial_metrics_file_reads_with_defaults_and_unknown_fields_are_ignored() {
    let m: RunMetrics = serde_json::from_str(
        r#"{"robots": {"r1": {"reached_goal": true, "latency_us": {"p99": 90.0}}},
            "ticks": 7, "world_pid": 999, "some_future_field": [1, 2]}"#,
    )
    .expect("reads");
    assert_eq!(m.ticks, 7);
    assert_eq!(m.world_pid, 999);
    assert!(m.robots["r1"].reached_goal);
    assert_eq!(m.robots["r1"].latency_us.p99, 90.0);
    assert_eq!(m.robots["r1"].latency_us.count, 0);
    assert_eq!(m.robots["r1"].min_clearance, None);
    assert_eq!(m.timing.cpus_steal_s, None);
}

#[test]
fn metrics_written_to_a_folder_read_back_equal_and_a_missing_file_names_its_path() {
    let dir = std::env::temp_dir().join(format!("mrsim-runfolder-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let m: RunMetrics = serde_json::from_str(&text("crossing-metrics.json")).expect("reads");
    mrsim_runfolder::write_metrics(&dir, &m).expect("writes");
    assert_eq!(read_metrics(&dir).expect("reads back"), m);
    std::fs::remove_file(dir.join(METRICS_FILE)).expect("remove");
    let err = read_metrics(&dir).expect_err("no file");
    assert!(matches!(err, FileError::Io { .. }));
    assert_eq!(err.path(), dir.join(METRICS_FILE));
    std::fs::write(dir.join("usage.json"), "{\"agents_cpu_s\": \"many\"}").expect("write");
    let err = read_json::<Usage>(&dir, "usage.json").expect_err("bad type");
    assert!(matches!(err, FileError::Json { .. }), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
