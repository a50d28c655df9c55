//! Car-like robots end to end: a holonomic planner (orca) drives two cars
//! past each other through the tracking controller in an in-process run,
//! the world's goal test asks a car's heading as well as its place, a car
//! with `route = "shortest"` reverses into a parking bay by its route, and
//! a car goal no route reaches is refused at load.

use crate::common::*;
use mrsim::{InProcess, Registry, ScenarioSource};
use std::path::Path;
use std::sync::Arc;

/// One row of a car's trajectory: tick, x, y, theta.
type Pose = (u64, f64, f64, f64);

/// The poses of `body` in trajectory.csv (which has `theta` for cars).
fn poses(dir: &Path, body: &str) -> Vec<Pose> {
    let text = std::fs::read_to_string(dir.join("trajectory.csv")).expect("trajectory.csv");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("tick,time,body,kind,x,y,vx,vy,theta"));
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[2] == body)
        .map(|f| {
            let n = |i: usize| f[i].parse::<f64>().expect("number");
            (f[0].parse().expect("tick"), n(4), n(5), n(8))
        })
        .collect()
}

#[test]
fn orca_drives_two_cars_past_each_other_through_the_tracking_controller() {
    // examples/cars.toml: two of ir-sim's cars (4.6 x 1.6 m, wheelbase 3
    // m) at the two ends of a road, each driving to the other's start,
    // half a metre off the other's line: orca must take them round each
    // other.
    let out = fresh_dir("car-swap");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(root().join("examples/cars.toml")),
            ..Default::default()
        },
        registry: Arc::new(Registry::builtin()),
        out: Some(out.join("run")),
        render: false,
        plan_timeout: None,
    })
    .expect("the run");
    let m = metrics(&result.dir);
    assert_eq!(m["success_rate"], 1.0, "{m}");
    assert_eq!(m["collisions_total"], 0, "{m}");
    for car in ["a", "b"] {
        let track = poses(&result.dir, car);
        // It had to turn out of the way: its heading left its start's by
        // more than 0.1 rad, and came back to the road's.
        let start = track[0].3;
        let off = track
            .iter()
            .map(|p| mrsim_scenario::angle_between(p.3, start))
            .fold(0.0, f64::max);
        assert!(off > 0.1, "{car} never turned: {off}");
        // Its wheels never slipped: the rear axle (1.5 m behind the
        // centre) moved along the heading every tick, its sideways part
        // within the six decimals of the file and a chord of the tick's
        // arcs off their mid-heading (measured: at most 0.1% of the
        // chord; the centre itself moves up to 6 cm sideways in a tick).
        for w in track.windows(2) {
            let (p, q) = (w[0], w[1]);
            let rear = |p: Pose| (p.1 - 1.5 * p.3.cos(), p.2 - 1.5 * p.3.sin());
            let (r0, r1) = (rear(p), rear(q));
            let mid = (p.3 + q.3) / 2.0;
            let (dx, dy) = (r1.0 - r0.0, r1.1 - r0.1);
            let sideways = (-mid.sin() * dx + mid.cos() * dy).abs();
            assert!(
                sideways < 1e-4 + 0.003 * dx.hypot(dy),
                "{car} slid {sideways} m at tick {}",
                q.0
            );
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A car that starts on its goal facing +x, with goal heading `deg`.
fn parked(deg: f64) -> String {
    format!(
        "[world]\ndt = 0.1\nduration = 3.0\n\n\
         [[robot]]\nname = \"car\"\nstart = [0.0, 0.0]\ngoal = [0.0, 0.0]\n\
         kinematics = \"ackermann\"\nwheelbase = 3.0\n\
         shape = {{ kind = \"rectangle\", length = 4.6, width = 1.6 }}\n\
         goal_heading_deg = {deg}\n"
    )
}

#[test]
fn a_car_on_its_goal_facing_the_wrong_way_has_not_arrived() {
    // One process per robot: the car's commands cross the wire as
    // ACKERMANN. Parked on its goal facing +x, it has not arrived when its
    // goal heading is +y, and has (after goal_hold_ticks) when it is 5
    // degrees, within the default 10.
    let dir = fresh_dir("car-heading");
    let wrong = run_quietly(&dir, &parked(90.0), "wrong", &[]);
    let m = metrics(&wrong);
    assert_eq!(m["robots"]["car"]["reached_goal"], false, "{m}");
    assert!(
        !events(&wrong).iter().any(|e| e["type"] == "goal_reached"),
        "a goal_reached event"
    );
    let right = run_quietly(&dir, &parked(5.0), "right", &[]);
    let m = metrics(&right);
    assert_eq!(m["robots"]["car"]["reached_goal"], true, "{m}");
    assert_eq!(m["commands_rejected"], 0, "{m}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The corners of robot `spec`'s body at pose `p` (its shape placed).
fn corners(spec: &mrsim_scenario::RobotSpec, p: Pose) -> Vec<[f64; 2]> {
    spec.body_shape()
        .placed(mrsim_planners::Pose::new([p.1, p.2], p.3))
        .expect("a rectangle")
        .points()
        .to_vec()
}

#[test]
fn a_car_on_its_route_reverses_into_a_bay_between_two_parked_cars_and_stands_in_it() {
    // scenarios/cars/parking.toml: a 4.6 x 1.6 m car (wheelbase 2.8 m, 35
    // degrees of steering) is to stand nose out in the 2.5 m bay between
    // two parked cars, by its route (Hybrid A*) and pure pursuit.
    let file = root().join("scenarios/cars/parking.toml");
    let s = mrsim_scenario::load(&file).expect("scenario").scenario;
    let out = fresh_dir("car-parking").join("out");
    assert_ok(&run(
        &file,
        &out,
        &run_id("car-parking"),
        &["--transport", "inproc"],
    ));
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m}");
    assert_eq!(m["collisions_total"], 0, "{m}");
    let car = &s.robots[0];
    let track = poses(&out, &car.name);
    // The bay: between the parked cars' inner sides, from the kerb (y = 0)
    // to the line of their fronts.
    let parked: Vec<Vec<[f64; 2]>> = s
        .obstacles
        .iter()
        .map(|o| {
            o.body_shape()
                .placed(mrsim_planners::Pose::new(o.start, o.heading))
                .expect("a parked car's rectangle")
                .points()
                .to_vec()
        })
        .collect();
    let xs =
        |c: &Vec<[f64; 2]>, f: fn(f64, f64) -> f64, init: f64| c.iter().map(|q| q[0]).fold(init, f);
    let west = xs(&parked[0], f64::max, f64::NEG_INFINITY);
    let east = xs(&parked[1], f64::min, f64::INFINITY);
    let front = parked
        .iter()
        .map(|c| c.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max))
        .fold(f64::INFINITY, f64::min);
    assert!((east - west - 2.5).abs() < 1e-9, "a bay of {}", east - west);
    let end = *track.last().expect("poses");
    for q in corners(car, end) {
        assert!(
            q[0] > west && q[0] < east && q[1] > 0.0 && q[1] < front,
            "corner {q:?} outside the bay [{west}, {east}] x [0, {front}]: {end:?}"
        );
    }
    let goal = car.goal_heading.expect("a goal heading");
    assert!(
        mrsim_scenario::angle_between(end.3, goal.heading) <= goal.tolerance,
        "heading {} at the end",
        end.3.to_degrees()
    );
    // It backed in: the rear axle's last moves were against the heading.
    let half = car.ackermann.expect("a car").wheelbase / 2.0;
    let rear = |p: Pose| [p.1 - half * p.3.cos(), p.2 - half * p.3.sin()];
    let moved: Vec<f64> = track
        .windows(2)
        .map(|w| {
            let (a, b) = (rear(w[0]), rear(w[1]));
            (b[0] - a[0]) * w[0].3.cos() + (b[1] - a[1]) * w[0].3.sin()
        })
        .filter(|d| d.abs() > 1e-3)
        .collect();
    assert!(
        moved.first().is_some_and(|d| *d > 0.0),
        "it set off forwards"
    );
    assert!(moved.last().is_some_and(|d| *d < 0.0), "it ended backwards");
    // The lot's walls bound it: no corner ever more than 1 mm beyond them.
    let (lo, hi) = s.walls.iter().flat_map(|w| w.segment).fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    for &p in &track {
        for q in corners(car, p) {
            let inside = q[0] >= lo[0] - 1e-3
                && q[1] >= lo[1] - 1e-3
                && q[0] <= hi[0] + 1e-3
                && q[1] <= hi[1] + 1e-3;
            assert!(inside, "corner {q:?} into a wall at tick {}", p.0);
        }
    }
    let _ = std::fs::remove_dir_all(out.parent().expect("a folder"));
}

#[test]
fn a_car_goal_its_route_cannot_reach_is_refused_naming_the_robot_file_and_line() {
    // The parking scene with a car that may not reverse: nose out in the
    // bay needs backing in, and no forward way exists.
    let text =
        std::fs::read_to_string(root().join("scenarios/cars/parking.toml")).expect("parking.toml");
    assert!(text.contains("max_reverse_speed = 1.0"));
    let text = text.replace("max_reverse_speed = 1.0", "max_reverse_speed = 0.0");
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("goal = "))
        .expect("a goal line");
    let dir = fresh_dir("car-unreachable");
    let file = dir.join("forwards.toml");
    std::fs::write(&file, &text).expect("write scenario");
    let err = run_refused(&file);
    let at = format!("{}:{line}", file.display());
    for w in [
        at.as_str(),
        "robot `car`",
        "route = \"shortest\"",
        "cannot reach its goal",
        "without reversing",
    ] {
        assert!(err.contains(w), "no `{w}` in: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two cars on their routes whose ways cross at the origin at right
/// angles: `a` (the lower id) from `a_from` west of it driving east, `b`
/// from `b_from` south of it driving north. Returns the times each centre
/// passes the crossing and the run's metrics.
fn crossing_cars(tag: &str, a_from: f64, b_from: f64) -> (f64, f64, serde_json::Value) {
    let car = "kinematics = \"ackermann\"\nwheelbase = 2.8\nmax_steering_deg = 35\n\
               max_steering_rate_deg = 60\nmax_speed = 8.0\nmax_accel = 2.5\n\
               shape = { kind = \"rectangle\", length = 4.6, width = 1.6 }\n\
               route = \"shortest\"\ngoal_tolerance = 1.0\n";
    let text = format!(
        "[world]\ndt = 0.1\nduration = 40.0\nmode = \"lockstep\"\n\
         arena = {{ min = [-40.0, -40.0], max = [40.0, 40.0] }}\n\n\
         [[robot]]\nname = \"a\"\nstart = [{a_from}, 0.0]\ngoal = [25.0, 0.0]\n{car}\n\
         [[robot]]\nname = \"b\"\nstart = [0.0, {b_from}]\ngoal = [0.0, 25.0]\n{car}"
    );
    let dir = run_quietly(&fresh_dir(tag), &text, tag, &["--transport", "inproc"]);
    let passed = |body: &str, axis: usize| {
        poses(&dir, body)
            .iter()
            .find(|p| if axis == 0 { p.1 >= 0.0 } else { p.2 >= 0.0 })
            .map(|p| p.0 as f64 * 0.1)
            .unwrap_or_else(|| panic!("{body} never passed the crossing"))
    };
    (passed("a", 0), passed("b", 1), metrics(&dir))
}

#[test]
fn two_cars_arriving_together_at_a_crossing_let_the_lower_id_go_first() {
    let (a, b, m) = crossing_cars("cross-tie", -20.0, -20.0);
    // b waits until a, 4.6 m long, is through: b's centre reaches the
    // crossing well after a's.
    assert!(b > a + 1.0, "a passed at {a} s, b at {b} s");
    assert_eq!(m["collisions_total"].as_u64(), Some(0));
    for r in ["a", "b"] {
        assert_eq!(m["robots"][r]["reached_goal"].as_bool(), Some(true), "{r}");
        assert!(m["robots"][r]["min_clearance"].as_f64().expect("gap") > 0.3);
    }
}
