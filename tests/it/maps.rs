//! Maps end to end: the shipped office runs with every robot at its goal
//! and none through a map wall; a robot aimed through a wall is stopped by
//! it; bad maps are refused with the file and the reason, exit status 2.

use crate::common::*;
use std::path::{Path, PathBuf};

/// Runs `scenario` in lockstep in-process; returns the run folder.
fn run_lockstep(scenario: &Path, tag: &str) -> PathBuf {
    let out = fresh_dir(tag).join("out");
    let o = run(
        scenario,
        &out,
        &run_id(tag),
        &["--mode", "lockstep", "--transport", "inproc"],
    );
    assert_ok(&o);
    out
}

/// Each robot's smallest clearance (distance minus radius) to the map's
/// walls over the whole run, from trajectory.csv and the map traced again.
fn map_clearances(scenario: &Path, out: &Path) -> Vec<(String, f64)> {
    let s = mrsim_scenario::load(scenario).expect("scenario").scenario;
    let info = s.map.as_ref().expect("the scenario has a map");
    assert!(info.walls > 0);
    let walls: Vec<[[f64; 2]; 2]> = s.walls[s.walls.len() - info.walls..]
        .iter()
        .map(|w| w.segment)
        .collect();
    let rows = trajectory(out);
    s.robots
        .iter()
        .map(|r| {
            let track = track(&rows, &r.name);
            assert!(!track.is_empty(), "{} has no rows", r.name);
            let clear = track
                .iter()
                .flat_map(|row| walls.iter().map(|w| segment_distance([row.x, row.y], *w)))
                .fold(f64::INFINITY, f64::min)
                - r.radius;
            (r.name.clone(), clear)
        })
        .collect()
}

#[test]
fn the_office_team_reaches_every_goal_without_passing_through_a_map_wall() {
    let scenario = root().join("scenarios/maps/office.toml");
    let out = run_lockstep(&scenario, "office");
    let m = metrics(&out);
    let robots = m["robots"].as_object().expect("robots");
    assert_eq!(robots.len(), 6);
    for (name, r) in robots {
        assert_eq!(r["reached_goal"], true, "{name} did not reach its goal");
    }
    for (name, clear) in map_clearances(&scenario, &out) {
        assert!(clear >= -1e-3, "{name} came {clear} m into a map wall");
    }
    // The map's walls are in the run's scenario.json, for the plots and the
    // replay.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("scenario.json")).unwrap()).unwrap();
    let walls = json["map"]["walls"].as_u64().expect("map.walls");
    assert!(json["walls"].as_array().unwrap().len() as u64 >= walls);
}

#[test]
fn a_robot_aimed_through_a_map_wall_is_stopped_by_it() {
    let dir = fresh_dir("through");
    let office = root().join("scenarios/maps/office.yaml");
    let file = dir.join("through.toml");
    // Homing from one upper room to the next, straight at the partition
    // between them (x = -6.1..-5.9).
    let src = format!(
        "[world]\nduration = 12.0\n[map]\nfile = {:?}\n[[robot]]\nname = \"h\"\nplanner = \"homing\"\nstart = [-9.0, 4.0]\ngoal = [-3.0, 4.0]\n",
        office.display().to_string()
    );
    std::fs::write(&file, src).unwrap();
    let out = run_lockstep(&file, "through");
    assert_eq!(metrics(&out)["robots"]["h"]["reached_goal"], false);
    let rows = trajectory(&out);
    let max_x = track(&rows, "h")
        .iter()
        .map(|r| r.x)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(max_x < -6.1 - 0.25 + 1e-3, "h got to x = {max_x}");
    assert!(
        max_x > -6.1 - 0.25 - 0.05,
        "h never reached the wall: x <= {max_x}"
    );
    for (name, clear) in map_clearances(&file, &out) {
        assert!(clear >= -1e-3, "{name} came {clear} m into a map wall");
    }
}

const YAML: &str = "image: m.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

/// A 4 m x 2 m room (walls 0.1 m thick all round) as m.pgm.
fn room_pgm() -> Vec<u8> {
    let (w, h) = (40, 20);
    let mut out = format!("P5\n{w} {h}\n255\n").into_bytes();
    for y in 0..h {
        for x in 0..w {
            let wall = x == 0 || y == 0 || x == w - 1 || y == h - 1;
            out.push(if wall { 0 } else { 254 });
        }
    }
    out
}

const ROBOT: &str = "[[robot]]\nname = \"r\"\nstart = [1.0, 1.0]\ngoal = [3.0, 1.0]\n";

/// Writes a scenario with `[map] file = "m.yaml"` and `robot`, the map's
/// YAML and image, and runs it: it must be refused with exit status 2 and
/// a message holding each of `words`, nothing run.
fn refused(tag: &str, yaml: &str, image: Option<&[u8]>, robot: &str, words: &[&str]) {
    let dir = fresh_dir(tag);
    std::fs::write(dir.join("m.yaml"), yaml).unwrap();
    if let Some(img) = image {
        std::fs::write(dir.join("m.pgm"), img).unwrap();
    }
    let file = dir.join("s.toml");
    std::fs::write(&file, format!("[map]\nfile = \"m.yaml\"\n\n{robot}")).unwrap();
    let stderr = run_refused(&file);
    for w in words {
        assert!(stderr.contains(w), "{tag}: expected `{w}` in: {stderr}");
    }
}

#[test]
fn the_room_map_runs_so_the_refusals_below_are_the_maps_faults() {
    let dir = fresh_dir("room");
    std::fs::write(dir.join("m.yaml"), YAML).unwrap();
    std::fs::write(dir.join("m.pgm"), room_pgm()).unwrap();
    let file = dir.join("s.toml");
    std::fs::write(&file, format!("[map]\nfile = \"m.yaml\"\n\n{ROBOT}")).unwrap();
    run_lockstep(&file, "room");
}

#[test]
fn a_map_whose_image_is_missing_is_refused() {
    refused("no-image", YAML, None, ROBOT, &["m.pgm", "No such file"]);
}

#[test]
fn a_map_with_a_bad_pgm_header_is_refused() {
    refused(
        "header",
        YAML,
        Some(b"P5\n40 twenty\n255\n"),
        ROBOT,
        &["m.pgm", "bad PGM header"],
    );
}

#[test]
fn a_map_with_resolution_zero_is_refused() {
    let yaml = YAML.replace("resolution: 0.1", "resolution: 0");
    refused(
        "res0",
        &yaml,
        Some(&room_pgm()),
        ROBOT,
        &[
            "s.toml:2",
            "m.yaml",
            "resolution must be a finite number > 0",
        ],
    );
}

#[test]
fn a_robot_starting_inside_a_map_wall_is_refused() {
    let robot = ROBOT.replace("start = [1.0, 1.0]", "start = [0.05, 1.0]");
    refused(
        "start-wall",
        YAML,
        Some(&room_pgm()),
        &robot,
        &[
            "s.toml:6",
            "robot `r`",
            "start [0.05, 1] is inside a wall of map",
            "m.yaml",
        ],
    );
}

#[test]
fn a_robot_whose_goal_is_inside_a_map_wall_is_refused() {
    let robot = ROBOT.replace("goal = [3.0, 1.0]", "goal = [3.95, 1.0]");
    refused(
        "goal-wall",
        YAML,
        Some(&room_pgm()),
        &robot,
        &[
            "s.toml:7",
            "robot `r`",
            "goal [3.95, 1] is inside a wall of map",
            "m.yaml",
        ],
    );
}

#[test]
fn a_map_whose_origin_is_nan_is_refused() {
    let yaml = YAML.replace("origin: [0.0, 0.0, 0.0]", "origin: [.nan, 0.0, 0.0]");
    refused(
        "origin-nan",
        &yaml,
        Some(&room_pgm()),
        ROBOT,
        &["m.yaml", "origin must be finite numbers, got [NaN, 0, 0]"],
    );
}

#[test]
fn a_map_whose_thresholds_leave_zero_to_one_is_refused() {
    for (tag, from, to) in [
        (
            "occ-above-1",
            "occupied_thresh: 0.65",
            "occupied_thresh: 1.5",
        ),
        ("free-below-0", "free_thresh: 0.196", "free_thresh: -0.1"),
        ("free-above-occ", "free_thresh: 0.196", "free_thresh: 0.9"),
    ] {
        refused(
            tag,
            &YAML.replace(from, to),
            Some(&room_pgm()),
            ROBOT,
            &[
                "m.yaml",
                "thresholds must satisfy 0 <= free_thresh <= occupied_thresh <= 1",
            ],
        );
    }
}

#[test]
fn a_map_whose_image_is_an_empty_file_is_refused() {
    refused(
        "empty-image",
        YAML,
        Some(b""),
        ROBOT,
        &["m.pgm", "the image file is empty"],
    );
}

#[test]
fn a_map_with_a_pixel_above_its_maxval_is_refused() {
    // maxval 100, and one pixel 200.
    let (w, h) = (40, 20);
    let mut img = format!("P5\n{w} {h}\n100\n").into_bytes();
    img.extend(std::iter::repeat_n(90u8, w * h));
    let last = img.len() - 5;
    img[last] = 200;
    refused(
        "above-maxval",
        YAML,
        Some(&img),
        ROBOT,
        &[
            "m.pgm",
            "the PGM has a pixel value 200 above its maxval 100",
        ],
    );
}

#[test]
fn an_obstacle_starting_inside_a_map_wall_is_refused() {
    let scene = format!(
        "{ROBOT}\n[[obstacle]]\nname = \"pillar\"\nstart = [0.05, 1.5]\nradius = 0.2\nmotion = {{ model = \"static\" }}\n"
    );
    refused(
        "obstacle-wall",
        YAML,
        Some(&room_pgm()),
        &scene,
        &[
            "obstacle `pillar`",
            "start [0.05, 1.5] is inside a wall of map",
            "m.yaml",
        ],
    );
}
