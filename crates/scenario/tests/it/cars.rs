//! Car-like robots (`kinematics = "ackermann"`) and goal headings: the keys
//! read with their defaults, bad values and misplaced keys refused at their
//! line.

use crate::common::*;
use mrsim_scenario::{Ackermann, GoalHeading, Kinematics};

/// BASE with robot r1 a car given `keys` (a 4.6 x 1.6 m body, far from r0).
fn car(keys: &str) -> String {
    let src = with(
        BASE,
        "start = [0.0, 3.0]\ngoal = [5.0, 3.0]\nradius = 0.3",
        &format!(
            "start = [0.0, 4.0]\ngoal = [5.0, 4.0]\n\
             shape = {{ kind = \"rectangle\", length = 4.6, width = 1.6 }}\n{keys}"
        ),
    );
    with(&src, "[-8.0, 8.0], [8.0, 8.0]", "[-8.0, 9.0], [8.0, 9.0]")
}

#[test]
fn a_car_is_read_with_its_steering_defaults_and_its_minimum_radius() {
    let l = accept(&car("kinematics = \"ackermann\"\nwheelbase = 3.0"));
    let r = &l.scenario.robots[1];
    assert_eq!(r.kinematics, Kinematics::Ackermann);
    let a = r.ackermann.expect("a car");
    assert_eq!(a.wheelbase, 3.0);
    assert!((a.max_steering - 30f64.to_radians()).abs() < 1e-15);
    assert!((a.max_steering_rate - 60f64.to_radians()).abs() < 1e-15);
    assert_eq!(a.max_reverse_speed, 0.0);
    assert!((a.min_turning_radius() - 3.0 / 30f64.to_radians().tan()).abs() < 1e-12);
    // It faces its goal and its headings go to trajectory.csv; the other
    // robot is no car.
    assert_eq!(r.start_heading(), 0.0);
    assert!(l.scenario.has_headings());
    assert_eq!(l.scenario.robots[0].ackermann, None);
}

#[test]
fn every_car_key_is_taken_from_the_robot_or_its_defaults() {
    let src = car(
        "kinematics = \"ackermann\"\nwheelbase = 2.5\nmax_steering_deg = 35\n\
         max_reverse_speed = 1.5",
    );
    let src = with(&src, "mass = 1.0", "mass = 1.0\nmax_steering_rate_deg = 90");
    let l = accept(&src);
    let a = l.scenario.robots[1].ackermann.expect("a car");
    assert_eq!(
        a,
        Ackermann {
            wheelbase: 2.5,
            max_steering: 35f64.to_radians(),
            max_steering_rate: 90f64.to_radians(),
            max_reverse_speed: 1.5,
        }
    );
    // The holonomic r0 ignores the default meant for the car.
    assert_eq!(l.scenario.robots[0].ackermann, None);
    // The car's keys survive scenario.json; a disc's JSON has none of them.
    let json = serde_json::to_string(&l.scenario).expect("json");
    let back: mrsim_scenario::Scenario = serde_json::from_str(&json).expect("back");
    assert_eq!(back, l.scenario);
    let r0 = serde_json::to_string(&l.scenario.robots[0]).expect("json");
    assert!(
        !r0.contains("ackermann") && !r0.contains("goal_heading"),
        "{r0}"
    );
}

#[test]
fn bad_car_keys_are_refused_at_their_line() {
    let ack = "kinematics = \"ackermann\"\n";
    for (keys, needle, words) in [
        ("wheelbase = 0.0", "wheelbase", "wheelbase must be > 0"),
        (
            "wheelbase = 3.0\nmax_steering_deg = 90",
            "max_steering_deg",
            "max_steering_deg must be in (0, 90) degrees",
        ),
        (
            "wheelbase = 3.0\nmax_steering_deg = 0",
            "max_steering_deg",
            "must be in (0, 90)",
        ),
        (
            "wheelbase = 3.0\nmax_steering_rate_deg = 0",
            "max_steering_rate_deg",
            "max_steering_rate_deg must be > 0",
        ),
        (
            "wheelbase = 3.0\nmax_reverse_speed = -1",
            "max_reverse_speed",
            "max_reverse_speed must be >= 0",
        ),
        ("max_speed = 2.0", "kinematics", "needs `wheelbase`"),
    ] {
        refused_at(&car(&format!("{ack}{keys}")), needle, words);
    }
}

#[test]
fn a_car_key_on_another_drive_is_refused_at_its_line() {
    for (kinematics, key) in [
        ("", "wheelbase = 3.0"),
        ("kinematics = \"unicycle\"\n", "max_steering_deg = 20"),
        ("kinematics = \"holonomic\"\n", "max_reverse_speed = 1.0"),
        ("", "max_steering_rate_deg = 20"),
    ] {
        let name = key.split(' ').next().expect("a key");
        refused_at(
            &car(&format!("{kinematics}{key}")),
            key,
            &format!("{name} is a car's key"),
        );
    }
    // In [defaults] it is for the cars of the file: refused when there is
    // none.
    let src = with(BASE, "mass = 1.0", "mass = 1.0\nwheelbase = 3.0");
    refused_at(&src, "wheelbase", "no robot is a car");
}

#[test]
fn a_goal_heading_is_read_with_its_tolerance() {
    let l = accept(&car(
        "kinematics = \"ackermann\"\nwheelbase = 3.0\ngoal_heading_deg = 90",
    ));
    let r = &l.scenario.robots[1];
    let g = r.goal_heading.expect("a goal heading");
    assert!((g.heading - 90f64.to_radians()).abs() < 1e-15);
    assert!((g.tolerance - 10f64.to_radians()).abs() < 1e-15);
    // At the goal: arrived only facing within 10 degrees of +y, either
    // side, whichever way the angle is written.
    assert!(!r.at_goal(r.goal, 0.0));
    assert!(r.at_goal(r.goal, 95f64.to_radians()));
    assert!(r.at_goal(r.goal, (85f64 - 360.0).to_radians()));
    assert!(!r.at_goal(r.goal, 101f64.to_radians()));
    // Facing right but off the goal: not arrived either.
    assert!(!r.at_goal([r.goal[0] + 0.2, r.goal[1]], 90f64.to_radians()));
    let g = GoalHeading {
        heading: 179f64.to_radians(),
        tolerance: 5f64.to_radians(),
    };
    assert!(g.holds(-178f64.to_radians()));
}

#[test]
fn bad_goal_headings_are_refused_at_their_line() {
    let src = car("goal_heading_tolerance_deg = 5");
    refused_at(&src, "goal_heading_tolerance_deg", "needs goal_heading_deg");
    let src =
        car("kinematics = \"unicycle\"\ngoal_heading_deg = 45\ngoal_heading_tolerance_deg = 0");
    refused_at(
        &src,
        "goal_heading_tolerance_deg",
        "must be in (0, 180] degrees",
    );
    let src = car("kinematics = \"unicycle\"\ngoal_heading_deg = inf");
    refused_at(&src, "goal_heading_deg", "must be a finite number");
    // A holonomic robot never turns: a heading other than 0 (within the
    // tolerance) can never be met.
    let src = car("goal_heading_deg = 45");
    refused_at(&src, "goal_heading_deg", "can never be met");
    accept(&car("goal_heading_deg = 5"));
    // A default tolerance with no goal heading in the file.
    let src = with(
        BASE,
        "mass = 1.0",
        "mass = 1.0\ngoal_heading_tolerance_deg = 5",
    );
    refused_at(&src, "goal_heading_tolerance_deg", "no robot has one");
}
