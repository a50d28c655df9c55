//! The unicycle and lidar robot keys: defaults, values taken, bad values
//! refused at their line.

use crate::common::*;
use mrsim_scenario::{Kinematics, Lidar};

#[test]
fn robots_are_holonomic_without_a_sensor_unless_they_say() {
    let l = accept(BASE);
    let r = &l.scenario.robots[0];
    assert_eq!(r.kinematics, Kinematics::Holonomic);
    assert_eq!(r.sensor, None);
    assert_eq!((r.max_angular_speed, r.max_angular_accel), (2.0, 4.0));
}

#[test]
fn unicycle_keys_and_a_lidar_are_read_with_their_defaults() {
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nkinematics = \"unicycle\"\nmax_angular_speed = 1.5\n\
         max_angular_accel = 3.0\nlookahead = 0.05\nsensor = { kind = \"lidar\", beams = 90, noise = 0.02 }",
    );
    let l = accept(&src);
    let r = l
        .scenario
        .robots
        .iter()
        .find(|r| r.kinematics == Kinematics::Unicycle)
        .expect("a unicycle");
    assert_eq!(
        (r.max_angular_speed, r.max_angular_accel, r.lookahead),
        (1.5, 3.0, 0.05)
    );
    assert_eq!(
        r.sensor,
        Some(Lidar {
            beams: 90,
            fov_deg: 360.0,
            range: 10.0,
            noise: 0.02,
            record: false
        })
    );
}

#[test]
fn bad_kinematics_and_sensors_are_refused_at_their_line() {
    let src = with(BASE, "radius = 0.3", "radius = 0.3\nkinematics = \"tank\"");
    refused_at(&src, "kinematics", "unknown variant `tank`");
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nmax_angular_speed = 0.0",
    );
    refused_at(&src, "max_angular_speed", "max_angular_speed must be > 0");
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nsensor = { kind = \"sonar\" }",
    );
    refused_at(&src, "sensor", "unknown sensor kind `sonar`");
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nsensor = { kind = \"lidar\", beams = 0 }",
    );
    refused_at(&src, "sensor", "beams must be >= 1");
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nsensor = { kind = \"lidar\", fov_deg = 400 }",
    );
    refused_at(&src, "sensor", "fov_deg must be in (0, 360]");
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nsensor = { kind = \"lidar\", rays = 4 }",
    );
    refused_at(&src, "sensor", "unknown field `rays`");
}
