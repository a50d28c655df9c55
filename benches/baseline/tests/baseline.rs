//! The baseline program on a tiny fan-out: it starts its agents, ticks and
//! writes its result (never its timing).

use std::process::Command;

#[test]
fn a_tiny_baseline_writes_its_round_trip_and_all_in_percentiles() {
    let out = std::env::temp_dir().join(format!("mrsim-baseline-test-{}.json", std::process::id()));
    let _ = std::fs::remove_file(&out);
    let run = format!("basetest{}", std::process::id());
    let o = Command::new(env!("CARGO_BIN_EXE_mrsim-baseline"))
        .args(["world", "--run", &run, "--agents", "2", "--rate", "50"])
        .args(["--duration", "0.5", "--out"])
        .arg(&out)
        .output()
        .expect("start mrsim-baseline");
    assert!(
        o.status.success(),
        "{:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&out).expect("the result");
    let _ = std::fs::remove_file(&out);
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["agents"], 2);
    assert_eq!(v["ticks"], 25);
    for k in ["allin_us", "roundtrip_us"] {
        assert!(v[k].get("p99").is_some(), "{k}: {v:#}");
    }
    let miss = v["miss_rate"].as_f64().expect("miss_rate");
    assert!((0.0..=1.0).contains(&miss));
}

#[test]
fn a_baseline_without_agents_is_refused() {
    let o = Command::new(env!("CARGO_BIN_EXE_mrsim-baseline"))
        .args([
            "world",
            "--run",
            "basebad",
            "--agents",
            "0",
            "--out",
            "/dev/null",
        ])
        .output()
        .expect("start mrsim-baseline");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("must be positive"));
}
