//! The hydrodynamic planner's unit tests: the flows against hand-computed
//! values and their boundary conditions, the speed corrections, and the
//! paper's experiment in the testkit.

use super::experiment as ex;
use super::*;
use crate::testkit::{RobotModel, Sim, observation, obstacle};
use crate::{ParamValue, Segment, Sensed};

const ROBOT: RobotModel = RobotModel {
    radius: 0.2,
    mass: 1.0,
    damping: 0.0,
    max_speed: 5.0,
    max_accel: 20.0,
};

/// The robot at rest at `pos`.
fn obs<'a>(pos: Vec2, goal: Vec2, others: &'a [Sensed], walls: &'a [Segment]) -> Observation<'a> {
    Observation {
        walls,
        ..observation(ROBOT.at(pos, Vec2::zeros()), goal, others)
    }
}

/// Obstacle 9.
fn sensed(p: Vec2, v: Vec2, r: f64) -> Sensed {
    obstacle(9, p, v, r)
}

#[test]
fn sink_flow_points_at_the_goal_everywhere_away_from_obstacles() {
    let goal = Vec2::new(3.0, -2.0);
    for i in 0..20 {
        for j in 0..20 {
            let z = Vec2::new(-10.0 + i as f64 * 1.07, -10.0 + j as f64 * 1.13);
            let mut p = Hydro {
                start: Some(Vec2::new(-12.0, 0.0)),
                ..Hydro::default()
            };
            let v = p.plan(&obs(z, goal, &[], &[])).vector();
            if (goal - z).norm() < 1e-9 {
                continue;
            }
            assert!(v.norm() > 0.0, "at {z:?}");
            let e = goal - z;
            let sin = (v.x * e.y - v.y * e.x) / (v.norm() * e.norm());
            assert!(sin.abs() < 1e-12 && v.dot(&e) > 0.0, "at {z:?}: {v:?}");
        }
    }
}

#[test]
fn the_flow_has_the_hand_computed_values_at_a_point_beside_a_cylinder() {
    // Goal at the origin, start at (-100, 0) (so eq 3's first factor is
    // 1 - e^-208 = 1), z = (4, 2), m = 0.5, c2 = 2: r = |z| = sqrt 20,
    //   h = r (1 - e^{-2r}) = 4.4721360 * 0.9998695 = 4.4715524.
    // No body: conj v = -h m / z, v = -h m z / |z|^2
    //   = (-0.4471552, -0.2235776), speed m (1 - e^{-2r}) = 0.4999348.
    // A standing cylinder of radius 1 at (4, 0): eq (1) with the image
    // point 4 + 1/conj(0 - 4) = 3.75, relative to the centre
    //   G'/m = -1/(2i + 4) - 1/(2i + 0.25) + 1/(2i)
    //        = (-0.2 + 0.1i) + (-0.0615385 + 0.4923077i) - 0.5i
    //        = -0.2615385 + 0.0923077i,
    //   v = conj(h G') = (-0.5847415, -0.2063793).
    // The same cylinder moving at (0.5, 0): z is abeam, b = 1 (eq 4),
    //   the doublet adds D' = a^2 u / (2i)^2 = -0.125 (eq 2),
    //   v = (-0.7097415, -0.2063793).
    let circle = Hydro {
        shape: Shape::Circle,
        ..Hydro::default()
    };
    let (z, start, goal) = (Vec2::new(4.0, 2.0), Vec2::new(-100.0, 0.0), Vec2::zeros());
    assert!((circle.speed_correction(z, start, goal) - 4.4715524).abs() < 1e-7);
    let cylinder = |u: f64| circle.body(Vec2::new(4.0, 0.0), Vec2::new(u, 0.0), 1.0, 0.0);
    let cases = [
        (vec![], (-0.4471552, -0.2235776)),
        (vec![cylinder(0.0)], (-0.5847415, -0.2063793)),
        (vec![cylinder(0.5)], (-0.7097415, -0.2063793)),
    ];
    for (bodies, (vx, vy)) in cases {
        let v = circle.velocity_at(z, start, goal, &bodies);
        assert!((v - Vec2::new(vx, vy)).norm() < 1e-7, "{v}");
    }
}

#[test]
fn far_from_everything_the_speed_is_the_sink_strength() {
    let p = Hydro::default();
    let start = Vec2::new(0.0, 0.0);
    let goal = Vec2::new(100.0, 0.0);
    let v = p.velocity_at(Vec2::new(50.0, 0.0), start, goal, &[]);
    assert!((v.norm() - p.strength).abs() < 1e-9, "{v:?}");
}

#[test]
fn no_flow_enters_a_standing_cylinder() {
    let p = Hydro::default();
    let goal = Vec2::new(10.0, 1.0);
    let body = p.body(Vec2::new(4.0, 0.5), Vec2::zeros(), 1.0, 0.2);
    for k in 0..72 {
        let th = k as f64 * PI / 36.0;
        let n = Vec2::new(th.cos(), th.sin());
        let z = body.center + n * (body.radius * (1.0 + 1e-9));
        let v = p.velocity_at(z, Vec2::new(-3.0, 0.0), goal, &[body]);
        assert!(
            v.dot(&n).abs() < 1e-6 * (1.0 + v.norm()),
            "theta {th}: {v:?}"
        );
    }
    // And the flow is not trivially zero there.
    let side = body.center + Vec2::new(0.0, body.radius * 1.000001);
    assert!(
        p.velocity_at(side, Vec2::new(-3.0, 0.0), goal, &[body])
            .norm()
            > 0.1
    );
}

/// Normal component of (flow - body velocity) on the ellipse boundary
/// of a translating body, without `h` and `b` (the exact potential).
fn worst_normal_flux(body: &FlowBody, goal: Vec2, m: f64) -> f64 {
    let speed = body.velocity.norm();
    let rot = cx(body.velocity) / speed;
    let big_r = body.zeta_radius();
    let c = body.focal;
    let major = big_r + c * c / big_r;
    let minor = big_r - c * c / big_r;
    assert!((minor - body.radius).abs() < 1e-12);
    let mut worst: f64 = 0.0;
    for k in 0..360 {
        let th = k as f64 * PI / 180.0 + 0.0123;
        // Point on the ellipse, slightly outside, in the body frame.
        let local = C::new(major * th.cos(), minor * th.sin()) * (1.0 + 1e-10);
        let normal_local = C::new(th.cos() / major, th.sin() / minor);
        let z = cx(body.center) + rot * local;
        let n = rot * normal_local / normal_local.norm();
        let BodyFlow::Outside(g, d) = body.flow(m, z, cx(goal)) else {
            panic!("point {th} counted inside");
        };
        let flow = (g + d).conj() - cx(body.velocity);
        let flux = (flow * n.conj()).re;
        worst = worst.max(flux.abs() / (1.0 + flow.norm()));
    }
    worst
}

#[test]
fn ellipse_flow_does_not_cross_the_moving_ellipse_in_its_own_frame() {
    let p = Hydro::default();
    for (vel, goal) in [
        (Vec2::new(-0.5, 0.0), Vec2::new(10.0, 0.0)),
        (Vec2::new(0.3, -0.8), Vec2::new(-4.0, 7.0)),
        (Vec2::new(1.5, 1.0), Vec2::new(2.0, -9.0)),
    ] {
        let body = p.body(Vec2::new(3.0, 1.0), vel, 0.3, 0.2);
        assert!(body.focal > 0.0);
        let worst = worst_normal_flux(&body, goal, p.strength);
        assert!(worst < 1e-6, "velocity {vel:?}: relative flux {worst}");
    }
}

#[test]
fn ellipse_is_longer_along_the_motion_and_grows_with_speed() {
    let p = Hydro::default();
    let slow = p.body(Vec2::zeros(), Vec2::new(0.2, 0.0), 0.3, 0.2);
    let fast = p.body(Vec2::zeros(), Vec2::new(0.8, 0.0), 0.3, 0.2);
    let major = |b: &FlowBody| {
        let r = b.zeta_radius();
        r + b.focal * b.focal / r
    };
    assert!(major(&slow) > slow.radius);
    assert!(major(&fast) > major(&slow));
    // A point ahead of the obstacle, outside the circle but inside the
    // fast ellipse, is inside the avoidance region.
    let ahead = Vec2::new(major(&fast) * 0.9, 0.0);
    assert!(ahead.x > fast.radius);
    assert!(matches!(
        fast.flow(0.5, cx(ahead), C::new(10.0, 0.0)),
        BodyFlow::Inside
    ));
}

#[test]
fn circle_doublet_does_not_cross_the_moving_circle_in_its_own_frame() {
    let p = Hydro {
        shape: Shape::Circle,
        ..Hydro::default()
    };
    let body = p.body(Vec2::new(3.0, 1.0), Vec2::new(-0.5, 0.2), 0.3, 0.2);
    assert_eq!(body.focal, 0.0);
    for k in 0..72 {
        let th = k as f64 * PI / 36.0 + 0.01;
        let n = C::new(th.cos(), th.sin());
        let z = cx(body.center) + n * body.radius * (1.0 + 1e-10);
        let BodyFlow::Outside(g, d) = body.flow(0.5, z, C::new(10.0, 0.0)) else {
            panic!("inside");
        };
        let flow = (g + d).conj() - cx(body.velocity);
        assert!((flow * n.conj()).re.abs() < 1e-6, "theta {th}");
    }
}

#[test]
fn speed_correction_is_finite_at_the_goal_and_the_speed_vanishes_there() {
    let p = Hydro::default();
    let start = Vec2::new(0.0, 0.0);
    let goal = Vec2::new(5.0, 0.0);
    let mut last = f64::INFINITY;
    for k in 1..12 {
        let r = 10f64.powi(-k);
        let z = goal - Vec2::new(r, 0.0);
        let h = p.speed_correction(z, start, goal);
        assert!(h.is_finite() && h <= r);
        let v = p.velocity_at(z, start, goal, &[]).norm();
        // Close to the goal the speed is about m c2 |z - z_g|.
        assert!(v <= p.strength * p.c2 * r * (1.0 + 1e-6), "r {r}: {v}");
        assert!(v < last);
        last = v;
    }
    assert_eq!(p.velocity_at(goal, start, goal, &[]), Vec2::zeros());
}

#[test]
fn speed_ramps_up_from_the_start() {
    let p = Hydro::default();
    let start = Vec2::new(0.0, 0.0);
    let goal = Vec2::new(10.0, 0.0);
    let v0 = p.velocity_at(start, start, goal, &[]).norm();
    let expected = p.strength * (1.0 - (-p.epsilon).exp()) * (1.0 - (-p.c2 * 10.0).exp());
    assert!((v0 - expected).abs() < 1e-12 && v0 > 0.0);
    let v1 = p.velocity_at(Vec2::new(0.5, 0.0), start, goal, &[]).norm();
    let v2 = p.velocity_at(Vec2::new(2.0, 0.0), start, goal, &[]).norm();
    assert!(v0 < v1 && v1 < v2, "{v0} {v1} {v2}");
}

#[test]
fn printed_eq_21_jumps_at_gamma_and_ours_is_continuous() {
    let gamma = 3.0 * PI / 4.0;
    // As printed: (1 + cos 2 beta) / 2 with beta = gamma - pi/2 at the band's end.
    let printed_end = 0.5 * (1.0 + (2.0 * (gamma - FRAC_PI_2)).cos());
    assert!((printed_end - 0.5).abs() < 1e-12);
    let p = Hydro::default();
    let body = FlowBody {
        center: Vec2::zeros(),
        radius: 0.5,
        velocity: Vec2::new(1.0, 0.0),
        focal: 0.0,
    };
    let b = |phi: f64| p.correction_at(Vec2::new(phi.cos(), phi.sin()) * 2.0, &body);
    let n = 20_000;
    let mut worst: f64 = 0.0;
    for k in 0..n {
        let a = -PI + 2.0 * PI * k as f64 / n as f64;
        let step = 2.0 * PI / n as f64;
        worst = worst.max((b(a + step) - b(a)).abs());
    }
    // The largest step over an angle step of 3e-4 rad is of its order.
    assert!(worst < 1e-3, "worst jump {worst}");
    assert!((b(0.0) - 1.0).abs() < 1e-12);
    assert!((b(FRAC_PI_2 + 1e-9) - 1.0).abs() < 1e-9);
    assert!(b(gamma - 1e-9).abs() < 1e-9);
    assert_eq!(b(PI), 0.0);
    // With gamma = pi it is the printed eq (21).
    let q = Hydro {
        gamma: PI,
        ..Hydro::default()
    };
    for phi in [1.7, 2.0, 2.5, 3.0] {
        let beta = phi - (0.0 + FRAC_PI_2);
        let printed = 0.5 * (1.0 + (2.0 * beta).cos());
        let ours = q.correction_at(Vec2::new(phi.cos(), phi.sin()), &body);
        assert!((printed - ours).abs() < 1e-12);
    }
}

#[test]
fn binary_correction_jumps_at_the_obstacles_beam() {
    let p = Hydro {
        correction: Correction::Binary,
        ..Hydro::default()
    };
    let body = FlowBody {
        center: Vec2::zeros(),
        radius: 0.5,
        velocity: Vec2::new(0.0, 1.0),
        focal: 0.0,
    };
    assert_eq!(p.correction_at(Vec2::new(1.0, 1e-9), &body), 1.0);
    assert_eq!(p.correction_at(Vec2::new(1.0, -1e-9), &body), 0.0);
}

#[test]
fn a_sensed_obstacle_ahead_deflects_the_command_to_the_free_side() {
    let goal = Vec2::new(10.0, 0.0);
    let mut free = Hydro::default();
    let v_free = free.plan(&obs(Vec2::zeros(), goal, &[], &[])).vector();
    // Obstacle slightly above the straight line, coming head-on.
    let others = [sensed(Vec2::new(1.5, 0.2), Vec2::new(-0.5, 0.0), 0.3)];
    let mut p = Hydro::default();
    let v = p.plan(&obs(Vec2::zeros(), goal, &others, &[])).vector();
    assert!(v_free.y.abs() < 1e-12);
    assert!(v.y < -1e-3 * v.norm(), "{v:?}");
}

#[test]
fn weights_favour_the_nearest_obstacle() {
    // Next to one obstacle's boundary the flow is that obstacle's alone:
    // no flow into it although another obstacle is near.
    let p = Hydro::default();
    let goal = Vec2::new(10.0, 0.0);
    let a = p.body(Vec2::new(4.0, 0.0), Vec2::zeros(), 0.5, 0.2);
    let b = p.body(Vec2::new(4.0, 2.0), Vec2::zeros(), 0.5, 0.2);
    let n = Vec2::new(-0.6, 0.8);
    let z = a.center + n * (a.radius + 1e-7);
    let v = p.velocity_at(z, Vec2::zeros(), goal, &[a, b]);
    assert!(v.dot(&n).abs() < 1e-5 * v.norm(), "{v:?}");
}

#[test]
fn a_wall_between_robot_and_goal_is_not_crossed() {
    let walls = [Segment {
        a: Vec2::new(2.0, -1.5),
        b: Vec2::new(2.0, 1.5),
    }];
    let mut sim = Sim::new(0.05, 10);
    let planner = Hydro::default();
    let i = sim.add_robot(
        Box::new(planner),
        Vec2::new(0.0, 0.1),
        Vec2::new(5.0, 0.0),
        0.2,
        1.0,
        0.0,
        5.0,
        20.0,
    );
    sim.robots[i].velocity_lag = 0.1;
    sim.walls = walls.to_vec();
    let mut reached = false;
    for _ in 0..1200 {
        sim.step();
        let p = sim.robots[i].state.position;
        let d = (walls[0].closest_point(p) - p).norm();
        assert!(d > 0.2, "touched the wall at {p:?}");
        if (p - Vec2::new(5.0, 0.0)).norm() < 0.05 {
            reached = true;
            break;
        }
    }
    assert!(reached, "stopped at {:?}", sim.robots[i].state.position);
}

#[test]
fn parameters_have_the_documented_names_and_refuse_bad_values() {
    let mut params = Params::new();
    for (k, v) in [
        ("strength", ParamValue::Number(0.7)),
        ("c1", ParamValue::Number(1.0)),
        ("c2", ParamValue::Number(3.0)),
        ("epsilon", ParamValue::Number(0.2)),
        ("shape", ParamValue::Text("circle".into())),
        ("correction", ParamValue::Text("binary".into())),
        ("gamma", ParamValue::Number(PI)),
        ("ellipse_time", ParamValue::Number(2.0)),
        ("delay", ParamValue::Number(0.1)),
    ] {
        params.insert(k.into(), v);
    }
    let p = Hydro::from_params(&params).unwrap();
    assert_eq!(p.shape, Shape::Circle);
    assert_eq!(p.correction, Correction::Binary);
    assert_eq!(p.delay, 0.1);
    params.insert("gamma".into(), ParamValue::Number(1.0));
    assert!(Hydro::from_params(&params).is_err());
    params.insert("gamma".into(), ParamValue::Number(PI));
    params.insert("shape".into(), ParamValue::Text("square".into()));
    assert!(Hydro::from_params(&params).is_err());
}

#[test]
fn delay_grows_the_avoidance_radius_by_the_distance_moved() {
    let p = Hydro {
        delay: 0.4,
        ..Hydro::default()
    };
    let b = p.body(Vec2::zeros(), Vec2::new(0.0, 2.0), 0.3, 0.2);
    assert!((b.radius - (0.3 + 0.2 + 0.8)).abs() < 1e-12);
}

/// One run of the paper's experiment (figs 15-20) with the constants of
/// the scenario files.
struct Run {
    reached: bool,
    reached_at: f64,
    min_clearance: f64,
    peak_time: f64,
    max_dv_time: f64,
    peak_speed: f64,
    max_dv: f64,
    velocities: Vec<Vec2>,
}

fn experiment(shape: &str, correction: &str) -> Run {
    experiment_d(shape, correction, ex::ELLIPSE_TIME)
}

/// Sugiyama et al. fig 17: the ellipse's peak speed is "a half" of the
/// circle's. Ours falls as the ellipse lengthens (`ellipse_time` 0 is the
/// circle, the files use 2 s: 1.002 to 0.722 m/s) but stays above 0.6 of
/// the circle's even at 4 s (0.623 m/s), so the half is not reached in
/// this range; every length still reaches the goal without contact, and
/// the smooth correction never makes the largest velocity change worse.
#[test]
fn a_longer_ellipse_lowers_the_peak_speed_but_not_to_half_the_circles() {
    let circle = experiment_d("ellipse", "binary", 0.0).peak_speed;
    let mut last = f64::INFINITY;
    for d in [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0] {
        let (b, s) = (
            experiment_d("ellipse", "binary", d),
            experiment_d("ellipse", "smooth", d),
        );
        for r in [&b, &s] {
            assert!(r.reached && r.min_clearance > 0.0, "ellipse_time {d}");
        }
        assert!(b.peak_speed < last, "ellipse_time {d}: {}", b.peak_speed);
        assert!(
            b.peak_speed > 0.6 * circle,
            "ellipse_time {d}: {}",
            b.peak_speed
        );
        assert!(s.max_dv <= b.max_dv + 1e-9, "ellipse_time {d}");
        last = b.peak_speed;
    }
}

fn experiment_d(shape: &str, correction: &str, d: f64) -> Run {
    let mut params = Params::new();
    params.insert("shape".into(), ParamValue::Text(shape.into()));
    params.insert("correction".into(), ParamValue::Text(correction.into()));
    params.insert("strength".into(), ParamValue::Number(ex::STRENGTH));
    params.insert("ellipse_time".into(), ParamValue::Number(d));
    params.insert("delay".into(), ParamValue::Number(ex::VELOCITY_LAG));
    let planner = crate::build("hydro", &params).unwrap();
    let mut sim = Sim::new(ex::DT, ex::SUBSTEPS);
    let goal = ex::v(ex::ROBOT_GOAL);
    let i = sim.add_robot(
        planner,
        ex::v(ex::ROBOT_START),
        goal,
        ex::ROBOT_RADIUS,
        ex::MASS,
        0.0,
        ex::MAX_SPEED,
        ex::MAX_ACCEL,
    );
    sim.robots[i].velocity_lag = ex::VELOCITY_LAG;
    sim.add_obstacle(
        ex::v(ex::OBSTACLE_START),
        ex::v(ex::OBSTACLE_VELOCITY),
        ex::OBSTACLE_RADIUS,
    );
    let ticks = (ex::DURATION / ex::DT).round() as u64;
    let mut run = Run {
        reached: false,
        reached_at: f64::NAN,
        min_clearance: f64::INFINITY,
        peak_time: 0.0,
        max_dv_time: 0.0,
        peak_speed: 0.0,
        max_dv: 0.0,
        velocities: Vec::new(),
    };
    let mut last_v = Vec2::zeros();
    for _ in 0..ticks {
        sim.step();
        let s = sim.robots[i].state;
        run.min_clearance = run.min_clearance.min(sim.clearance(i));
        let t = sim.tick as f64 * ex::DT;
        if s.velocity.norm() > run.peak_speed {
            run.peak_speed = s.velocity.norm();
            run.peak_time = t;
        }
        if (s.velocity - last_v).norm() > run.max_dv {
            run.max_dv = (s.velocity - last_v).norm();
            run.max_dv_time = t;
        }
        run.velocities.push(s.velocity);
        last_v = s.velocity;
        if !run.reached && (s.position - goal).norm() <= ex::GOAL_TOLERANCE {
            run.reached = true;
            run.reached_at = t;
        }
    }
    run
}

#[test]
fn scenario_files_use_the_experiment_constants() {
    let files = [
        (
            "circle",
            "binary",
            include_str!("../../../../scenarios/papers/hydro-circle-binary.toml"),
        ),
        (
            "circle",
            "smooth",
            include_str!("../../../../scenarios/papers/hydro-circle-smooth.toml"),
        ),
        (
            "ellipse",
            "binary",
            include_str!("../../../../scenarios/papers/hydro-ellipse-binary.toml"),
        ),
        (
            "ellipse",
            "smooth",
            include_str!("../../../../scenarios/papers/hydro-ellipse-smooth.toml"),
        ),
    ];
    let p = |x: [f64; 2]| format!("[{:?}, {:?}]", x[0], x[1]);
    let d = Hydro::default();
    for (shape, correction, text) in files {
        for line in [
            format!("dt = {:?}", ex::DT),
            format!("substeps = {}", ex::SUBSTEPS),
            format!("duration = {:?}", ex::DURATION),
            format!("radius = {:?}", ex::ROBOT_RADIUS),
            format!("mass = {:?}", ex::MASS),
            format!("max_speed = {:?}", ex::MAX_SPEED),
            format!("max_accel = {:?}", ex::MAX_ACCEL),
            format!("velocity_lag = {:?}", ex::VELOCITY_LAG),
            format!("goal_tolerance = {:?}", ex::GOAL_TOLERANCE),
            format!("start = {}", p(ex::ROBOT_START)),
            format!("goal = {}", p(ex::ROBOT_GOAL)),
            format!("start = {}", p(ex::OBSTACLE_START)),
            format!("radius = {:?}", ex::OBSTACLE_RADIUS),
            format!("velocity = {} }}", p(ex::OBSTACLE_VELOCITY)),
            format!(
                "strength = {:?}, c1 = {:?}, c2 = {:?}, epsilon = {:?},",
                ex::STRENGTH,
                d.c1,
                d.c2,
                d.epsilon
            ),
            format!("gamma = {:?},", d.gamma),
            format!("shape = \"{shape}\", correction = \"{correction}\""),
            format!(
                "ellipse_time = {:?}, delay = {:?} }}",
                ex::ELLIPSE_TIME,
                ex::VELOCITY_LAG
            ),
        ] {
            assert!(text.contains(&line), "{shape}-{correction} lacks `{line}`");
        }
    }
}

#[test]
fn paper_experiment_every_variant_reaches_the_goal_without_collision() {
    for shape in ["circle", "ellipse"] {
        for correction in ["binary", "smooth"] {
            let r = experiment(shape, correction);
            eprintln!(
                "hydro {shape}/{correction}: reached at {:.2} s, min clearance {:.4}, \
                 peak speed {:.4} at {:.2} s, max |dv| per tick {:.4} at {:.2} s",
                r.reached_at, r.min_clearance, r.peak_speed, r.peak_time, r.max_dv, r.max_dv_time
            );
            assert!(r.reached, "{shape}/{correction}");
            assert!(r.min_clearance > 0.0, "{shape}/{correction}");
        }
    }
}

/// The paper (fig 17): the ellipse's peak speed is half the circle's.
/// Not reproduced: ours is 0.72 of it (0.722 against 1.002 m/s binary,
/// 1.011 smooth); asserted as measured.
#[test]
fn paper_experiment_ellipse_peak_speed_is_0_72_of_the_circles_not_half() {
    for correction in ["binary", "smooth"] {
        let c = experiment("circle", correction);
        let e = experiment("ellipse", correction);
        assert!(
            (0.70..0.74).contains(&(e.peak_speed / c.peak_speed)),
            "{correction}: ellipse {} circle {}",
            e.peak_speed,
            c.peak_speed
        );
    }
}

#[test]
fn paper_experiment_smooth_velocity_change_is_below_the_binarys() {
    for shape in ["circle", "ellipse"] {
        let b = experiment(shape, "binary");
        let s = experiment(shape, "smooth");
        assert!(
            s.max_dv < b.max_dv,
            "{shape}: smooth {} binary {}",
            s.max_dv,
            b.max_dv
        );
    }
}

/// The largest tick-to-tick velocity change over the median of the ten around it: above 1.25 it stands out from
/// its neighbours, a jump.
fn sharpest_change(speeds: &[Vec2]) -> f64 {
    let dv: Vec<f64> = speeds.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let k = (0..dv.len()).fold(0, |k, i| if dv[i] > dv[k] { i } else { k });
    let mut around: Vec<f64> = dv[k.saturating_sub(5)..k]
        .iter()
        .chain(&dv[(k + 1).min(dv.len())..(k + 6).min(dv.len())])
        .copied()
        .collect();
    around.sort_by(f64::total_cmp);
    dv[k] / around[around.len() / 2]
}

/// Sugiyama et al. figs 17 and 20: with the binary b_j the velocity has
/// a discontinuous point at its maximum; with the smooth b_j, none.
#[test]
fn paper_experiment_binary_correction_jumps_and_smooth_does_not() {
    for shape in ["circle", "ellipse"] {
        let b = experiment(shape, "binary");
        let s = experiment(shape, "smooth");
        let jb = sharpest_change(&b.velocities);
        let js = sharpest_change(&s.velocities);
        assert!(jb > 1.25, "{shape}: binary {jb}");
        assert!(js < 1.25, "{shape}: smooth {js}");
    }
}
