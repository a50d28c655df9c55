//! The virtual-distance planner's unit tests: the virtual distance and its
//! force against hand-computed values, and the goal and crossing scenes in
//! the testkit.

use super::*;
use crate::testkit::{RobotModel, observation, obstacle};
use crate::{SelfState, Sensed};

const ROBOT: RobotModel = RobotModel {
    radius: 0.0,
    mass: 0.1,
    damping: 0.0,
    max_speed: 30.0,
    max_accel: 500.0,
};

fn me(pos: Vec2, vel: Vec2) -> SelfState {
    ROBOT.at(pos, vel)
}

fn obs<'a>(me: SelfState, goal: Vec2, others: &'a [Sensed]) -> Observation<'a> {
    Observation {
        goal_tolerance: 1.0,
        ..observation(me, goal, others)
    }
}

#[test]
fn gradient_matches_central_finite_differences() {
    let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let p_o = Vec2::new(20.0, 5.0);
    let cases = [
        (Vec2::new(3.0, 1.0), Vec2::new(-5.0, -10.0)),
        (Vec2::new(10.0, 12.0), Vec2::new(2.0, -3.0)),
        (Vec2::new(15.0, -2.0), Vec2::new(-1.0, 4.0)),
        (Vec2::new(12.0, 6.0), Vec2::new(0.0, 0.0)),
    ];
    for (p, v_o) in cases {
        let rep = v.repulsion(p, 0.0, p_o, v_o, 5.0);
        assert!(rep.vd < v.eps_vd && rep.vd.is_finite(), "{p}: {}", rep.vd);
        let h = 1e-5;
        let u = |q: Vec2| v.potential(q, 0.0, p_o, v_o, 5.0);
        let gx = (u(p + Vec2::new(h, 0.0)) - u(p - Vec2::new(h, 0.0))) / (2.0 * h);
        let gy = (u(p + Vec2::new(0.0, h)) - u(p - Vec2::new(0.0, h))) / (2.0 * h);
        let fd = -Vec2::new(gx, gy);
        let rel = (rep.force - fd).norm() / fd.norm().max(1e-12);
        assert!(rel < 1e-6, "at {p}: analytic {} vs fd {fd}", rep.force);
        // And the outward-speed part matters: the force with v_or's own
        // dependence on P dropped (grad vd = alpha grad d / (beta - v_or),
        // eq 3 with v_or held fixed) differs from the finite difference
        // wherever the body moves across the line of sight.
        let rel = p_o - p;
        let u = rel / rel.norm();
        let across = (v_o - u * v_o.dot(&u)).norm();
        if across > 0.0 {
            let denom = v.beta - v_o.dot(&u);
            let coef = v.eta * (1.0 / rep.vd - 1.0 / v.eps_vd) / (rep.vd * rep.vd);
            let d_only = -u * (v.alpha / denom) * coef;
            let miss = (d_only - fd).norm() / fd.norm();
            assert!(
                miss > 1e-3,
                "at {p}: v_or's gradient changes the force by {miss}"
            );
        }
    }
}

#[test]
fn eq_7_has_the_hand_computed_values() {
    // Robot (a point) at the origin, a body of radius 5 at (20, 0), so
    // d = 15 and u = (1, 0); alpha = beta = 5, eta = 1000, eps_vd = 40.
    // Approaching at (-3, 0): v_or = -3, vd = 5 * 15 / 8 = 9.375,
    //   U = 500 (1/9.375 - 1/40)^2 = 3.3347222,
    //   grad vd = 5 (-1, 0)/8, F = 1000 (1/9.375 - 1/40)/9.375^2 grad vd
    //     = (-0.5807407, 0).
    // Crossing at (0, 4): v_or = 0, vd = 15, U = 500 (1/15 - 1/40)^2
    //   = 0.8680556; grad v_or = -(0, 4)/20, grad vd = 5 [5 (-1, 0)
    //   + 15 (0, -0.2)]/25 = (-1, -0.6), F = 1000 (1/15 - 1/40)/225
    //   (-1, -0.6) = (-0.1851852, -0.1111111).
    // Receding at (3, 0): vd = 37.5, U = 0.0013889; at (3.5, 0): vd = 50
    //   is beyond eps_vd, U = 0 and no force.
    let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let p_o = Vec2::new(20.0, 0.0);
    let cases = [
        ((-3.0, 0.0), 9.375, 3.3347222, (-0.5807407, 0.0)),
        ((0.0, 4.0), 15.0, 0.8680556, (-0.1851852, -0.1111111)),
        ((3.0, 0.0), 37.5, 0.0013889, (-0.0029630, 0.0)),
        ((3.5, 0.0), 50.0, 0.0, (0.0, 0.0)),
    ];
    for ((vx, vy), vd, u, (fx, fy)) in cases {
        let v_o = Vec2::new(vx, vy);
        let rep = v.repulsion(Vec2::zeros(), 0.0, p_o, v_o, 5.0);
        assert!((rep.vd - vd).abs() < 1e-12, "{v_o}: vd {}", rep.vd);
        let pot = v.potential(Vec2::zeros(), 0.0, p_o, v_o, 5.0);
        assert!((pot - u).abs() < 1e-7, "{v_o}: U {pot}");
        assert!(
            (rep.force - Vec2::new(fx, fy)).norm() < 1e-7,
            "{v_o}: {}",
            rep.force
        );
    }
}

#[test]
fn gradient_includes_the_outward_speed_dependence_on_position() {
    // Robot beside a body moving across the line of sight: moving the
    // robot sideways changes v_or, so the force has a sideways part the
    // distance alone would not give.
    let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let p_o = Vec2::new(10.0, 0.0);
    let rep = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(0.0, -4.0), 1.0);
    assert!(rep.force.x < 0.0);
    assert!(
        rep.force.y.abs() > 1e-3 * rep.force.x.abs(),
        "{}",
        rep.force
    );
    let still = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::zeros(), 1.0);
    assert!(still.force.y.abs() < 1e-12);
}

#[test]
fn repulsion_grows_as_obstacle_nears() {
    let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let mut last = 0.0;
    for x in [40.0, 30.0, 20.0, 12.0, 8.0, 6.0] {
        let rep = v.repulsion(
            Vec2::zeros(),
            0.0,
            Vec2::new(x, 0.0),
            Vec2::new(-3.0, 0.0),
            5.0,
        );
        let push = -rep.force.x;
        assert!(push >= last, "at {x}: {push} < {last}");
        last = push;
    }
    assert!(last > 0.0);
}

#[test]
fn outward_speed_raises_the_virtual_distance() {
    let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let p_o = Vec2::new(20.0, 0.0);
    let vd = |vx: f64| v.virtual_distance(Vec2::zeros(), 0.0, p_o, Vec2::new(vx, 0.0), 5.0);
    assert!(vd(-4.0) < vd(-1.0) && vd(-1.0) < vd(0.0) && vd(0.0) < vd(2.0) && vd(2.0) < vd(4.9));
    // Stationary: vd = (alpha/beta) d.
    assert!((vd(0.0) - 15.0).abs() < 1e-12);
    // Eq (4) broken on the receding side: infinite, no force.
    assert_eq!(vd(5.0), f64::INFINITY);
    assert_eq!(vd(7.0), f64::INFINITY);
}

#[test]
fn khatib_ignores_the_outward_speed() {
    let k = Vdf::khatib(1e4, 2.0, 40.0);
    let p_o = Vec2::new(20.0, 0.0);
    let a = k.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(-10.0, 3.0), 5.0);
    let b = k.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(10.0, 0.0), 5.0);
    assert_eq!(a, b);
    assert!((a.vd - 15.0).abs() < 1e-12);
    // Case 7's huge alpha = beta gives the same field.
    let v = Vdf::new(1e8, 1e8, 1e4, 2.0, 40.0);
    let c = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(-10.0, 3.0), 5.0);
    assert!((c.force - a.force).norm() < 1e-5 * a.force.norm());
}

#[test]
fn acceleration_stays_within_the_limit_including_the_carried_term() {
    // eq (12): ||P''(t_i) + F_acc/m|| <= a_max, every tick, whatever the force.
    let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let others = [obstacle(1, Vec2::new(8.0, 1.0), Vec2::new(-5.0, -3.0), 5.0)];
    let mut vel = Vec2::new(3.0, 0.0);
    for i in 0..20 {
        let s = me(Vec2::new(i as f64 * 0.1, 0.0), vel);
        let f = v.plan(&obs(s, Vec2::new(80.0, -40.0), &others)).vector();
        let a = f / s.mass;
        assert!(a.norm() <= s.max_accel * (1.0 + 1e-12), "{}", a.norm());
        assert!(v.carried_acceleration().norm() <= s.max_accel * (1.0 + 1e-12));
        vel += a * 0.1;
        // eq (16): the velocity at the end of the period within v_max.
        assert!(vel.norm() <= s.max_speed * (1.0 + 1e-9), "{}", vel.norm());
    }
}

#[test]
fn the_carried_acceleration_accumulates_the_artificial_force() {
    // eq (11): a small constant F_art adds F_art/m every period.
    let mut v = Vdf::new(5.0, 5.0, 0.0, 2.0, 40.0);
    let s = me(Vec2::zeros(), Vec2::zeros());
    let goal = Vec2::new(10.0, 0.0);
    let mut s_big = s;
    s_big.max_accel = 1e6;
    s_big.max_speed = 1e6;
    let a1 = v.plan(&obs(s_big, goal, &[])).vector() / s.mass;
    let a2 = v.plan(&obs(s_big, goal, &[])).vector() / s.mass;
    assert!((a1.x - 200.0).abs() < 1e-9, "{a1}");
    assert!((a2.x - 400.0).abs() < 1e-9, "{a2}");
}

#[test]
fn scaling_keeps_direction_and_picks_the_largest_k() {
    let a = Vec2::new(300.0, 0.0);
    let g = Vec2::new(0.0, 1000.0);
    let k = scale_to_accel_limit(a, g, 500.0);
    assert!(((a + g * k).norm() - 500.0).abs() < 1e-9);
    assert!((k - 0.4).abs() < 1e-12);
    assert_eq!(scale_to_accel_limit(a, Vec2::new(-100.0, 0.0), 500.0), 1.0);
}

#[test]
fn speed_limit_time_solves_eq_18() {
    let s = time_to_speed_limit(Vec2::new(20.0, 0.0), Vec2::new(500.0, 0.0), 30.0, 0.1);
    assert!((s.unwrap() - 0.02).abs() < 1e-12);
    assert_eq!(
        time_to_speed_limit(Vec2::new(20.0, 0.0), Vec2::new(50.0, 0.0), 30.0, 0.1),
        None
    );
    // At the limit and pushing sideways: coasts (t_v = t_i).
    let s = time_to_speed_limit(Vec2::new(30.0, 0.0), Vec2::new(0.0, 100.0), 30.0, 0.1);
    assert_eq!(s, Some(0.0));
}

#[test]
fn diagnostics_name_each_body_vd() {
    let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let others = [
        obstacle(4, Vec2::new(20.0, 0.0), Vec2::zeros(), 5.0),
        obstacle(9, Vec2::new(0.0, 30.0), Vec2::new(0.0, 10.0), 5.0),
    ];
    v.plan(&obs(
        me(Vec2::zeros(), Vec2::zeros()),
        Vec2::new(80.0, 0.0),
        &others,
    ));
    let d = v.diagnostics();
    assert_eq!(d.len(), 2);
    assert_eq!(d[0].name, "vd_4");
    assert!((d[0].value - 15.0).abs() < 1e-12);
    assert_eq!(d[1].name, "vd_9");
    assert_eq!(d[1].value, f64::INFINITY);
}

#[test]
fn the_goal_test_counts_the_robots_own_goal_hold_ticks() {
    // N = 6 from the observation: the seventh consecutive sample brakes.
    let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let goal = Vec2::new(10.0, 0.0);
    let vel = Vec2::new(2.0, 0.0);
    let s = me(Vec2::new(9.8, 0.0), vel);
    let mut o = obs(s, goal, &[]);
    o.goal_hold_ticks = 6;
    for _ in 0..6 {
        assert!(v.plan(&o).vector().x > 0.0);
    }
    let f = v.plan(&o).vector();
    assert!((f / s.mass - (-vel / 0.1)).norm() < 1e-9, "{f}");
}

#[test]
fn it_brakes_once_the_goal_test_holds() {
    let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
    let goal = Vec2::new(10.0, 0.0);
    let vel = Vec2::new(2.0, 0.0);
    let s = me(Vec2::new(9.8, 0.0), vel);
    // N = 3: the fourth consecutive sample within tolerance triggers it.
    for _ in 0..3 {
        let f = v.plan(&obs(s, goal, &[])).vector();
        assert!(f.x > 0.0);
    }
    let f = v.plan(&obs(s, goal, &[])).vector();
    assert!((f / s.mass - (-vel / 0.1)).norm() < 1e-9, "{f}");
    // Latched: a later sample outside the tolerance still brakes.
    let far = me(Vec2::new(5.0, 0.0), vel);
    let f = v.plan(&obs(far, goal, &[])).vector();
    assert!(f.x < 0.0);
}
