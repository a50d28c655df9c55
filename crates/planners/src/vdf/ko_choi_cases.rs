//! Ko & Choi section 5.1, cases 1-3, built from the same numbers as
//! scenarios/papers/ko-choi-case-{1,2,3}.toml and run in the testkit.

use super::*;
use crate::testkit::Sim;

/// The robot speed limit chosen for the scenario files (cm/s).
const MAX_SPEED: f64 = 23.3;
const START: [f64; 2] = [0.0, 2.0];
const GOAL: [f64; 2] = [80.0, -40.0];
const OBSTACLE_START: [f64; 2] = [55.0, 3.0];
const OBSTACLE_RADIUS: f64 = 5.0;
const CASES: [(&str, [f64; 2]); 3] = [
    (
        include_str!("../../../../scenarios/papers/ko-choi-case-1.toml"),
        [-5.0, -10.0],
    ),
    (
        include_str!("../../../../scenarios/papers/ko-choi-case-2.toml"),
        [-5.0, -11.0],
    ),
    (
        include_str!("../../../../scenarios/papers/ko-choi-case-3.toml"),
        [-5.0, -14.0],
    ),
];

struct Outcome {
    /// Where the robot first crosses the obstacle's line: its offset
    /// along the obstacle's motion from the obstacle's centre (> 0:
    /// in front of it, i.e. ahead).
    crossing_offset: f64,
    /// Sign changes of the along-track velocity before that crossing.
    reversals: usize,
    min_clearance: f64,
    /// Distance to the goal, 10 s to 60 s.
    goal_distance: (f64, f64),
    goal_test_held: bool,
}

fn run(max_speed: f64, v_o: [f64; 2]) -> Outcome {
    let mut sim = Sim::new(0.1, 10);
    let goal = Vec2::from(GOAL);
    let start = Vec2::from(START);
    let r = sim.add_robot(
        Box::new(Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0)),
        start,
        goal,
        0.0,
        0.1,
        0.0,
        max_speed,
        500.0,
    );
    let v_o = Vec2::from(v_o);
    sim.add_obstacle(Vec2::from(OBSTACLE_START), v_o, OBSTACLE_RADIUS);
    let dir = v_o.normalize();
    let normal = Vec2::new(-dir.y, dir.x);
    let track = (goal - start).normalize();
    let mut out = Outcome {
        crossing_offset: f64::NAN,
        reversals: 0,
        min_clearance: f64::INFINITY,
        goal_distance: (f64::INFINITY, 0.0),
        goal_test_held: false,
    };
    let (mut side_prev, mut along_prev, mut within) = (f64::NAN, 0.0, 0);
    for tick in 1..=600 {
        sim.step();
        out.min_clearance = out.min_clearance.min(sim.clearance(r));
        let s = sim.robots[r].state;
        let rel = s.position - sim.obstacles[0].position;
        let side = rel.dot(&normal);
        if out.crossing_offset.is_nan() {
            if side * side_prev < 0.0 {
                out.crossing_offset = rel.dot(&dir);
            }
            let along = s.velocity.dot(&track);
            if along * along_prev < 0.0 {
                out.reversals += 1;
            }
            if along != 0.0 {
                along_prev = along;
            }
        }
        side_prev = side;
        let d = (s.position - goal).norm();
        within = if d <= 1.0 { within + 1 } else { 0 };
        out.goal_test_held |= within > 3;
        if tick >= 100 {
            out.goal_distance = (out.goal_distance.0.min(d), out.goal_distance.1.max(d));
        }
    }
    out
}

#[test]
fn scenario_files_carry_the_numbers_these_tests_use() {
    for (text, v_o) in CASES {
        assert!(text.contains(&format!("max_speed = {MAX_SPEED}")));
        assert!(text.contains(&format!("velocity = [{:?}, {:?}]", v_o[0], v_o[1])));
        assert!(text.contains("start = [0.0, 2.0]") && text.contains("goal = [80.0, -40.0]"));
        assert!(text.contains("start = [55.0, 3.0]") && text.contains("radius = 5.0"));
        assert!(text.contains("alpha = 5.0, beta = 5.0, eta = 1000.0, zeta = 2.0, eps_vd = 40.0"));
        assert!(text.contains("mass = 0.1") && text.contains("max_accel = 500.0"));
        assert!(text.contains("length_unit = \"cm\""));
    }
}

#[test]
fn case_1_goes_ahead_of_the_obstacle() {
    let o = run(MAX_SPEED, CASES[0].1);
    assert!(o.crossing_offset > 0.0, "{}", o.crossing_offset);
    assert!(o.min_clearance > 0.0);
}

#[test]
fn case_2_moves_back_and_forth_then_takes_the_back_track() {
    let o = run(MAX_SPEED, CASES[1].1);
    assert!(o.crossing_offset < 0.0, "{}", o.crossing_offset);
    assert!(o.reversals >= 4, "{}", o.reversals);
    assert!(o.min_clearance > 0.0);
}

#[test]
fn case_3_detours_slightly_to_the_back() {
    let o = run(MAX_SPEED, CASES[2].1);
    assert!(o.crossing_offset < 0.0, "{}", o.crossing_offset);
    assert_eq!(o.reversals, 0);
    assert!(o.min_clearance > 0.0);
}

#[test]
fn outcomes_hold_across_the_reported_band_and_fail_outside_it() {
    let ok = |v: f64| {
        let (a, b, c) = (run(v, CASES[0].1), run(v, CASES[1].1), run(v, CASES[2].1));
        a.crossing_offset > 0.0
            && b.crossing_offset < 0.0
            && b.reversals >= 2
            && c.crossing_offset < 0.0
            && c.reversals == 0
            && [a.min_clearance, b.min_clearance, c.min_clearance]
                .iter()
                .all(|m| *m > 0.0)
    };
    for v in [21.1, 22.0, 22.4, 23.0, 23.7] {
        assert!(ok(v), "{v} should reproduce the paper");
    }
    for v in [20.0, 21.0, 23.8, 25.0] {
        assert!(!ok(v), "{v} should not");
    }
}

#[test]
fn as_printed_the_robot_never_settles_at_the_goal() {
    for (_, v_o) in CASES {
        let o = run(MAX_SPEED, v_o);
        assert!(!o.goal_test_held);
        assert!(o.goal_distance.0 > 5.0, "{}", o.goal_distance.0);
        assert!(o.goal_distance.1 < 200.0, "{}", o.goal_distance.1);
    }
}
