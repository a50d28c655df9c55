//! `[output]`: the trajectory as CSV, Parquet or not at all, every tick or
//! every K-th, on real runs; the metrics and the report whatever it says.

use crate::common::*;
use std::path::{Path, PathBuf};

/// Runs the lockstep crossing scene (8 robots, 5 s) in-process with
/// `extra` settings; returns its folder.
fn crossing(tag: &str, extra: &[&str]) -> PathBuf {
    five_seconds_of("crossing.toml", tag, extra)
}

/// Runs `scenarios/{file}` in lockstep for 5 s in-process with `extra`
/// settings; returns its folder.
fn five_seconds_of(file: &str, tag: &str, extra: &[&str]) -> PathBuf {
    let dir = fresh_dir(tag);
    let mut args = vec![
        "--transport",
        "inproc",
        "--quiet",
        "--set",
        "world.duration=5",
    ];
    for s in extra {
        args.extend(["--set", s]);
    }
    let out = run(
        &root().join("scenarios").join(file),
        &dir,
        &run_id(tag),
        &args,
    );
    assert_ok(&out);
    dir
}

fn csv_lines(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("trajectory.csv"))
        .expect("trajectory.csv")
        .lines()
        .map(str::to_string)
        .collect()
}

/// The motion metrics of every robot: the ones that do not depend on the
/// wall clock.
fn motion(dir: &Path) -> Vec<(String, serde_json::Value)> {
    let m = metrics(dir);
    let robots = m["robots"].as_object().expect("robots");
    robots
        .iter()
        .map(|(name, r)| {
            let keep: serde_json::Map<_, _> = [
                "reached_goal",
                "time_to_goal",
                "path_length",
                "collisions",
                "min_clearance",
                "max_speed",
            ]
            .iter()
            .map(|k| (k.to_string(), r[*k].clone()))
            .collect();
            (name.clone(), serde_json::Value::Object(keep))
        })
        .collect()
}

#[test]
fn parquet_holds_the_same_rows_as_the_csv_of_the_same_run() {
    let csv = crossing("out-csv", &[]);
    let pq = crossing("out-parquet", &["output.trajectory=parquet"]);
    assert!(
        !pq.join("trajectory.csv").exists(),
        "a parquet run wrote a CSV too"
    );
    let table =
        mrsim_runfolder::trajectory::read_parquet_trajectory(&pq.join("trajectory.parquet"))
            .expect("reads back");
    assert!(!table.has_theta(), "no unicycle, no theta column");
    let lines = csv_lines(&csv);
    assert_eq!(lines[0], "tick,time,body,kind,x,y,vx,vy");
    assert_eq!(table.len(), lines.len() - 1, "row count");
    // Value for value: the CSV is the Parquet file's numbers to six decimals.
    for (row, line) in table.rows().zip(&lines[1..]) {
        let written = format!(
            "{},{:.6},{},{},{:.6},{:.6},{:.6},{:.6}",
            row.tick, row.time, row.body, row.kind, row.x, row.y, row.vx, row.vy
        );
        assert_eq!(&written, line);
    }
    assert_eq!(motion(&csv), motion(&pq));
    // DOUBLE exact: each robot's path length summed from the file's
    // positions, the way the world sums it from its states every tick, is
    // metrics.json's to the last bit (positions rounded to six decimals, as
    // in the CSV, would be off by about 1e-6).
    let m = metrics(&pq);
    let mut last: std::collections::BTreeMap<String, (f64, f64)> = Default::default();
    let mut length: std::collections::BTreeMap<String, f64> = Default::default();
    for row in table.rows().filter(|r| r.kind == "robot") {
        if let Some((x0, y0)) = last.insert(row.body.to_string(), (row.x, row.y)) {
            let (dx, dy) = (row.x - x0, row.y - y0);
            *length.entry(row.body.to_string()).or_default() += (dx * dx + dy * dy).sqrt();
        }
    }
    assert_eq!(length.len(), 8, "{length:?}");
    for (robot, l) in &length {
        let recorded = m["robots"][robot]["path_length"]
            .as_f64()
            .expect("path_length");
        assert!(*l > 0.5, "{robot} moved: {l}");
        assert_eq!(
            l.to_bits(),
            recorded.to_bits(),
            "{robot}: {l} vs {recorded}"
        );
    }
    // The report reads it: plots and a replay page with the same ticks.
    let out = mrsim().arg("report").arg(&pq).output().expect("report");
    assert_ok(&out);
    let page = std::fs::read_to_string(pq.join("replay.html")).expect("replay.html");
    assert!(page.contains(r#""ticksRecorded":51"#), "51 ticks in 5 s");
}

#[test]
fn every_kth_tick_keeps_those_rows_and_the_last_and_the_metrics_see_every_tick() {
    let all = crossing("out-every1", &[]);
    let some = crossing("out-every7", &["output.every=7"]);
    let full = csv_lines(&all);
    let last_tick: u64 = full
        .last()
        .and_then(|l| l.split(',').next())
        .and_then(|t| t.parse().ok())
        .expect("last tick");
    assert_eq!(last_tick, 50);
    let expected: Vec<&String> = full
        .iter()
        .enumerate()
        .filter(|(i, l)| {
            let tick: u64 = l
                .split(',')
                .next()
                .and_then(|t| t.parse().ok())
                .unwrap_or(0);
            *i == 0 || tick.is_multiple_of(7) || tick == last_tick
        })
        .map(|(_, l)| l)
        .collect();
    let got = csv_lines(&some);
    assert_eq!(got.iter().collect::<Vec<_>>(), expected);
    assert_eq!(motion(&all), motion(&some), "metrics from every tick");
}

#[test]
fn without_a_trajectory_the_metrics_are_the_same_and_the_report_draws_the_scene() {
    let all = crossing("out-all", &[]);
    let none = crossing("out-none", &["output.trajectory=none"]);
    assert!(!none.join("trajectory.csv").exists());
    assert!(!none.join("trajectory.parquet").exists());
    assert_eq!(motion(&all), motion(&none));
    assert_eq!(
        metrics(&none)["robots"].as_object().map(|r| r.len()),
        Some(8)
    );
    let out = mrsim().arg("report").arg(&none).output().expect("report");
    assert_ok(&out);
    assert!(none.join("plot.svg").exists() && none.join("replay.html").exists());
    let page = std::fs::read_to_string(none.join("replay.html")).expect("replay.html");
    assert!(page.contains(r#""ticksRecorded":0"#));
}

/// Runs the lockstep unicycle crossing (4 unicycles, 5 s) in-process with
/// `extra` settings; returns its folder.
fn unicycle_crossing(tag: &str, extra: &[&str]) -> PathBuf {
    five_seconds_of("unicycle-crossing.toml", tag, extra)
}

#[test]
fn a_unicycle_run_in_parquet_keeps_every_heading_of_the_csv() {
    let csv = unicycle_crossing("uc-csv", &[]);
    let pq = unicycle_crossing("uc-parquet", &["output.trajectory=parquet"]);
    let table =
        mrsim_runfolder::trajectory::read_parquet_trajectory(&pq.join("trajectory.parquet"))
            .expect("reads back");
    assert!(table.has_theta(), "a unicycle run's Parquet file has theta");
    let lines = csv_lines(&csv);
    assert_eq!(lines[0], "tick,time,body,kind,x,y,vx,vy,theta");
    assert_eq!(table.len(), lines.len() - 1, "row count");
    let mut turned = 0;
    for (row, line) in table.rows().zip(&lines[1..]) {
        let theta = row.theta.expect("every row has a heading");
        let written = format!(
            "{},{:.6},{},{},{:.6},{:.6},{:.6},{:.6},{:.6}",
            row.tick, row.time, row.body, row.kind, row.x, row.y, row.vx, row.vy, theta
        );
        assert_eq!(&written, line);
        turned += usize::from(theta.abs() > 0.1);
    }
    // Stream b starts facing +y: headings other than 0 are written.
    assert!(turned > 0, "no heading away from 0");
    assert_eq!(motion(&csv), motion(&pq));
}

#[test]
fn the_report_refuses_a_parquet_trajectory_whose_footer_is_cut_or_wrong() {
    let pq = crossing("out-pq-footer", &["output.trajectory=parquet"]);
    let file = pq.join("trajectory.parquet");
    let whole = std::fs::read(&file).expect("trajectory.parquet");
    assert_eq!(
        &whole[whole.len() - 4..],
        b"PAR1",
        "a Parquet file ends with its magic"
    );
    // Cut mid-footer, the magic gone; then the magic kept but the footer's
    // length pointing past the start; then a file that is only the magic.
    let mut bad_length = whole.clone();
    let at = bad_length.len() - 8;
    bad_length[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    for (what, bytes) in [
        ("cut", whole[..whole.len() - 10].to_vec()),
        ("bad footer length", bad_length),
        ("magic only", b"PAR1".to_vec()),
    ] {
        std::fs::write(&file, &bytes).expect("write");
        let o = mrsim().arg("report").arg(&pq).output().expect("report");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {stderr}");
        assert!(stderr.contains("trajectory.parquet"), "{what}: {stderr}");
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    }
}
