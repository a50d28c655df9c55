//! `[generate]`: every kind gives robots that do not overlap.

use crate::common::*;
use mrsim_scenario::{RobotSpec, Scenario};

fn generated(kind: &str, count: usize, extra: &str) -> Scenario {
    let src = format!(
        "name = \"g\"\n[world]\nseed = 7\n[defaults]\nradius = 0.2\n\n[generate]\nkind = \"{kind}\"\ncount = {count}\n{extra}\n"
    );
    accept(&src).scenario
}

fn d(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn no_overlap(robots: &[RobotSpec]) {
    for (i, a) in robots.iter().enumerate() {
        for b in &robots[..i] {
            assert!(
                d(a.start, b.start) >= a.radius + b.radius,
                "starts of {} and {}",
                a.name,
                b.name
            );
            assert!(
                d(a.goal, b.goal) >= a.radius + b.radius,
                "goals of {} and {}",
                a.name,
                b.name
            );
        }
    }
}

#[test]
fn circle_robots_sit_evenly_and_go_to_the_antipode() {
    let s = generated("circle", 16, "radius = 5.0\ncenter = [1.0, 2.0]");
    assert_eq!(s.robots.len(), 16);
    no_overlap(&s.robots);
    for r in &s.robots {
        assert!((d(r.start, [1.0, 2.0]) - 5.0).abs() < 1e-9);
        assert!(
            d(
                [
                    (r.start[0] + r.goal[0]) / 2.0,
                    (r.start[1] + r.goal[1]) / 2.0
                ],
                [1.0, 2.0]
            ) < 1e-9
        );
    }
    let gap = d(s.robots[0].start, s.robots[1].start);
    assert!((gap - 10.0 * (std::f64::consts::PI / 16.0).sin()).abs() < 1e-9);
}

#[test]
fn crossing_is_half_going_along_x_and_half_along_y() {
    let s = generated("crossing", 7, "radius = 3.0");
    no_overlap(&s.robots);
    let x: Vec<_> = s
        .robots
        .iter()
        .filter(|r| r.start[1] == 0.0 && r.goal[0] > r.start[0])
        .collect();
    let y: Vec<_> = s
        .robots
        .iter()
        .filter(|r| r.start[0] == 0.0 && r.goal[1] > r.start[1])
        .collect();
    assert_eq!((x.len(), y.len()), (4, 3));
    // Every path crosses the centre.
    assert!(x.iter().all(|r| r.start[0] < 0.0 && r.goal[0] > 0.0));
    assert!(y.iter().all(|r| r.start[1] < 0.0 && r.goal[1] > 0.0));
}

#[test]
fn corridor_groups_enter_from_opposite_ends_and_swap() {
    let s = generated("corridor", 6, "radius = 4.0");
    no_overlap(&s.robots);
    let right: Vec<_> = s
        .robots
        .iter()
        .filter(|r| r.start[0] < -4.0 + 1e-9 && r.goal[0] >= 4.0)
        .collect();
    let left: Vec<_> = s
        .robots
        .iter()
        .filter(|r| r.start[0] > 4.0 - 1e-9 && r.goal[0] <= -4.0)
        .collect();
    assert_eq!((right.len(), left.len()), (3, 3));
    let mut starts: Vec<f64> = s.robots.iter().map(|r| r.start[0]).collect();
    let mut goals: Vec<f64> = s.robots.iter().map(|r| r.goal[0]).collect();
    starts.sort_by(f64::total_cmp);
    goals.sort_by(f64::total_cmp);
    assert_eq!(starts, goals, "each group ends where the other started");
}

#[test]
fn random_robots_stay_inside_and_apart_and_follow_the_seed() {
    let s = generated("random", 30, "radius = 4.0");
    no_overlap(&s.robots);
    for r in &s.robots {
        for p in [r.start, r.goal] {
            assert!(p[0].abs() <= 4.0 - 0.2 && p[1].abs() <= 4.0 - 0.2, "{p:?}");
        }
    }
    assert_eq!(generated("random", 30, "radius = 4.0"), s);
    let other = accept("name = \"g\"\n[world]\nseed = 8\n[defaults]\nradius = 0.2\n\n[generate]\nkind = \"random\"\ncount = 30\nradius = 4.0\n")
    .scenario;
    assert_ne!(other.robots[0].start, s.robots[0].start);
}

#[test]
fn random_robots_use_the_arena_when_there_is_one() {
    let src = "[world]\narena = { min = [10, 10], max = [14, 12] }\n[generate]\nkind = \"random\"\ncount = 4\n";
    let s = accept(src).scenario;
    for r in &s.robots {
        assert!(
            r.start[0] >= 10.25
                && r.start[0] <= 13.75
                && r.start[1] >= 10.25
                && r.start[1] <= 11.75
        );
    }
    no_overlap(&s.robots);
}

#[test]
fn random_robots_avoid_the_files_robots() {
    let src = "[[robot]]\nname = \"big\"\nstart = [0, 0]\ngoal = [1, 1]\nradius = 2.0\n[generate]\nkind = \"random\"\ncount = 10\nradius = 4\n";
    let s = accept(src).scenario;
    for r in &s.robots[1..] {
        assert!(d(r.start, [0.0, 0.0]) >= 2.0 + r.radius);
    }
}

#[test]
fn too_many_random_robots_for_the_area_are_refused_at_the_generate_table() {
    let src = "[generate]\nkind = \"random\"\ncount = 50\nradius = 0.5\n";
    refused_at(src, "[generate]", "could not place 50 robots");
}

#[test]
fn names_are_padded_to_the_count_and_take_the_prefix() {
    let s = generated("circle", 5, "radius = 5.0");
    let names: Vec<&str> = s.robots.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["g00", "g01", "g02", "g03", "g04"]);
    let s = generated("circle", 101, "radius = 40.0\nname_prefix = \"bot\"");
    assert_eq!(
        (s.robots[0].name.as_str(), s.robots[100].name.as_str()),
        ("bot000", "bot100")
    );
}

#[test]
fn generated_robots_come_after_the_files_robots_and_take_the_defaults() {
    let src = "[defaults]\nmass = 4.0\n[[robot]]\nname = \"first\"\nstart = [0, 0]\ngoal = [1, 0]\n[generate]\nkind = \"circle\"\ncount = 3\nradius = 5\n";
    let s = accept(src).scenario;
    assert_eq!(s.robots[0].name, "first");
    assert!(
        s.robots[1..]
            .iter()
            .all(|r| r.mass == 4.0 && r.name.starts_with('g'))
    );
}

#[test]
fn jitter_moves_each_start_by_at_most_its_value_reproducibly_and_keeps_goals() {
    let exact = generated("circle", 16, "radius = 5.0");
    let jittered = generated("circle", 16, "radius = 5.0\njitter = 0.1");
    let again = generated("circle", 16, "radius = 5.0\njitter = 0.1");
    let mut moved = 0;
    for ((e, j), a) in exact.robots.iter().zip(&jittered.robots).zip(&again.robots) {
        assert_eq!(j.start, a.start, "same seed, same starts");
        assert_eq!(e.goal, j.goal, "goals stay");
        let shift = d(e.start, j.start);
        assert!(shift <= 0.1 + 1e-12, "{} moved {shift}", e.name);
        moved += usize::from(shift > 0.0);
    }
    assert_eq!(moved, 16);
    // Directions are spread: the mean shift is far from any single direction.
    let mean = jittered
        .robots
        .iter()
        .zip(&exact.robots)
        .fold([0.0, 0.0], |m, (j, e)| {
            [
                m[0] + j.start[0] - e.start[0],
                m[1] + j.start[1] - e.start[1],
            ]
        });
    assert!(mean[0].hypot(mean[1]) / 16.0 < 0.05);
    no_overlap(&jittered.robots);
}

#[test]
fn a_negative_jitter_is_refused_with_its_line() {
    let src = "name = \"g\"\n[defaults]\nradius = 0.2\n[generate]\nkind = \"circle\"\ncount = 4\nradius = 5.0\njitter = -0.1\n";
    refused_at(src, "jitter = -0.1", "jitter must be >= 0");
}
