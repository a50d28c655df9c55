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
    let Some((g, right, _)) = goal_axes(obs) else {
        return false;
    };
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

/// The unit vector from the robot to its goal, the one to its right, and
/// the distance; `None` at the goal.
fn goal_axes(obs: &Observation) -> Option<(Vec2, Vec2, f64)> {
    let to_goal = obs.goal - obs.me.position;
    let d_goal = to_goal.norm();
    if d_goal <= f64::EPSILON {
        return None;
    }
    let g = to_goal / d_goal;
    Some((g, Vec2::new(g.y, -g.x), d_goal))
}

/// Whether another body (true states) lies ahead in the way to
/// `obs.goal`: its nearest point, its centre less its circumscribed
/// radius, within twice `half` of the line to the goal (the strip the
/// robot's padded footprint, `half` to either side of its centre, sweeps,
/// widened by another as wide), up to the look-ahead.
pub(super) fn body_in_the_way(obs: &Observation, half: f64, horizon: f64) -> bool {
    let me = &obs.me;
    let Some((g, right, _)) = goal_axes(obs) else {
        return false;
    };
    let far = look(obs, horizon);
    obs.others.iter().any(|o| {
        let d = o.position - me.position;
        let along = d.dot(&g) + o.radius;
        along > 0.0 && along - 2.0 * o.radius <= far && d.dot(&right).abs() - o.radius < 2.0 * half
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
    let Some((_, right, _)) = goal_axes(obs).filter(|_| shift > 0.0) else {
        return obs.goal;
    };
    // Room to the right of the goal: how far the padded disc moves that way
    // before it touches a wall.
    let room = room_right(obs, grid, obs.goal, right, padded, shift);
    obs.goal + right * room.max(0.0)
}

/// How far the disc of radius `padded` at `at` moves along `right` before
/// it touches one of the walls (`grid` holds `obs.walls`), up to `shift`.
fn room_right(
    obs: &Observation,
    grid: &mut WallGrid,
    at: Vec2,
    right: Vec2,
    padded: f64,
    shift: f64,
) -> f64 {
    let reach = Vec2::repeat(shift + padded);
    let mut buf = Vec::new();
    grid.query(at - reach, at + reach, false, &mut buf);
    buf.iter()
        .filter_map(|&k| time_to_segment(at, right, padded, &obs.walls[k as usize]))
        .fold(shift, f64::min)
}

/// [`right_of_goal`] for a footprint on true states: the shift is as far
/// as the walls leave room beside the whole way to the goal (sampled every
/// `padded`, from the robot's own position on), not only beside the goal,
/// so that a robot in a door or about to enter one does not swerve into
/// its jamb.
pub(super) fn right_of_way(
    obs: &Observation,
    grid: &mut WallGrid,
    padded: f64,
    shift: f64,
) -> Vec2 {
    let Some((_, right, d_goal)) = goal_axes(obs).filter(|_| shift > 0.0 && padded > 0.0) else {
        return obs.goal;
    };
    let to_goal = obs.goal - obs.me.position;
    let n = (d_goal / padded).ceil().max(1.0) as usize;
    let room = (0..=n)
        .map(|k| obs.me.position + to_goal * (k as f64 / n as f64))
        .map(|at| room_right(obs, grid, at, right, padded, shift))
        .fold(shift, f64::min);
    obs.goal + right * room.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{RobotModel, observation};

    const ROBOT: RobotModel = RobotModel::unit(0.25);
    const PADDED: f64 = 0.3125;

    fn wall(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
        Segment {
            a: Vec2::new(ax, ay),
            b: Vec2::new(bx, by),
        }
    }

    /// The returns of a disc of radius 0.25 at `c` that face the origin.
    fn disc_returns(c: Vec2) -> Vec<Vec2> {
        (0..16)
            .map(|k| {
                let a = std::f64::consts::PI * (0.5 + k as f64 / 15.0);
                c + Vec2::new(a.cos(), a.sin()) * 0.25
            })
            .collect()
    }

    #[test]
    fn another_body_in_the_way_is_met_and_a_wall_or_what_is_behind_is_not() {
        // A corridor along x, 1.85 m wide, with a pillar wall across its
        // middle 2 m ahead; the robot at the origin heading for (5, 0).
        let walls = [
            wall(-5.0, 0.925, 5.0, 0.925),
            wall(-5.0, -0.925, 5.0, -0.925),
            wall(2.0, -0.2, 2.0, 0.2),
        ];
        let me = ROBOT.unicycle(Vec2::zeros(), Vec2::zeros(), 0.0, 0.0, 2.0, 4.0);
        let obs = Observation {
            walls: &walls,
            ..observation(me, Vec2::new(5.0, 0.0), &[])
        };
        let mut grid = WallGrid::default();
        grid.prepare(&walls, 2.0 * PADDED);
        let met =
            |points: &[Vec2], grid: &mut WallGrid| in_the_way(&obs, points, grid, PADDED, 3.0);
        // The walls' own returns: the pillar ahead, the sides.
        let on_walls: Vec<Vec2> = (0..9)
            .map(|k| Vec2::new(2.0, -0.2 + 0.05 * k as f64))
            .chain((0..30).map(|k| Vec2::new(0.1 * k as f64, 0.925)))
            .collect();
        assert!(!met(&on_walls, &mut grid));
        // A robot 1.5 m ahead, a little off the middle: met.
        assert!(met(&disc_returns(Vec2::new(1.5, 0.3)), &mut grid));
        // The same behind, beside (out of the strip) or beyond the
        // look-ahead (3 m at top speed 1 over 3 s): not.
        assert!(!met(&disc_returns(Vec2::new(-1.5, 0.0)), &mut grid));
        assert!(!met(&disc_returns(Vec2::new(0.0, 0.9)), &mut grid));
        assert!(!met(&disc_returns(Vec2::new(3.6, 0.0)), &mut grid));
    }

    #[test]
    fn keeping_right_moves_the_goal_right_as_far_as_the_walls_leave_room() {
        let me = ROBOT.unicycle(Vec2::zeros(), Vec2::zeros(), 0.0, 0.0, 2.0, 4.0);
        let goal = Vec2::new(1.2, 0.0);
        let shifted = |half_width: f64| {
            let walls = [
                wall(-5.0, half_width, 5.0, half_width),
                wall(-5.0, -half_width, 5.0, -half_width),
            ];
            let obs = Observation {
                walls: &walls,
                ..observation(me, goal, &[])
            };
            let mut grid = WallGrid::default();
            grid.prepare(&walls, 2.0 * PADDED);
            right_of_goal(&obs, &mut grid, PADDED, 0.375)
        };
        // A corridor 1.85 m wide: the whole shift, to the right (-y).
        let p = shifted(0.925);
        assert!((p - Vec2::new(1.2, -0.375)).norm() < 1e-12, "{p:?}");
        // One robot wide (0.8 m): only as far as the padded disc fits.
        let p = shifted(0.4);
        assert!(
            (p - Vec2::new(1.2, -(0.4 - PADDED))).norm() < 1e-12,
            "{p:?}"
        );
        // No wider than the padded disc: not at all.
        let p = shifted(0.3);
        assert!((p - goal).norm() < 1e-12, "{p:?}");
    }

    #[test]
    fn a_footprint_meeting_another_in_a_door_keeps_right_only_as_far_as_the_door_leaves_room() {
        // A door 1.2 wide (jambs at y = +-0.6, x = 0.5) into an open room;
        // the robot at the origin heading for (2, 0), another body ahead.
        let walls = [wall(0.5, 0.6, 0.5, 5.0), wall(0.5, -0.6, 0.5, -5.0)];
        let other = [crate::testkit::robot(
            1,
            Vec2::new(1.5, 0.1),
            Vec2::zeros(),
            0.54,
        )];
        let me = ROBOT.unicycle(Vec2::zeros(), Vec2::zeros(), 0.0, 0.0, 2.0, 4.0);
        let obs = Observation {
            walls: &walls,
            ..observation(me, Vec2::new(2.0, 0.0), &other)
        };
        assert!(body_in_the_way(&obs, 0.375, 3.0));
        let mut grid = WallGrid::default();
        grid.prepare(&walls, 0.75);
        // Beside the goal alone there is room for the whole 0.45; the way
        // there passes the door, which leaves 0.6 - 0.375 = 0.225 at the
        // jambs (a little more, the samples along the way, about every
        // 0.375, falling beside them rather than level with them).
        let p = right_of_goal(&obs, &mut grid, 0.375, 0.45);
        assert!((p - Vec2::new(2.0, -0.45)).norm() < 1e-9, "{p:?}");
        let p = right_of_way(&obs, &mut grid, 0.375, 0.45);
        assert!(p.x == 2.0 && p.y < -0.225 + 1e-9 && p.y > -0.3, "{p:?}");
        // Nothing ahead: not met.
        let obs = Observation {
            walls: &walls,
            ..observation(me, Vec2::new(2.0, 0.0), &[])
        };
        assert!(!body_in_the_way(&obs, 0.375, 3.0));
    }
}
