//! The designated-path planner's unit tests: the cone and tangent geometry,
//! eq 1's cost, the subgoals, and the fig 8 experiments in the testkit.

use super::*;
use crate::testkit::{RobotModel, Sim, observation, obstacle};
use crate::{SelfState, Sensed};

// The fig 8 experiment, with the constants of
// scenarios/papers/yamada-{behind,front,side}.toml.
const DT: f64 = 0.1;
const SUBSTEPS: u32 = 10;
const ROBOT_RADIUS: f64 = 0.2;
const OBSTACLE_RADIUS: f64 = 0.2;
const MAX_SPEED: f64 = 0.5;
const MAX_ACCEL: f64 = 0.5;
const NOMINAL: f64 = 0.2;
const BOUNDARY: f64 = 1.0;
const GOAL: [f64; 2] = [5.0, 0.0];
const DURATION: f64 = 40.0;
// yamada-behind: 1 m behind, 0.5 m right, 0.3 m/s towards the point
// x = 2.0806 of the path that the robot reaches at nominal speed at the
// same time (t = 10.4 s).
const BEHIND: ([f64; 2], [f64; 2]) = ([-1.0, -0.5], [0.296127, 0.048063]);
// yamada-front: 2 m ahead, head-on at 0.3 m/s.
const FRONT: ([f64; 2], [f64; 2]) = ([2.0, 0.0], [-0.3, 0.0]);
// yamada-side: 1 m right, 1 m ahead, 0.3 m/s to the left.
const SIDE: ([f64; 2], [f64; 2]) = ([1.0, -1.0], [0.0, 0.3]);

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

fn planner() -> DesignatedPathPlanner {
    DesignatedPathPlanner::from_params(&Params::new()).unwrap()
}

const ROBOT: RobotModel = RobotModel {
    radius: ROBOT_RADIUS,
    mass: 1.0,
    damping: 0.0,
    max_speed: MAX_SPEED,
    max_accel: MAX_ACCEL,
};

fn me(p: Vec2, vel: Vec2) -> SelfState {
    ROBOT.at(p, vel)
}

fn obs<'a>(
    me: SelfState,
    goal: Vec2,
    others: &'a [Sensed],
    path: Option<&'a DesignatedPath>,
) -> Observation<'a> {
    Observation {
        dt: DT,
        goal_tolerance: 0.1,
        path,
        ..observation(me, goal, others)
    }
}

fn straight_path(boundary: f64) -> DesignatedPath {
    DesignatedPath {
        points: vec![Vec2::zeros(), v(GOAL[0], GOAL[1])],
        boundary,
    }
}

fn fig8(case: ([f64; 2], [f64; 2])) -> Sim {
    let mut sim = Sim::new(DT, SUBSTEPS);
    let i = sim.add_robot(
        Box::new(planner()),
        Vec2::zeros(),
        v(GOAL[0], GOAL[1]),
        ROBOT_RADIUS,
        1.0,
        0.0,
        MAX_SPEED,
        MAX_ACCEL,
    );
    sim.robots[i].path = Some(straight_path(BOUNDARY));
    sim.add_obstacle(
        v(case.0[0], case.0[1]),
        v(case.1[0], case.1[1]),
        OBSTACLE_RADIUS,
    );
    sim
}

/// Per tick: robot position, robot speed, obstacle position, clearance.
struct Trace {
    pos: Vec<Vec2>,
    speed: Vec<f64>,
    obstacle: Vec<Vec2>,
    clearance: Vec<f64>,
}

fn run(mut sim: Sim, seconds: f64) -> Trace {
    let mut tr = Trace {
        pos: vec![],
        speed: vec![],
        obstacle: vec![],
        clearance: vec![],
    };
    for _ in 0..(seconds / DT).round() as u64 {
        sim.step();
        tr.pos.push(sim.robots[0].state.position);
        tr.speed.push(sim.robots[0].state.velocity.norm());
        tr.obstacle.push(sim.obstacles[0].position);
        tr.clearance.push(sim.clearance(0));
    }
    tr
}

/// No contact, never out of the corridor, the goal reached.
fn assert_safe_and_arrives(tr: &Trace) {
    let min_clearance = tr.clearance.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(min_clearance > 0.0, "collision: clearance {min_clearance}");
    let path = straight_path(BOUNDARY);
    let worst = tr
        .pos
        .iter()
        .map(|p| distance_to_path(&path.points, *p))
        .fold(0.0, f64::max);
    assert!(worst <= BOUNDARY, "left the corridor by {worst}");
    let end = *tr.pos.last().unwrap();
    assert!((end - v(GOAL[0], GOAL[1])).norm() < 0.1, "ended at {end}");
}

#[test]
fn tangent_points_of_a_circle_seen_from_the_robot() {
    // Circle at (2, 0) of radius 1 seen from the origin: tangent length
    // sqrt(3), half-angle 30 degrees.
    let c = Cylinder::new(Vec2::zeros(), v(2.0, 0.0), Vec2::zeros(), 1.0);
    let [left, right] = c.tangents.unwrap();
    let h = 3f64.sqrt() / 2.0;
    assert!((left - v(1.5, h)).norm() < 1e-12, "{left}");
    assert!((right - v(1.5, -h)).norm() < 1e-12, "{right}");
    // From inside there is no tangent.
    assert!(
        Cylinder::new(Vec2::zeros(), v(0.5, 0.0), Vec2::zeros(), 1.0)
            .tangents
            .is_none()
    );
}

#[test]
fn cone_meets_the_avoiding_line_where_computed_by_hand() {
    // Avoiding line through (0, 1) moving at (0.3, 0); cone of 0.5 m/s:
    // 1 + 0.09 t^2 = 0.25 t^2  ->  t = 2.5 s, via point (0.75, 1).
    let t = cone_meets_avoiding_line(v(0.0, 1.0), v(0.3, 0.0), 0.5).unwrap();
    assert!((t - 2.5).abs() < 1e-12, "{t}");
    let via = v(0.0, 1.0) + v(0.3, 0.0) * t;
    assert!((via - v(0.75, 1.0)).norm() < 1e-12);
    assert!((via.norm() - 0.5 * t).abs() < 1e-12, "via is on the cone");
    // At 0.2 m/s the line runs away faster than the cone widens.
    assert!(cone_meets_avoiding_line(v(0.0, 1.0), v(0.3, 0.0), 0.2).is_none());
    // A still line is met at |w| / v.
    let t = cone_meets_avoiding_line(v(3.0, 4.0), Vec2::zeros(), 0.5).unwrap();
    assert!((t - 10.0).abs() < 1e-12);
}

#[test]
fn eq_1_adds_the_four_weighted_terms() {
    let c = Candidate {
        speed: 0.5,
        via: v(1.0, 0.0),
        dist: 5.0,
        theta: 0.1,
        outside: 0.0,
        second_leg_blocked: false,
        turn: 0.0,
    };
    let w = planner().weights;
    // 0.1 * 5 + 0.001 * 10 + 0.08 * 0.3 + 0.3 * 0.1
    assert!((c.cost(&w, 0.2) - 0.564).abs() < 1e-12);
}

fn cand(speed: f64, dist: f64, theta: f64, outside: f64) -> Candidate {
    Candidate {
        speed,
        via: v(1.0, theta),
        dist,
        theta,
        outside,
        second_leg_blocked: false,
        turn: 0.0,
    }
}

#[test]
fn eq_1_picks_the_lower_cost_candidate() {
    let w = planner().weights;
    let slow = cand(0.1, 5.0, 0.0, 0.0);
    let fast_turning = cand(0.5, 5.2, 0.4, 0.0);
    assert!(slow.cost(&w, 0.2) < fast_turning.cost(&w, 0.2));
    assert_eq!(choose(&[fast_turning, slow], &w, 0.2), Some(slow));
    let fast_straight = cand(0.3, 5.0, 0.0, 0.0);
    assert!(fast_straight.cost(&w, 0.2) < slow.cost(&w, 0.2));
    assert_eq!(
        choose(&[slow, fast_turning, fast_straight], &w, 0.2),
        Some(fast_straight)
    );
}

#[test]
fn via_points_outside_the_boundary_are_dropped() {
    let w = planner().weights;
    let cheap_but_out = cand(0.2, 5.0, 0.0, 0.3);
    let dear_but_in = cand(0.1, 6.0, 0.5, 0.0);
    assert_eq!(
        choose(&[cheap_but_out, dear_but_in], &w, 0.2),
        Some(dear_but_in)
    );
    // All out: the least out stays.
    let less_out = cand(0.1, 6.0, 0.5, 0.1);
    assert_eq!(choose(&[cheap_but_out, less_out], &w, 0.2), Some(less_out));
}

#[test]
fn head_on_obstacle_is_passed_left_unless_the_left_is_out_of_bounds() {
    let others = [obstacle(1, v(2.0, 0.0), v(-0.3, 0.0), OBSTACLE_RADIUS)];
    let me = me(Vec2::zeros(), v(NOMINAL, 0.0));
    let wide = straight_path(BOUNDARY);
    let cmd = planner()
        .plan(&obs(me, v(5.0, 0.0), &others, Some(&wide)))
        .vector();
    assert!(cmd.y > 0.0, "turns left on a tie: {cmd}");
    // The same path shifted 0.5 m to the right with a 0.8 m boundary:
    // the left via point (y ~ +0.4) is 0.9 m from it, the right one in.
    let shifted = DesignatedPath {
        points: vec![v(0.0, -0.5), v(5.0, -0.5)],
        boundary: 0.8,
    };
    let mut p = planner();
    let cmd = p
        .plan(&obs(me, v(5.0, -0.5), &others, Some(&shifted)))
        .vector();
    assert!(cmd.y < 0.0, "the left detour is out of bounds: {cmd}");
    assert!(
        p.cands.iter().any(|c| c.outside > 0.0),
        "some via point was out"
    );
}

#[test]
fn goes_straight_at_nominal_speed_when_nothing_crosses() {
    // An obstacle behind and moving away crosses nothing.
    let others = [obstacle(1, v(-2.0, 0.5), v(-0.3, 0.0), OBSTACLE_RADIUS)];
    let path = straight_path(BOUNDARY);
    let mut p = planner();
    let cmd = p
        .plan(&obs(
            me(Vec2::zeros(), Vec2::zeros()),
            v(5.0, 0.0),
            &others,
            Some(&path),
        ))
        .vector();
    assert!((cmd - v(NOMINAL, 0.0)).norm() < 1e-12, "{cmd}");
    let d = p.diagnostics();
    assert_eq!(d[0].name, "speed");
    assert!((d[0].value - NOMINAL).abs() < 1e-12);
    assert_eq!(d[1].name, "subgoal");
}

fn corner_path() -> DesignatedPath {
    DesignatedPath {
        points: vec![v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0)],
        boundary: 1.0,
    }
}

#[test]
fn a_subgoal_an_obstacle_sits_on_is_skipped() {
    let path = corner_path();
    let at = me(v(1.0, 0.0), v(NOMINAL, 0.0));
    // Free corner: the robot heads for it (subgoal 1).
    let mut p = planner();
    let cmd = p.plan(&obs(at, v(2.0, 2.0), &[], Some(&path))).vector();
    assert_eq!(p.current_subgoal(), 1);
    assert!(cmd.y.abs() < 1e-12 && cmd.x > 0.0, "{cmd}");
    // A standing body on the corner: given up, on to (2, 2).
    let others = [obstacle(1, v(2.0, 0.1), Vec2::zeros(), OBSTACLE_RADIUS)];
    let mut p = planner();
    let cmd = p.plan(&obs(at, v(2.0, 2.0), &others, Some(&path))).vector();
    assert_eq!(p.current_subgoal(), 2);
    assert!(cmd.y > 0.0, "heads for the next subgoal: {cmd}");
}

#[test]
fn at_a_junction_the_robot_goes_to_the_corner_before_turning() {
    let path = corner_path();
    let mut p = planner();
    // Within the threshold but short of the vertex: keep the corner.
    p.plan(&obs(
        me(v(1.9, 0.05), v(NOMINAL, 0.0)),
        v(2.0, 2.0),
        &[],
        Some(&path),
    ));
    assert_eq!(p.current_subgoal(), 1);
    // Level with it: turn.
    let cmd = p
        .plan(&obs(
            me(v(2.01, 0.0), v(NOMINAL, 0.0)),
            v(2.0, 2.0),
            &[],
            Some(&path),
        ))
        .vector();
    assert_eq!(p.current_subgoal(), 2);
    assert!(cmd.y > 0.0);
}

#[test]
fn without_a_path_the_goal_is_the_only_subgoal() {
    let mut p = planner();
    let cmd = p
        .plan(&obs(
            me(Vec2::zeros(), Vec2::zeros()),
            v(0.0, 3.0),
            &[],
            None,
        ))
        .vector();
    assert_eq!(p.subgoal_list().len(), 1);
    assert!((cmd - v(0.0, NOMINAL)).norm() < 1e-12);
}

#[test]
fn distance_to_path_is_to_the_nearest_segment() {
    let pts = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0)];
    assert!((distance_to_path(&pts, v(1.0, 0.5)) - 0.5).abs() < 1e-12);
    assert!((distance_to_path(&pts, v(3.0, 1.0)) - 1.0).abs() < 1e-12);
    assert!((distance_to_path(&pts, v(-3.0, 4.0)) - 5.0).abs() < 1e-12);
    assert!((distance_to_path(&pts[..1], v(3.0, 4.0)) - 5.0).abs() < 1e-12);
    assert_eq!(distance_to_path(&[], v(1.0, 1.0)), f64::INFINITY);
}

#[test]
fn fig_8_from_behind_the_robot_speeds_up_and_runs_ahead() {
    let tr = run(fig8(BEHIND), DURATION);
    assert_safe_and_arrives(&tr);
    // Before the obstacle has come level with the robot.
    let before: Vec<usize> = (0..tr.pos.len())
        .filter(|&k| tr.obstacle[k].x < tr.pos[k].x - 0.5)
        .collect();
    let fastest = before.iter().map(|&k| tr.speed[k]).fold(0.0, f64::max);
    assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
    // Ahead of where nominal speed would have put it at t = 10 s.
    assert!(tr.pos[99].x > NOMINAL * 10.0 + 0.3, "{}", tr.pos[99]);
    // On the path, not around the obstacle.
    assert!(tr.pos.iter().all(|p| p.y.abs() < 0.05));
}

#[test]
fn fig_8_from_the_front_the_robot_turns_left_to_pass() {
    let tr = run(fig8(FRONT), DURATION);
    assert_safe_and_arrives(&tr);
    let left = tr.pos.iter().map(|p| p.y).fold(f64::MIN, f64::max);
    let right = tr.pos.iter().map(|p| p.y).fold(f64::MAX, f64::min);
    assert!(left > 0.2, "deviates left by {left}");
    assert!(right > -0.05, "never right: {right}");
    // Fig 9b: accelerated while turning.
    let fastest = tr.speed.iter().copied().fold(0.0, f64::max);
    assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
}

#[test]
fn fig_8_from_the_side_the_robot_slows_down_and_lets_it_pass() {
    let tr = run(fig8(SIDE), DURATION);
    assert_safe_and_arrives(&tr);
    // While the obstacle has not yet crossed the path (after the first
    // second: from rest the robot reaches nominal speed in 0.4 s).
    let crossing: Vec<usize> = (0..tr.pos.len())
        .filter(|&k| tr.obstacle[k].y < 0.0)
        .collect();
    let slowest = crossing
        .iter()
        .filter(|&&k| k >= 9)
        .map(|&k| tr.speed[k])
        .fold(1.0, f64::min);
    assert!(slowest < NOMINAL - 0.05, "slowest {slowest}");
    // It lets the obstacle pass ahead: behind the crossing line when
    // the obstacle is on the path, and it does not swerve.
    let k = *crossing.last().unwrap();
    assert!(tr.pos[k].x < SIDE.0[0] - 0.4, "at {}", tr.pos[k]);
    assert!(tr.pos.iter().all(|p| p.y.abs() < 0.05));
    // Then resumes the nominal speed.
    assert!((tr.speed[150] - NOMINAL).abs() < 1e-6);
}

#[test]
fn side_obstacle_arriving_together_is_passed_in_front_at_speed() {
    // Not a paper case: the side obstacle 2/3 m ahead, so that both
    // centres would reach the crossing at once at nominal speed.
    let tr = run(fig8(([2.0 / 3.0, -1.0], SIDE.1)), DURATION);
    assert_safe_and_arrives(&tr);
    let k = (0..tr.pos.len())
        .find(|&k| tr.obstacle[k].y >= 0.0)
        .unwrap();
    assert!(tr.pos[k].x > 2.0 / 3.0 + 0.4, "ahead of it: {}", tr.pos[k]);
    let fastest = tr.speed[..k].iter().copied().fold(0.0, f64::max);
    assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
}

#[test]
fn corner_path_with_an_obstacle_crossing_the_corner() {
    // scenarios/papers/yamada-corners.toml: the path turns at (3, 0) and
    // (3, 3); a body crosses the first corner as the robot reaches it.
    let path = DesignatedPath {
        points: vec![v(0.0, 0.0), v(3.0, 0.0), v(3.0, 3.0), v(6.0, 3.0)],
        boundary: 0.8,
    };
    let mut sim = Sim::new(DT, SUBSTEPS);
    sim.add_robot(
        Box::new(planner()),
        Vec2::zeros(),
        v(6.0, 3.0),
        ROBOT_RADIUS,
        1.0,
        0.0,
        MAX_SPEED,
        MAX_ACCEL,
    );
    sim.robots[0].path = Some(path.clone());
    sim.add_obstacle(v(3.0, -3.0), v(0.0, 0.2), OBSTACLE_RADIUS);
    let mut worst = 0.0f64;
    let mut min_clearance = f64::INFINITY;
    let mut turned_at = None;
    for _ in 0..600 {
        sim.step();
        let p = sim.robots[0].state.position;
        worst = worst.max(distance_to_path(&path.points, p));
        min_clearance = min_clearance.min(sim.clearance(0));
        if turned_at.is_none() && p.y > 0.5 {
            turned_at = Some(p);
        }
    }
    // The body reaches the corner with the robot: the corner subgoal is
    // given up (fig 3), so the robot turns short of the vertex instead
    // of going level with it first.
    let turned_at = turned_at.unwrap();
    assert!(turned_at.x < 3.0, "turned at {turned_at}");
    assert!(min_clearance > 0.0, "collision: {min_clearance}");
    assert!(worst <= path.boundary, "out of the corridor by {worst}");
    let end = sim.robots[0].state.position;
    assert!((end - v(6.0, 3.0)).norm() < 0.1, "ended at {end}");
}
