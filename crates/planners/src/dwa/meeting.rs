//! Keeping right on meeting (dwa from the scan, on a unicycle): when a
//! return that the map does not explain lies in the way to the goal, the
//! heading term aims that much to the right of the goal, as far as the map
//! leaves room (module documentation of `dwa`, "Keeping right").

use super::contact::time_to_segment;
use super::walls::WallGrid;
use crate::{Observation, Segment, Vec2};

/// How far ahead a return counts as meeting: the robot's look-ahead, its
/// top speed times the horizon.
fn look(obs: &Observation, horizon: f64) -> f64 {
    obs.me.max_speed * horizon
}

/// Whether the world point `w` lies within `tol` of one of `walls` (the
/// grid's), the map explaining the return there.
fn on_a_wall(
    grid: &mut WallGrid,
    walls: &[Segment],
    w: Vec2,
    tol: f64,
    buf: &mut Vec<u32>,
) -> bool {
    let t = Vec2::repeat(tol);
    grid.query(w - t, w + t, false, buf);
    buf.iter()
        .any(|&k| (walls[k as usize].closest_point(w) - w).norm() <= tol)
}

/// Whether a return the walls do not explain (another robot, a person, an
/// obstacle not on the map) lies ahead in the way to `obs.goal`: in the
/// strip the `padded` disc sweeps towards it (beyond it too: a route's goal
/// is a waypoint a little ahead), widened by another padded disc
/// (something about to enter it), up to the look-ahead. `points` are the
/// scan's returns in the robot's frame; `grid` holds `obs.walls`.
pub(super) fn in_the_way(
    obs: &Observation,
    points: &[Vec2],
    grid: &mut WallGrid,
    padded: f64,
    horizon: f64,
) -> bool {
    let me = &obs.me;
    let to_goal = obs.goal - me.position;
    let d_goal = to_goal.norm();
    if d_goal <= f64::EPSILON {
        return false;
    }
    let g = to_goal / d_goal;
    let right = Vec2::new(g.y, -g.x);
    let (s, c) = me.heading.sin_cos();
    let to_world = |q: &Vec2| Vec2::new(c * q.x - s * q.y, s * q.x + c * q.y);
    let far = look(obs, horizon);
    let half = 2.0 * padded;
    let tol = me.radius / 4.0;
    let mut buf = Vec::new();
    points.iter().any(|q| {
        let d = to_world(q);
        let along = d.dot(&g);
        along > 0.0
            && along <= far
            && d.dot(&right).abs() < half
            && !on_a_wall(grid, obs.walls, me.position + d, tol, &mut buf)
    })
}

/// `obs.goal` moved `shift` to the right of the way to it, less where the
/// walls there leave the `padded` disc less room (`grid` holds
/// `obs.walls`).
pub(super) fn right_of_goal(
    obs: &Observation,
    grid: &mut WallGrid,
    padded: f64,
    shift: f64,
) -> Vec2 {
    let to_goal = obs.goal - obs.me.position;
    let d_goal = to_goal.norm();
    if d_goal <= f64::EPSILON || shift <= 0.0 {
        return obs.goal;
    }
    let right = Vec2::new(to_goal.y, -to_goal.x) / d_goal;
    // Room to the right of the goal: how far the padded disc moves that way
    // before it touches a wall.
    let reach = Vec2::repeat(shift + padded);
    let mut buf = Vec::new();
    grid.query(obs.goal - reach, obs.goal + reach, false, &mut buf);
    let room = buf
        .iter()
        .filter_map(|&k| time_to_segment(obs.goal, right, padded, &obs.walls[k as usize]))
        .fold(shift, f64::min);
    obs.goal + right * room.max(0.0)
}
