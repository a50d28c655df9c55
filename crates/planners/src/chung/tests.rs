//! Chung's unit tests: each strategy's terms against hand-computed values,
//! and the crossing and goal experiments in the testkit.

use super::*;
use crate::testkit::Sim;
use crate::testkit::{RobotModel, observation, robot};
use crate::{SelfState, Sensed};

const ROBOT: RobotModel = RobotModel {
    radius: 0.2,
    mass: 10.0,
    damping: 0.5,
    max_speed: 5.0,
    max_accel: 5.0,
};

fn me(pos: Vec2, vel: Vec2) -> SelfState {
    ROBOT.at(pos, vel)
}

/// Another robot of the same size.
fn body(id: u32, pos: Vec2, vel: Vec2) -> Sensed {
    robot(id, pos, vel, ROBOT.radius)
}

fn force(p: &mut Chung, me: SelfState, goal: Vec2, others: &[Sensed]) -> Vec2 {
    p.plan(&observation(me, goal, others)).vector()
}

fn chung(strategy: Strategy) -> Chung {
    Chung::from_params(strategy, &Params::new()).unwrap()
}

#[test]
fn defaults_are_the_figure_captions() {
    let c1 = chung(Strategy::I);
    assert_eq!((c1.f_g, c1.alpha, c1.f_m, c1.f_v), (1.0, 0.8, 20.0, 0.0));
    let c2 = chung(Strategy::II);
    assert_eq!((c2.f_m, c2.f_v), (10.0, 0.1));
    let c3 = chung(Strategy::III);
    assert_eq!((c3.f_m, c3.f_v), (10.0, 20.0));
}

#[test]
fn strategy_one_refuses_a_velocity_constant() {
    let mut p = Params::new();
    p.insert("f_v".into(), crate::ParamValue::Number(1.0));
    assert!(Chung::from_params(Strategy::I, &p).is_err());
    assert!(Chung::from_params(Strategy::II, &p).is_ok());
}

#[test]
fn without_bodies_it_is_attraction_minus_f_g_alpha_v() {
    let mut p = chung(Strategy::III);
    p.f_g = 2.0;
    let f = force(
        &mut p,
        me(Vec2::zeros(), Vec2::new(0.0, 1.0)),
        Vec2::new(10.0, 0.0),
        &[],
    );
    assert!((f - Vec2::new(2.0, -1.6)).norm() < 1e-12, "{f}");
}

#[test]
fn repulsion_grows_as_obstacle_nears() {
    for s in [Strategy::I, Strategy::II, Strategy::III] {
        let p = chung(s);
        let goal = Vec2::new(10.0, 0.0);
        let at = |d: f64| {
            let o = [body(1, Vec2::new(d, 0.0), Vec2::new(-0.3, 0.0))];
            force(&mut p.clone(), me(Vec2::zeros(), Vec2::zeros()), goal, &o).x
        };
        // The push back (-x) grows as the obstacle ahead comes nearer.
        assert!(at(1.0) < at(2.0) && at(2.0) < at(4.0), "{s:?}");
        assert!(at(1.0) < 0.0, "{s:?}");
    }
}

#[test]
fn position_repulsion_has_the_hand_computed_value_with_its_goal_counter_term() {
    // Robot at rest at the origin, goal (10, 0), one body at rest at
    // (3, 4); Strategy I, f_g = 1, f_m = 20. By hand:
    //   attraction            (1, 0)
    //   (r_i - r_j)/|.|^3     (-3, -4)/125          = (-0.024, -0.032)
    //   (r_g - r_j)/|.|^3     (7, -4)/65^1.5        = (0.0133576, -0.0076329)
    //   f = (1, 0) + 20 [(-0.024, -0.032) - (0.0133576, -0.0076329)]
    //     = (0.2528483, -0.4873419)
    let mut p = chung(Strategy::I);
    let o = [body(1, Vec2::new(3.0, 4.0), Vec2::zeros())];
    let f = force(
        &mut p,
        me(Vec2::zeros(), Vec2::zeros()),
        Vec2::new(10.0, 0.0),
        &o,
    );
    assert!((f - Vec2::new(0.2528483, -0.4873419)).norm() < 1e-6, "{f}");
}

#[test]
fn strategy_three_velocity_term_has_the_hand_computed_value() {
    // Robot at the origin moving at (0.5, 0), goal (10, 0), one body at
    // (2, 0) moving at (-0.3, 0.4); f_v = 20. Eq (5) as we read it:
    //   (v_i - v_j) f_v / |r_i - r_j|^3 = (0.8, -0.4) 20/8   = (2, -1)
    //   - (v_g - v_j) f_v / |r_g - r_j|^3 = -(0.3, -0.4) 20/512
    //                                     = (-0.01171875, 0.015625)
    // so Strategy III's force is Strategy I's (same f_m) plus
    // (1.98828125, -0.984375); and in full, with attraction (1, 0),
    // damping -0.8 (0.5, 0) and position repulsion
    // 10 [(-2, 0)/8 - (8, 0)/512] = (-2.65625, 0):
    //   (-0.06796875, -0.984375).
    let o = [body(1, Vec2::new(2.0, 0.0), Vec2::new(-0.3, 0.4))];
    let at = me(Vec2::zeros(), Vec2::new(0.5, 0.0));
    let goal = Vec2::new(10.0, 0.0);
    let f3 = force(&mut chung(Strategy::III), at, goal, &o);
    let mut one = chung(Strategy::I);
    one.f_m = 10.0;
    let f1 = force(&mut one, at, goal, &o);
    assert!(
        (f3 - f1 - Vec2::new(1.98828125, -0.984375)).norm() < 1e-12,
        "{}",
        f3 - f1
    );
    assert!(
        (f3 - Vec2::new(-0.06796875, -0.984375)).norm() < 1e-12,
        "{f3}"
    );
}

#[test]
fn the_goal_is_an_equilibrium_because_the_counter_terms_cancel_the_bodies_there() {
    // At the goal at rest each term is its own value minus its value at
    // the goal, so the force vanishes whatever the bodies do. That alone
    // would hold for any kernel; what makes it the paper's equilibrium is
    // that the same bodies push hard 5 cm away (the hand-computed kernel
    // is pinned by the two tests above).
    let goal = Vec2::new(3.0, 1.0);
    let others = [
        body(1, Vec2::new(4.0, 1.5), Vec2::new(0.2, -0.1)),
        body(2, Vec2::new(2.0, 0.0), Vec2::new(-0.4, 0.3)),
    ];
    for s in [Strategy::I, Strategy::II, Strategy::III] {
        let mut p = chung(s);
        let f = force(&mut p, me(goal, Vec2::zeros()), goal, &others);
        assert!(f.norm() < 1e-12, "{s:?}: {f}");
        let near = me(goal + Vec2::new(0.05, 0.0), Vec2::zeros());
        let with = force(&mut chung(s), near, goal, &others);
        let without = force(&mut chung(s), near, goal, &[]);
        assert!((with - without).norm() > 0.1, "{s:?}: {}", with - without);
    }
}

#[test]
fn strategy_two_pushes_along_its_own_velocity_when_bodies_rest() {
    // Sensed body at rest: eq (4)'s term is f_v v_i/||v_i||^3, growing
    // as the robot slows.
    let mut p = chung(Strategy::II);
    p.f_m = 0.0;
    p.alpha = 0.0;
    let goal = Vec2::new(0.0, 0.0);
    let o = [body(1, Vec2::new(5.0, 5.0), Vec2::zeros())];
    let slow = force(&mut p, me(goal, Vec2::new(0.01, 0.0)), goal, &o);
    let fast = force(&mut p, me(goal, Vec2::new(0.1, 0.0)), goal, &o);
    assert!((slow.x - 0.1 / 1e-4).abs() < 1e-6, "{slow}");
    assert!(slow.x > fast.x && fast.x > 0.0);
}

#[test]
fn strategy_three_velocity_term_fades_with_distance() {
    let mut p = chung(Strategy::III);
    p.f_m = 0.0;
    p.alpha = 0.0;
    let goal = Vec2::new(0.0, 0.0);
    let pos = Vec2::new(-20.0, 0.0);
    let near = [body(1, Vec2::new(-19.0, 0.0), Vec2::new(-1.0, 0.0))];
    let far = [body(1, Vec2::new(-16.0, 0.0), Vec2::new(-1.0, 0.0))];
    let attraction = 1.0;
    let fn_ = force(&mut p, me(pos, Vec2::zeros()), goal, &near).x - attraction;
    let ff = force(&mut p, me(pos, Vec2::zeros()), goal, &far).x - attraction;
    assert!(fn_ > ff && ff > 0.0, "{fn_} {ff}");
}

#[test]
fn strategy_one_passes_a_crossing_robot_and_reaches_the_goal() {
    let mut sim = Sim::new(0.1, 10);
    let r0 = sim.add_robot(
        Box::new(chung(Strategy::I)),
        Vec2::zeros(),
        Vec2::new(10.0, 0.0),
        0.2,
        10.0,
        0.5,
        2.0,
        5.0,
    );
    sim.add_obstacle(Vec2::new(5.0, -5.0), Vec2::new(0.0, 0.4), 0.2);
    let mut min_clear = f64::INFINITY;
    for _ in 0..1500 {
        sim.step();
        min_clear = min_clear.min(sim.clearance(r0));
    }
    assert!(min_clear > 0.0, "collided: {min_clear}");
    let end = sim.robots[r0].state.position;
    assert!((end - Vec2::new(10.0, 0.0)).norm() < 0.3, "{end}");
}

/// The chung-strategy-{2,3} scenarios: returns the robot's largest
/// distance to its goal from 200 s to 300 s, the number of sign changes
/// of x - 10 in that window, and its smallest clearance.
fn crossing_scenario(strategy: Strategy, f_v: f64) -> (f64, usize, f64) {
    let mut sim = Sim::new(0.1, 10);
    let goal = Vec2::new(10.0, 0.0);
    let mut planner = chung(strategy);
    planner.f_m = 10.0;
    planner.f_v = f_v;
    let r0 = sim.add_robot(
        Box::new(planner),
        Vec2::zeros(),
        goal,
        0.2,
        10.0,
        0.5,
        2.0,
        1.0,
    );
    for (start, end) in [((4.0, -5.0), (4.0, 5.0)), ((7.0, 6.0), (7.0, -4.0))] {
        let h = crate::homing::Homing {
            f_g: 1.0,
            alpha: 0.8,
        };
        sim.add_robot(
            Box::new(h),
            Vec2::new(start.0, start.1),
            Vec2::new(end.0, end.1),
            0.2,
            10.0,
            0.5,
            2.0,
            1.0,
        );
    }
    let (mut dev, mut changes, mut min_clear, mut last) = (0.0f64, 0, f64::INFINITY, 0.0);
    for tick in 1..=3000 {
        sim.step();
        min_clear = min_clear.min(sim.clearance(r0));
        if tick > 2000 {
            let p = sim.robots[r0].state.position;
            dev = dev.max((p - goal).norm());
            let e = p.x - goal.x;
            if e * last < 0.0 {
                changes += 1;
            }
            if e != 0.0 {
                last = e;
            }
        }
    }
    (dev, changes, min_clear)
}

#[test]
fn scenario_files_carry_the_numbers_these_tests_use() {
    let two = include_str!("../../../../scenarios/papers/chung-strategy-2.toml");
    let three = include_str!("../../../../scenarios/papers/chung-strategy-3.toml");
    for (text, f_v) in [(two, "0.1"), (three, "20.0")] {
        assert!(text.contains(&format!("f_g = 1.0, alpha = 0.8, f_m = 10.0, f_v = {f_v}")));
        assert!(text.contains("mass = 10.0") && text.contains("damping = 0.5"));
        assert!(text.contains("max_speed = 2.0") && text.contains("max_accel = 1.0"));
        assert!(text.contains("radius = 0.2") && text.contains("goal = [10.0, 0.0]"));
        assert!(text.contains("start = [4.0, -5.0]") && text.contains("goal = [4.0, 5.0]"));
        assert!(text.contains("start = [7.0, 6.0]") && text.contains("goal = [7.0, -4.0]"));
        assert!(text.contains("params = { f_g = 1.0, alpha = 0.8 }"));
    }
}

#[test]
fn strategy_two_keeps_oscillating_around_the_goal() {
    let (dev, changes, min_clear) = crossing_scenario(Strategy::II, 0.1);
    assert!(dev > 1.0, "{dev}");
    assert!(changes >= 3, "{changes}");
    assert!(min_clear > 0.0);
}

#[test]
fn strategy_three_settles_at_the_goal() {
    let (dev, _, min_clear) = crossing_scenario(Strategy::III, 20.0);
    assert!(dev < 0.1, "{dev}");
    assert!(min_clear > 0.0);
}
