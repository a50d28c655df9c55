//! The trajectory-guided planner's unit tests: the candidates, the
//! prediction of the obstacles, the choice, and crossings in the testkit.

use super::*;
use crate::testkit::{RobotModel, Sim, observation, obstacle};
use crate::{ParamValue, SelfState, Sensed};

const ROBOT: RobotModel = RobotModel::unit(0.3);

fn me(position: Vec2, velocity: Vec2) -> SelfState {
    ROBOT.at(position, velocity)
}

fn planner() -> TrajectoryGuided {
    TrajectoryGuided::from_params(&Params::new()).unwrap()
}

#[test]
fn free_scene_goes_straight_to_the_goal_at_full_speed() {
    let mut p = planner();
    let obs = observation(me(Vec2::zeros(), Vec2::zeros()), Vec2::new(10.0, 0.0), &[]);
    let v = p.plan(&obs).vector();
    assert!((v - Vec2::new(1.0, 0.0)).norm() < 1e-12, "{v}");
    assert_eq!(p.last_choice().unwrap().rank, 0);
}

#[test]
fn goal_candidate_slows_down_to_stop_at_the_goal() {
    let mut p = planner();
    let obs = observation(
        me(Vec2::new(9.96, 0.0), Vec2::new(0.4, 0.0)),
        Vec2::new(10.0, 0.0),
        &[],
    );
    let v = p.plan(&obs).vector();
    // d / Δt = 0.4: reach the goal in one tick, no overshoot.
    assert!((v.x - 0.4).abs() < 1e-9 && v.y.abs() < 1e-12, "{v}");
}

#[test]
fn candidates_are_ordered_goal_then_inherited_then_by_progress() {
    let mut p = planner();
    p.inherited = Some(Vec2::new(0.0, 1.0));
    let obs = observation(me(Vec2::zeros(), Vec2::zeros()), Vec2::new(10.0, 0.0), &[]);
    let c = p.candidates_in_order(&obs);
    assert_eq!(c.len(), 32);
    assert_eq!(c[0].origin, Origin::Goal);
    assert_eq!(c[1].origin, Origin::Inherited);
    // Full speed straight at the goal (the same as the goal candidate
    // here) leads the rest; backing away at full speed comes last.
    assert!((c[2].velocity - Vec2::new(1.0, 0.0)).norm() < 1e-12);
    // Then everything that gets closer to the goal, standing still, and
    // what does not get closer; backing straight away fell off the list.
    let stop = c.iter().position(|c| c.origin == Origin::Stop).unwrap();
    assert!(c[2..stop].iter().all(|c| c.velocity.x > 0.0));
    assert!(c[stop + 1..].iter().all(|c| c.velocity.x <= 1e-9));
    assert!(
        c.iter()
            .all(|c| (c.velocity - Vec2::new(-1.0, 0.0)).norm() > 1e-9)
    );
}

#[test]
fn obstacle_on_the_straight_line_is_predicted_and_the_goal_candidate_refused() {
    let mut p = planner();
    // Crossing obstacle that will be at (1.5, 0) in 1.5 s, when the robot
    // would be there too.
    let others = [obstacle(5, Vec2::new(1.5, -1.5), Vec2::new(0.0, 1.0), 0.3)];
    let obs = observation(
        me(Vec2::zeros(), Vec2::new(1.0, 0.0)),
        Vec2::new(10.0, 0.0),
        &others,
    );
    p.plan(&obs);
    let c = p.last_choice().unwrap();
    assert_ne!(c.candidate.origin, Origin::Goal);
    assert_eq!(c.free_steps, c.steps);
}

fn crossing(planner: Box<dyn Planner>) -> (f64, f64) {
    // Robot from (0, 0) to (8, 0) at up to 1 m/s; an obstacle crosses
    // its line at x = 4, timed to arrive there when the robot does.
    let mut sim = Sim::new(0.1, 10);
    sim.add_robot(
        planner,
        Vec2::new(0.0, 0.0),
        Vec2::new(8.0, 0.0),
        0.3,
        1.0,
        0.0,
        1.0,
        2.0,
    );
    sim.add_obstacle(Vec2::new(4.0, -4.25), Vec2::new(0.0, 1.0), 0.4);
    let mut min_clearance = f64::INFINITY;
    for _ in 0..200 {
        sim.step();
        min_clearance = min_clearance.min(sim.clearance(0));
    }
    let left = (sim.robots[0].state.position - Vec2::new(8.0, 0.0)).norm();
    (min_clearance, left)
}

struct Straight;
impl Planner for Straight {
    fn plan(&mut self, obs: &Observation) -> Command {
        let e = obs.goal - obs.me.position;
        Command::Velocity(e * (obs.me.max_speed / e.norm().max(obs.me.max_speed * obs.dt)))
    }
}

#[test]
fn a_single_crossing_obstacle_is_avoided_and_the_goal_reached() {
    // The crossing is a real threat: going straight collides.
    let (straight_clearance, _) = crossing(Box::new(Straight));
    assert!(straight_clearance < 0.0, "{straight_clearance}");
    for prediction in ["anticipation", "extended", "probabilistic"] {
        let mut params = Params::new();
        params.insert("prediction".into(), ParamValue::Text(prediction.into()));
        let p = TrajectoryGuided::from_params(&params).unwrap();
        let (clearance, left) = crossing(Box::new(p));
        assert!(clearance > 0.0, "{prediction}: clearance {clearance}");
        assert!(left < 0.05, "{prediction}: {left} from the goal");
    }
}

#[test]
fn when_nothing_is_free_the_candidate_free_longest_is_taken() {
    let mut p = planner();
    // Surrounded by a ring of obstacles closing in: every candidate
    // collides; the chosen one must be free at least as long as any.
    let others: Vec<Sensed> = (0..12)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 12.0;
            let dir = Vec2::new(a.cos(), a.sin());
            obstacle(i, dir * (1.2 + 0.1 * i as f64), -dir * 0.5, 0.4)
        })
        .collect();
    let obs = observation(
        me(Vec2::zeros(), Vec2::zeros()),
        Vec2::new(10.0, 0.0),
        &others,
    );
    p.plan(&obs);
    let chosen = p.last_choice().unwrap();
    assert!(chosen.free_steps < chosen.steps);
    let steps = chosen.steps;
    let cands = p.candidates_in_order(&obs);
    let best = cands
        .iter()
        .map(|c| p.free_steps(&obs, c, steps))
        .max()
        .unwrap();
    assert_eq!(chosen.free_steps, best);
}

#[test]
fn a_wall_across_the_way_is_not_crossed() {
    let walls = [Segment {
        a: Vec2::new(1.0, -0.5),
        b: Vec2::new(1.0, 0.5),
    }];
    let mut p = planner();
    let mut obs = observation(me(Vec2::zeros(), Vec2::zeros()), Vec2::new(5.0, 0.0), &[]);
    obs.walls = &walls;
    p.plan(&obs);
    assert_ne!(p.last_choice().unwrap().candidate.origin, Origin::Goal);
}

#[test]
fn parameters_are_checked() {
    let mut params = Params::new();
    params.insert("candidates".into(), ParamValue::Number(2.0));
    assert!(TrajectoryGuided::from_params(&params).is_err());
    let mut params = Params::new();
    params.insert("grid".into(), ParamValue::Number(0.1));
    assert!(TrajectoryGuided::from_params(&params).is_err());
}
