//! Car-like robots end to end: a holonomic planner (orca) drives two cars
//! past each other through the tracking controller in an in-process run,
//! and the world's goal test asks a car's heading as well as its place.

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
