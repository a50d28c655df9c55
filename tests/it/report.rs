//! `mrsim report DIR` on a finished run, a run cut short, and folders that
//! are not runs.

use crate::common::*;
use std::path::Path;

fn report(dir: &Path) -> std::process::Output {
    mrsim()
        .arg("report")
        .arg(dir)
        .output()
        .expect("start mrsim")
}

fn finished_run(tag: &str) -> std::path::PathBuf {
    let dir = fresh_dir(tag);
    let out = dir.join("run");
    let id = run_id(tag);
    let o = run(
        &root().join("scenarios/crossing.toml"),
        &out,
        &id,
        &["--quiet"],
    );
    assert_ok(&o);
    assert_clean(&id);
    out
}

#[test]
fn a_run_cut_short_without_metrics_and_with_a_cut_last_line_is_still_drawn() {
    let out = finished_run("rep-cut");
    for f in ["metrics.json", "plot.svg", "plot.png", "replay.html"] {
        std::fs::remove_file(out.join(f)).expect(f);
    }
    // A world killed mid-write: the trajectory ends in half a row.
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory");
    let cut = traj.len() - traj.lines().last().expect("a row").len() / 2 - 1;
    std::fs::write(out.join("trajectory.csv"), &traj[..cut]).expect("cut");

    let o = report(&out);
    assert_ok(&o);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("no metrics.json"), "{stderr}");
    for f in ["plot.svg", "plot.png", "replay.html"] {
        assert!(out.join(f).is_file(), "{f} not drawn");
    }
}

#[test]
fn a_folder_that_is_not_a_run_is_refused_with_the_missing_file_named() {
    let dir = fresh_dir("rep-empty");
    std::fs::write(dir.join("notes.txt"), "not a run").expect("write");
    let o = report(&dir);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("scenario.json: missing"), "{stderr}");
    assert!(!dir.join("plot.svg").exists());

    let o = report(&dir.join("notes.txt"));
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a run folder"));

    let o = report(&dir.join("nowhere"));
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_malformed_trajectory_row_is_refused_with_its_line() {
    let out = finished_run("rep-bad");
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory");
    let mut lines: Vec<&str> = traj.lines().collect();
    lines[4] = "3,0.3,a0,robot,1,nan-ish,0,0";
    std::fs::write(out.join("trajectory.csv"), lines.join("\n") + "\n").expect("write");
    let o = report(&out);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("trajectory.csv:5"), "{stderr}");
}
