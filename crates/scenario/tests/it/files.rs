//! The shipped scenario files load, and a resolved scenario survives JSON.

use crate::common::*;
use mrsim_scenario::{Mode, Scenario, demo, load};
use std::path::Path;

fn shipped(name: &str) -> mrsim_scenario::Loaded {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    match load(&path) {
        Ok(l) => l,
        Err(e) => panic!("{e}"),
    }
}

fn overlap_free(s: &Scenario) {
    for (i, a) in s.robots.iter().enumerate() {
        for b in &s.robots[..i] {
            let d = (a.start[0] - b.start[0]).hypot(a.start[1] - b.start[1]);
            assert!(d >= a.radius + b.radius, "{} and {}", a.name, b.name);
        }
    }
}

#[test]
fn the_demo_is_eight_robots_swapping_across_a_circle_in_realtime() {
    let l = demo();
    let s = &l.scenario;
    assert_eq!(s.robots.len(), 8);
    assert_eq!(s.world.mode, Mode::Realtime);
    assert_eq!(s.world.dt, 0.05);
    assert!(!s.description.trim().is_empty());
    for r in &s.robots {
        assert!(
            (r.start[0].hypot(r.start[1]) - 4.0).abs() < 1e-5,
            "{}",
            r.name
        );
        assert!((r.start[0] + r.goal[0]).abs() < 1e-9 && (r.start[1] + r.goal[1]).abs() < 1e-9);
        assert_eq!(r.radius, 0.2);
        assert_eq!(r.max_speed, 1.0);
    }
    overlap_free(s);
    assert_eq!(shipped("demo.toml").scenario, l.scenario);
}

#[test]
fn crossing_is_two_streams_of_four_at_right_angles_in_lockstep() {
    let s = shipped("crossing.toml").scenario;
    assert_eq!(s.world.mode, Mode::Lockstep);
    assert_eq!(s.robots.len(), 8);
    let along_x = s
        .robots
        .iter()
        .filter(|r| r.start[1] == 0.0 && r.goal[1] == 0.0 && r.goal[0] > r.start[0])
        .count();
    let along_y = s
        .robots
        .iter()
        .filter(|r| r.start[0] == 0.0 && r.goal[0] == 0.0 && r.goal[1] > r.start[1])
        .count();
    assert_eq!((along_x, along_y), (4, 4));
    assert!(!s.description.trim().is_empty());
    overlap_free(&s);
}

#[test]
fn corridor_is_two_walls_and_three_robots_each_way_in_lockstep() {
    let s = shipped("corridor.toml").scenario;
    assert_eq!(s.world.mode, Mode::Lockstep);
    assert_eq!(s.walls.len(), 2);
    let right = s.robots.iter().filter(|r| r.goal[0] > r.start[0]).count();
    let left = s.robots.iter().filter(|r| r.goal[0] < r.start[0]).count();
    assert_eq!((right, left), (3, 3));
    assert!(!s.description.trim().is_empty());
    overlap_free(&s);
}

#[test]
fn a_resolved_scenario_survives_json_both_ways() {
    let rich = format!(
        "{}\n[generate]\nkind = \"random\"\ncount = 5\nradius = 4.0\nparams = {{ gain = 2, shape = \"ellipse\", on = true, speeds = [0.1, 0.2], pts = [[0, 1], [2, 3]], empty = [] }}\n",
        with(
            BASE,
            "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
            "motion = { model = \"intentional\", behavior = \"goal\", goal = [1, 1], points = [[0, 0]], max_speed = 1, max_accel = 2 }",
        )
    );
    for l in [
        demo(),
        shipped("crossing.toml"),
        shipped("corridor.toml"),
        accept(&rich),
    ] {
        let json = serde_json::to_string(&l.scenario).unwrap();
        let back: Scenario = serde_json::from_str(&json).unwrap();
        assert_eq!(back, l.scenario);
    }
}
