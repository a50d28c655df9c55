//! `mrsim sweep` end to end: 2 values x 2 seeds of a tiny scenario give a
//! sweep.csv of the right shape, and the same command gives the same file.

use crate::common::*;

const SCENARIO: &str = r#"
name = "sweep-tiny"
[world]
dt = 0.1
duration = 2.0
[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [1.0, 0.0]
max_speed = 1.0
max_accel = 2.0
goal_tolerance = 0.1
[[obstacle]]
name = "o1"
start = [0.5, 1.0]
radius = 0.2
motion = { model = "random", accel_sigma = 1.0, max_speed = 0.5 }
"#;

fn sweep(dir: &std::path::Path, scenario: &std::path::Path) -> std::process::Output {
    sweep_with(dir, scenario, &[])
}

/// The sweep of two values and two seeds, with `extra` arguments.
fn sweep_with(
    dir: &std::path::Path,
    scenario: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    mrsim()
        .arg("sweep")
        .arg(scenario)
        .args([
            "--set",
            "robot.r0.max_speed=0.5,1.5",
            "--seeds",
            "2",
            "--jobs",
            "2",
        ])
        .args(extra)
        .arg("--out")
        .arg(dir)
        .output()
        .expect("start mrsim")
}

#[test]
fn a_sweep_of_two_values_and_two_seeds_writes_four_rows_and_repeats_exactly() {
    let dir = fresh_dir("sweep");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = sweep(&dir.join("a"), &scenario);
    assert_ok(&out);
    let csv = std::fs::read_to_string(dir.join("a/sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 5, "{csv}");
    let header = &rows[0];
    for col in [
        "robot.r0.max_speed",
        "seed",
        "success_rate",
        "collisions_total",
        "collided",
        "makespan",
        "path_length_ratio",
        "min_clearance",
        "time_to_goal",
        "agents_lost",
        "ticks",
        "run",
    ] {
        assert!(header.contains(&col), "no column {col} in {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let got: Vec<(&str, &str)> = rows[1..]
        .iter()
        .map(|r| (r[col("robot.r0.max_speed")], r[col("seed")]))
        .collect();
    assert_eq!(
        got,
        [("0.5", "1"), ("0.5", "2"), ("1.5", "1"), ("1.5", "2")]
    );
    for r in &rows[1..] {
        assert_eq!(r.len(), header.len());
        // Each row's run folder holds that run, made at that speed.
        let run = dir.join("a").join(r[col("run")]);
        let m = metrics(&run);
        assert_eq!(m["mode"], "lockstep");
        assert_eq!(r[col("ticks")], m["ticks"].to_string());
        let sc: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(run.join("scenario.json")).expect("scenario.json"),
        )
        .expect("scenario.json parses");
        assert_eq!(
            sc["robots"][0]["max_speed"].as_f64().map(|v| v.to_string()),
            Some(r[col("robot.r0.max_speed")].to_string())
        );
        assert_eq!(sc["world"]["seed"].to_string(), r[col("seed")]);
    }
    // The summary has one line per combination.
    let summary = std::fs::read_to_string(dir.join("a/summary.csv")).expect("summary.csv");
    assert_eq!(summary.lines().count(), 3, "{summary}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("±"), "{stdout}");

    let again = sweep(&dir.join("b"), &scenario);
    assert_ok(&again);
    let csv2 = std::fs::read_to_string(dir.join("b/sweep.csv")).expect("sweep.csv");
    assert_eq!(csv, csv2);
}

#[test]
fn a_resumed_sweep_keeps_the_whole_runs_and_runs_again_only_the_missing_and_the_foreign() {
    let dir = fresh_dir("sweep-resume");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = sweep(&dir.join("a"), &scenario);
    assert_ok(&out);
    let csv = std::fs::read_to_string(dir.join("a/sweep.csv")).expect("sweep.csv");
    let runs: Vec<String> = csv
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next_back().map(str::to_string))
        .collect();
    assert_eq!(runs.len(), 4, "{csv}");
    // A run cut before its metrics were written, and a folder holding
    // another run (other overrides) than the sweep's.
    std::fs::remove_file(dir.join("a").join(&runs[0]).join("metrics.json")).expect("rm");
    let source = dir.join("a").join(&runs[3]).join("source.json");
    let text = std::fs::read_to_string(&source).expect("source.json");
    std::fs::write(&source, text.replace("max_speed=1.5", "max_speed=0.7")).expect("write");
    let again = sweep_with(&dir.join("a"), &scenario, &["--resume"]);
    assert_ok(&again);
    let said = String::from_utf8_lossy(&again.stderr);
    assert!(said.contains("kept 2 of 4 runs"), "{said}");
    for (i, run) in runs.iter().enumerate() {
        let kept = said.contains(&format!("{run} (kept)"));
        assert_eq!(kept, i == 1 || i == 2, "{run}: {said}");
    }
    assert!(dir.join("a").join(&runs[0]).join("metrics.json").exists());
    let text = std::fs::read_to_string(&source).expect("source.json");
    assert!(text.contains("max_speed=1.5"), "{text}");
    // The same table as the sweep run whole.
    let csv2 = std::fs::read_to_string(dir.join("a/sweep.csv")).expect("sweep.csv");
    assert_eq!(csv, csv2);
}

#[test]
fn a_resume_without_an_output_folder_is_refused() {
    let dir = fresh_dir("sweep-resume-no-out");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let o = mrsim()
        .arg("sweep")
        .arg(&scenario)
        .args(["--set", "robot.r0.max_speed=0.5,1.5", "--resume"])
        .output()
        .expect("start mrsim");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--out"), "{err}");
}

#[test]
fn a_sweep_with_a_bad_value_is_refused_before_any_run() {
    let dir = fresh_dir("sweep-bad");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = mrsim()
        .arg("sweep")
        .arg(&scenario)
        .args(["--set", "robot.r0.max_speed=1,-2"])
        .arg("--out")
        .arg(dir.join("o"))
        .output()
        .expect("start mrsim");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("max_speed=-2"), "{err}");
    assert!(!dir.join("o").exists());
}

/// A header's column index by name.
fn column(header: &[&str], name: &str) -> usize {
    header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// The `<text>` contents of an SVG, in order.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = t.split_once('>')?.1;
            Some(body.split_once("</text>")?.0.trim().to_string())
        })
        .collect()
}

/// Opaque lines of width 2 through `n` points: the modelled curves of a
/// sweep of `n` values (a measured curve is drawn as short translucent
/// dashes, the legend's samples as paths of two points).
fn solid_curves(svg: &str, n: usize) -> usize {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| {
            let tag = p.split_once("/>").map_or(*p, |(t, _)| t);
            let points = tag
                .split_once("points=\"")
                .map_or("", |(_, r)| r.split_once('"').map_or("", |(p, _)| p));
            tag.contains("stroke-width=\"2\"")
                && tag.contains("opacity=\"1\"")
                && points.split_whitespace().count() == n
        })
        .count()
}

/// From summary.csv: how many lines of the figure have a point at every
/// one of the `n` swept values, over the panels (metrics), for the rows of
/// `mode`, one line per value of `other` (a column) or one if none.
fn complete_lines(summary: &str, mode: &str, other: Option<&str>, n: usize) -> usize {
    let rows: Vec<Vec<&str>> = summary.lines().map(|l| l.split(',').collect()).collect();
    let h = &rows[0];
    let metrics: Vec<&str> = h.iter().filter_map(|c| c.strip_suffix("_mean")).collect();
    let mut lines = 0;
    for m in metrics {
        let mean = column(h, &format!("{m}_mean"));
        let mut groups: Vec<(&str, usize)> = Vec::new();
        for r in rows[1..].iter().filter(|r| r[column(h, "mode")] == mode) {
            let g = other.map_or("", |o| r[column(h, o)]);
            let has = usize::from(!r[mean].is_empty());
            match groups.iter_mut().find(|(k, _)| *k == g) {
                Some(e) => e.1 += has,
                None => groups.push((g, has)),
            }
        }
        lines += groups.iter().filter(|(_, c)| *c == n).count();
    }
    lines
}

/// Runs `mrsim sweep` of the tiny scenario with `args` into a fresh folder;
/// returns that folder and the output.
fn sweep_tiny(tag: &str, args: &[&str]) -> (std::path::PathBuf, std::process::Output) {
    let dir = fresh_dir(tag);
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = mrsim()
        .arg("sweep")
        .arg(&scenario)
        .args(args)
        .arg("--out")
        .arg(dir.join("o"))
        .output()
        .expect("start mrsim");
    (dir.join("o"), out)
}

#[test]
fn a_sweep_draws_every_metric_with_one_line_per_combination_of_the_other_keys() {
    let (o, out) = sweep_tiny(
        "sweep-plot",
        &[
            "--set",
            "robot.r0.max_speed=0.5,1,1.5",
            "--set",
            "world.dt=0.05,0.1",
            "--seeds",
            "2",
            "--x",
            "robot.r0.max_speed",
        ],
    );
    assert_ok(&out);
    let svg = std::fs::read_to_string(o.join("sweep.svg")).expect("sweep.svg");
    let png = std::fs::read(o.join("sweep.png")).expect("sweep.png");
    assert_eq!(&png[1..4], b"PNG");
    let texts = svg_texts(&svg);
    // The legend: one entry per value of the other key.
    for label in ["dt=0.05", "dt=0.1"] {
        assert_eq!(
            texts.iter().filter(|t| *t == label).count(),
            1,
            "{label} in {texts:?}"
        );
    }
    // One panel per metric, its axis labelled with its unit.
    for metric in [
        "success_rate",
        "collided",
        "makespan",
        "path_length_ratio",
        "min_clearance",
    ] {
        assert!(texts.iter().any(|t| t == metric), "no panel {metric}");
    }
    assert!(texts.iter().any(|t| t == "robot.r0.max_speed [m/s]"));
    assert!(texts.iter().any(|t| t == "last arrival [s]"));
    // Two lines (one per dt) of three points in each of the nine panels,
    // except where a point has no value (time_to_goal where the robot
    // never arrived).
    let summary = std::fs::read_to_string(o.join("summary.csv")).expect("summary.csv");
    let want = complete_lines(&summary, "lockstep", Some("world.dt"), 3);
    assert!(want >= 2 * 8, "{summary}");
    assert_eq!(solid_curves(&svg, 3), want, "{svg}");
}

#[test]
fn the_summary_intervals_are_students_t_over_the_seeds() {
    let (o, out) = sweep_tiny(
        "sweep-ci",
        &["--set", "robot.r0.max_speed=0.5,1.5", "--seeds", "3"],
    );
    assert_ok(&out);
    let csv = std::fs::read_to_string(o.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let summary = std::fs::read_to_string(o.join("summary.csv")).expect("summary.csv");
    let srows: Vec<Vec<&str>> = summary.lines().map(|l| l.split(',').collect()).collect();
    let (h, sh) = (&rows[0], &srows[0]);
    let mut checked = 0;
    for speed in ["0.5", "1.5"] {
        let srow = srows[1..]
            .iter()
            .find(|r| r[column(sh, "robot.r0.max_speed")] == speed)
            .expect("a summary row per speed");
        assert_eq!(srow[column(sh, "mode")], "lockstep");
        assert_eq!(srow[column(sh, "runs")], "3");
        for metric in ["makespan", "path_length_ratio", "min_clearance", "ticks"] {
            let xs: Vec<f64> = rows[1..]
                .iter()
                .filter(|r| r[column(h, "robot.r0.max_speed")] == speed)
                .map(|r| r[column(h, metric)].parse().expect("a number"))
                .collect();
            assert_eq!(xs.len(), 3);
            // By hand: mean, sample standard deviation, t(0.975, 2) = 4.303.
            let mean = xs.iter().sum::<f64>() / 3.0;
            let s = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
            let half = 4.303 * s / 3f64.sqrt();
            let got_mean: f64 = srow[column(sh, &format!("{metric}_mean"))]
                .parse()
                .expect("mean");
            let got_half: f64 = srow[column(sh, &format!("{metric}_ci95"))]
                .parse()
                .expect("half-width");
            assert!(
                (got_mean - mean).abs() < 1e-9,
                "{metric}: {got_mean} vs {mean}"
            );
            assert!(
                (got_half - half).abs() < 1e-9,
                "{metric}: {got_half} vs {half}"
            );
            checked += usize::from(half > 0.0);
        }
    }
    // The random obstacle makes the seeds differ: some interval is not 0.
    assert!(checked > 0, "every metric was the same for every seed");
}

#[test]
fn realtime_runs_go_one_at_a_time_and_both_modes_share_one_figure() {
    let (o, out) = sweep_tiny(
        "sweep-both",
        &[
            "--set",
            "robot.r0.max_speed=0.5,1,1.5",
            "--seeds",
            "2",
            "--mode",
            "both",
        ],
    );
    assert_ok(&out);
    let csv = std::fs::read_to_string(o.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let h = &rows[0];
    let modes: Vec<&str> = rows[1..].iter().map(|r| r[column(h, "mode")]).collect();
    assert_eq!(modes, [["lockstep"; 6], ["realtime"; 6]].concat());
    // Each realtime run's files were all written before the next run's
    // first: one run at a time.
    let span = |run: &std::path::Path| {
        let times: Vec<std::time::SystemTime> = std::fs::read_dir(run)
            .expect("run folder")
            .flatten()
            .filter_map(|e| e.metadata().ok()?.modified().ok())
            .collect();
        let first = times.iter().min().copied().expect("files");
        let last = times.iter().max().copied().expect("files");
        (first, last)
    };
    let realtime: Vec<_> = rows[1..]
        .iter()
        .filter(|r| r[column(h, "mode")] == "realtime")
        .map(|r| {
            let run = o.join(r[column(h, "run")]);
            assert_eq!(metrics(&run)["mode"], "realtime");
            span(&run)
        })
        .collect();
    for pair in realtime.windows(2) {
        assert!(pair[0].1 <= pair[1].0, "realtime runs overlapped: {pair:?}");
    }
    // One figure with the modelled and the measured curve.
    let svg = std::fs::read_to_string(o.join("sweep.svg")).expect("sweep.svg");
    let texts = svg_texts(&svg);
    for label in ["lockstep (modelled)", "realtime (measured)"] {
        assert!(texts.iter().any(|t| t == label), "{label} in {texts:?}");
    }
    let summary = std::fs::read_to_string(o.join("summary.csv")).expect("summary.csv");
    let want = complete_lines(&summary, "lockstep", None, 3);
    assert!(want >= 8, "{summary}");
    assert_eq!(solid_curves(&svg, 3), want, "one modelled line per panel");
    // And the measured one: its dashes, translucent.
    assert!(svg.contains("opacity=\"0.9\""), "no dashed line");
    assert_eq!(summary.lines().count(), 7, "{summary}");
}

#[test]
fn realtime_runs_in_parallel_are_refused() {
    let (o, out) = sweep_tiny(
        "sweep-rt-jobs",
        &[
            "--set",
            "robot.r0.max_speed=0.5,1.5",
            "--mode",
            "realtime",
            "--jobs",
            "2",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("one at a time"));
    assert!(!o.exists());
}

#[test]
fn a_timing_sweep_reports_the_miss_rate_and_draws_only_the_metrics_asked_for() {
    // No timing in the file: `compute.ms` alone names the fixed model.
    // At dt 0.1 s, 20 ms of compute meets every deadline, 150 ms none.
    let (o, out) = sweep_tiny(
        "sweep-misses",
        &[
            "--set",
            "defaults.timing.compute.ms=20,150",
            "--metrics",
            "miss_rate,success_rate",
        ],
    );
    assert_ok(&out);
    let csv = std::fs::read_to_string(o.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let (key, rate) = (
        column(&rows[0], "defaults.timing.compute.ms"),
        column(&rows[0], "miss_rate"),
    );
    let rate_at = |ms: &str| -> f64 {
        let r = rows[1..].iter().find(|r| r[key] == ms).expect("row");
        r[rate].parse().expect("miss_rate")
    };
    assert_eq!(rate_at("20"), 0.0, "{csv}");
    assert_eq!(rate_at("150"), 1.0, "{csv}");
    let texts = svg_texts(&std::fs::read_to_string(o.join("sweep.svg")).expect("sweep.svg"));
    let panels: Vec<&String> = texts
        .iter()
        .filter(|t| METRIC_NAMES.contains(&t.as_str()))
        .collect();
    assert_eq!(panels, ["miss_rate", "success_rate"], "{texts:?}");

    let (_, out) = sweep_tiny(
        "sweep-bad-metric",
        &[
            "--set",
            "defaults.timing.compute.ms=20",
            "--metrics",
            "misses",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--metrics misses: no such metric (known: success_rate"),
        "{err}"
    );
}

/// The names of sweep.csv's metrics.
const METRIC_NAMES: [&str; 24] = [
    "success_rate",
    "collisions_total",
    "collided",
    "makespan",
    "path_length_ratio",
    "min_clearance",
    "time_to_goal",
    "agents_lost",
    "ticks",
    "spl",
    "flowtime",
    "collisions_per_robot_km",
    "deadlocks",
    "time_not_moving",
    "ttc_min",
    "time_intimate",
    "time_personal",
    "time_social",
    "jerk_mean",
    "path_irregularity",
    "heading_change",
    "stuck_time",
    "miss_rate",
    "predicted_missing",
];
