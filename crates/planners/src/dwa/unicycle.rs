//! [`crate::dwa`] on a unicycle robot: the search over (v, omega) of Fox,
//! Burgard & Thrun's section 3 (the module documentation of `dwa` gives
//! the window, the admissibility test and the objective).

use super::brake::Braking;
use super::contact::{scan_points, time_to_disc, time_to_segment};
use super::footprint::{Footprint, Motion, Rollout, unicycle_poses};
use super::meeting::{body_in_the_way, in_the_way, right_of_goal, right_of_way};
use super::planner::{Dwa, Obstacles};
use super::walls::WallGrid;
use crate::{Command, Observation, Segment, Sensed, Shape, Vec2};
use std::f64::consts::PI;

/// Pose after driving `v`, `omega` for `t` from `p`, `theta` (the exact
/// arc; a straight line when omega is ~0).
pub(super) fn arc(p: Vec2, theta: f64, v: f64, omega: f64, t: f64) -> (Vec2, f64) {
    let th = theta + omega * t;
    if omega.abs() < 1e-9 {
        return (p + Vec2::new(theta.cos(), theta.sin()) * (v * t), th);
    }
    let k = v / omega;
    (
        p + Vec2::new(k * (th.sin() - theta.sin()), -k * (th.cos() - theta.cos())),
        th,
    )
}

/// Time to the first contact along the arc of (v, omega), up to
/// `horizon` (infinite if none): the arc is followed chord by chord (steps
/// of `step`), each chord checked exactly against every sensed body
/// (moving at its velocity, and also standing where it is) and every wall
/// within the robot's reach that the chord's disc can touch (the walls'
/// grid gives those near the chord).
#[allow(clippy::too_many_arguments)]
fn arc_contact(
    obs: &Observation,
    radius: f64,
    others: &[Sensed],
    walls: &mut ArcWalls,
    v: f64,
    omega: f64,
    step: f64,
    horizon: f64,
) -> f64 {
    let me = &obs.me;
    let (mut p, mut th) = (me.position, me.heading);
    let mut t = 0.0;
    while t < horizon {
        let (q, th2) = arc(p, th, v, omega, step);
        let vel = (q - p) / step;
        let mut hit = f64::INFINITY;
        for o in others {
            let rel = vel - o.velocity;
            let at = o.position + o.velocity * t;
            if let Some(h) = time_to_disc(p - at, rel, radius + o.radius) {
                hit = hit.min(h);
            }
            // Also where it stands: a robot need not hold its velocity
            // (it plans too), and may stop or turn into the arc.
            if let Some(h) = time_to_disc(p - o.position, vel, radius + o.radius) {
                hit = hit.min(h);
            }
        }
        if walls.any {
            let pad = Vec2::repeat(walls.radius * (1.0 + 1e-9) + 1e-9);
            walls
                .grid
                .query_near(p.inf(&q) - pad, p.sup(&q) + pad, &mut walls.buf);
            for &k in &walls.buf {
                if let Some(h) = time_to_segment(p, vel, walls.radius, &walls.all[k as usize]) {
                    hit = hit.min(h);
                }
            }
        }
        if hit <= step {
            return t + hit;
        }
        (p, th) = (q, th2);
        t += step;
    }
    f64::INFINITY
}

/// The walls an arc is checked against: all the run's, their grid (its
/// [`WallGrid::near`] done for this tick), and a buffer for its queries.
struct ArcWalls<'a> {
    all: &'a [Segment],
    grid: &'a mut WallGrid,
    buf: Vec<u32>,
    /// Whether any wall is within reach.
    any: bool,
    /// The disc's radius against the walls: the padded radius, or, when
    /// the centre is already nearer a wall than that, just under its
    /// distance to the nearest (module documentation of `dwa`, "Walls on
    /// true states").
    radius: f64,
}

/// Time to the first contact of the disc of radius `r` with any of the
/// still `points` (robot frame, x along the heading) along the arc of
/// (v, omega), up to `horizon` (infinite if none): exact, each point
/// against the circle the centre drives (a line when omega is ~0). A point
/// already inside the disc counts at 0 only when it is ahead of the motion.
fn arc_points(points: &[Vec2], r: f64, v: f64, omega: f64, horizon: f64) -> f64 {
    let speed = v.abs();
    if speed < 1e-9 {
        return f64::INFINITY;
    }
    // Backwards is forwards in the frame mirrored about the wheel axis,
    // with the turn mirrored too.
    let (sx, w) = if v < 0.0 {
        (-1.0, -omega)
    } else {
        (1.0, omega)
    };
    let sy = if w < 0.0 { -1.0 } else { 1.0 };
    let curv = w.abs() / speed;
    let mut best = f64::INFINITY;
    for q in points {
        let q = Vec2::new(sx * q.x, sy * q.y);
        let s = if q.norm() < r {
            if q.x > 0.0 { 0.0 } else { continue }
        } else if curv < 1e-9 {
            if q.y.abs() >= r || q.x <= 0.0 {
                continue;
            }
            q.x - (r * r - q.y * q.y).sqrt()
        } else {
            let big = 1.0 / curv;
            let d = q - Vec2::new(0.0, big);
            let rho = d.norm();
            if (rho - big).abs() >= r {
                continue;
            }
            let cos0 = ((rho * rho + big * big - r * r) / (2.0 * rho * big)).clamp(-1.0, 1.0);
            let half = cos0.acos();
            let delta = (d.y.atan2(d.x) + PI / 2.0).rem_euclid(2.0 * PI);
            big * (delta - half).max(0.0)
        };
        best = best.min(s / speed);
    }
    if best > horizon { f64::INFINITY } else { best }
}

/// Whether driving off at `v` leaves the robot able to stop within half
/// the gap to each of `ahead` (the cosine of its direction off the
/// heading, and the gap), after a tick's delay: (v cos)^2 / (2 a) +
/// v cos dt <= gap / 2. Arcs are checked against where things are; a robot
/// there moves too, and two robots each bending away from where the other
/// stands can bend into each other (meeting head-on, each swerving to the
/// same side). Closing on it only as fast as it can stop in its half of
/// the gap keeps the two apart whatever the other does, as long as it
/// keeps its half too. Along the heading only: what is beside the robot
/// does not limit its speed.
fn reciprocal_stop(ahead: &[(f64, f64)], v: f64, a: f64, dt: f64) -> bool {
    ahead.iter().all(|&(cos, gap)| {
        let u = v * cos;
        u <= 0.0 || u * u / (2.0 * a) + u * dt <= gap / 2.0
    })
}

/// Scores closer than this (relative to the objective's range) are a tie.
const TIE: f64 = 1e-6;

/// The best of the scored samples `(score, v, omega)`: among those within
/// `tie` of the highest score, the one turning furthest right (least
/// omega), and of those the highest scored (the first of equals). A scene
/// that is its own mirror image (two robots meeting exactly head-on) scores
/// each turn as its mirror turn; rounding, different in each robot's
/// frame, would pick the left turn for one and the right for the other,
/// which is the same side of the line between them: they would meet
/// again. Within rounding, both turn right.
pub(super) fn rightmost_best(scored: &[(f64, f64, f64)], tie: f64) -> Option<(f64, f64, f64)> {
    let top = scored.iter().map(|s| s.0).fold(f64::NEG_INFINITY, f64::max);
    let mut best: Option<(f64, f64, f64)> = None;
    for &s in scored.iter().filter(|s| s.0 >= top - tie) {
        if best.is_none_or(|b| s.2 < b.2 || (s.2 == b.2 && s.0 > b.0)) {
            best = Some(s);
        }
    }
    best
}

/// Angle `a` wrapped to (-pi, pi].
pub(super) fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI { w - 2.0 * PI } else { w }
}

/// Whether a back-off (v, omega) may go on for another tick: no contact
/// along it within the tick (a disc: driving straight, its turn in place
/// being always clear), and, for a footprint, stopping from it clear of
/// everything.
fn backing_clear(
    probe: &mut impl FnMut(f64, f64, bool) -> (f64, bool),
    v: f64,
    omega: f64,
    foot: bool,
    dt: f64,
) -> bool {
    if foot {
        let (t, stops) = probe(v, omega, true);
        t > dt && stops
    } else {
        probe(v, 0.0, false).0 > dt
    }
}

/// How far the shape reaches to either side of its heading (a
/// rectangle's half width, a disc's radius).
fn lateral_extent(shape: &Shape) -> f64 {
    match shape {
        Shape::Disc { radius } => *radius,
        Shape::Polygon(p) => p.points().iter().map(|q| q[1].abs()).fold(0.0, f64::max),
    }
}

/// Seconds facing the goal without moving before the robot backs off.
const STILL_FOR: f64 = 3.0;
/// Seconds a back-off lasts at most.
const BACK_OFF_FOR: f64 = 1.5;
/// Seconds without progress, blocked, before the robot goes round.
const STALL_FOR: f64 = 1.5;
/// Seconds the robot keeps right after it last met something in its way.
const KEEP_RIGHT_FOR: f64 = 3.0;
/// Seconds a detour lasts at most.
const DETOUR_FOR: f64 = 2.0;
/// Within this angle of straight in the way, an obstacle is passed on
/// the right (10 degrees, as its sine).
const DEAD_AHEAD: f64 = 0.17364817766693033;

/// Which way to turn from what lies in direction `toward` (a unit vector)
/// for one going along `along`: away from its side, -1 (right) when it is
/// on the left, +1 (left) when on the right; right when it is (within
/// DEAD_AHEAD) straight in the way, whatever rounding says, so that two
/// robots face to face both turn right and pass.
fn side_of(toward: Vec2, along: Vec2) -> f64 {
    let lateral = along.x * toward.y - along.y * toward.x;
    if lateral < -DEAD_AHEAD * toward.norm() {
        1.0
    } else {
        -1.0
    }
}

/// The nearest obstacle's surface distance from the disc and its
/// direction in the robot's frame (a unit vector; zero if none).
fn nearest(
    obs: &Observation,
    points: &[Vec2],
    walls: &[&Segment],
    others: &[Sensed],
) -> (f64, Vec2) {
    let me = &obs.me;
    let (s, c) = me.heading.sin_cos();
    let to_robot = |d: Vec2| Vec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
    let mut best = (f64::INFINITY, Vec2::zeros());
    let mut take = |gap: f64, dir: Vec2| {
        if gap < best.0 {
            let n = dir.norm();
            best = (gap, if n > 0.0 { dir / n } else { Vec2::zeros() });
        }
    };
    for q in points {
        take(q.norm() - me.radius, *q);
    }
    for w in walls {
        let d = w.closest_point(me.position) - me.position;
        take(d.norm() - me.radius, to_robot(d));
    }
    for o in others {
        let d = o.position - me.position;
        take(d.norm() - me.radius - o.radius, to_robot(d));
    }
    best
}

/// One control step of DWA in (v, omega).
pub(super) fn plan(dwa: &mut Dwa, obs: &Observation, w_max: f64, alpha_max: f64) -> Command {
    let me = &obs.me;
    let dt = if obs.dt > 0.0 { obs.dt } else { 0.1 };
    let (s, c) = me.heading.sin_cos();
    let v_c = me.velocity.dot(&Vec2::new(c, s));
    let w_c = me.angular_velocity;
    let a = me.max_accel;
    let to_goal = obs.goal - me.position;
    let d_goal = to_goal.norm();
    let at_goal = d_goal <= obs.goal_tolerance;
    // What is avoided: the scan's returns, or the bodies and the walls the
    // robot can reach within the horizon.
    let scan = dwa.obstacles == Obstacles::Scan;
    // A rectangle or polygon on true states is checked with its true
    // footprint, keeping a quarter of its inscribed radius by default
    // (module documentation of `dwa`, "True footprints").
    let foot = !scan && !me.shape.is_disc();
    let pad = if foot {
        dwa.padding.unwrap_or(me.shape.inradius() / 4.0)
    } else {
        dwa.padding.unwrap_or(me.radius / 4.0)
    };
    let padded = me.radius + pad;
    let reach = me.max_speed * dwa.horizon + padded;
    let points: Vec<Vec2> = if scan {
        scan_points(obs).filter(|q| q.norm() <= reach).collect()
    } else {
        Vec::new()
    };
    // (On true states the walls come from a grid of them built at the
    // first tick: those within reach, in their order, for the nearest
    // obstacle, and per chord of an arc those near the chord.)
    let near: Vec<u32> = if scan {
        Vec::new()
    } else {
        dwa.walls.prepare(obs.walls, 2.0 * padded);
        dwa.walls.near(obs.walls, me.position, reach)
    };
    let walls: Vec<&Segment> = near.iter().map(|&k| &obs.walls[k as usize]).collect();
    // From the scan, whether something that is not a wall is in the way
    // (keeping right, below).
    let meeting = if scan && !at_goal {
        dwa.walls.prepare(obs.walls, 2.0 * padded);
        let shift = (1.5 * me.radius).min(d_goal / 3.0);
        if in_the_way(obs, &points, &mut dwa.walls, padded, dwa.horizon) {
            dwa.recovery.met = obs.time;
        }
        (obs.time - dwa.recovery.met <= KEEP_RIGHT_FOR)
            .then(|| right_of_goal(obs, &mut dwa.walls, padded, shift))
    } else if foot && !at_goal {
        // A footprint on true states keeps right too: its half width
        // (padded) is what the walls must leave room for beside the goal.
        let half = lateral_extent(&me.shape);
        let shift = (1.5 * half).min(d_goal / 3.0);
        if body_in_the_way(obs, half + pad, dwa.horizon) {
            dwa.recovery.met = obs.time;
        }
        (obs.time - dwa.recovery.met <= KEEP_RIGHT_FOR)
            .then(|| right_of_way(obs, &mut dwa.walls, half + pad, shift))
    } else {
        None
    };
    // On true states, the others' turn rates (from their velocity's
    // direction a tick ago) and the robot's braking, for "both could stop".
    let turns = if scan {
        Vec::new()
    } else {
        dwa.turns.update(obs.others, obs.time, dt, w_max)
    };
    let braking = Braking {
        position: me.position,
        heading: me.heading,
        radius: padded,
        a,
        dt,
    };
    let wall_distance = walls
        .iter()
        .map(|w| (w.closest_point(me.position) - me.position).norm())
        .fold(f64::INFINITY, f64::min);
    let others: &[Sensed] = if scan { &[] } else { obs.others };
    let step = dt / 2.0;
    let horizon = dwa.horizon;
    // The nearest obstacle (recovery, going round): to the disc, or to the
    // true footprint.
    let grid = &mut dwa.walls;
    let (mut arc_walls, mut footprint, (gap, toward)) = if foot {
        let mut f = Footprint::new(
            me.shape,
            (me.position, me.heading),
            pad,
            obs.walls,
            grid,
            !walls.is_empty(),
            others,
        );
        let (g, d) = f.nearest((me.position, me.heading), padded);
        let to_robot = Vec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
        (None, Some(f), (g, to_robot))
    } else {
        let near = nearest(obs, &points, &walls, others);
        let aw = ArcWalls {
            all: obs.walls,
            grid,
            buf: Vec::new(),
            any: !walls.is_empty(),
            radius: padded.min(wall_distance * (1.0 - 1e-6)),
        };
        (Some(aw), None, near)
    };
    // Time to the first contact along the arc of (v, omega), and, with
    // `brake`, for a footprint, whether driving it a tick and braking
    // leaves it clear of everything ("Both could stop"; a disc's is
    // `Braking::both_stop`).
    let moving = [Motion::Constant, Motion::Still];
    let stopping = [Motion::Braking { delay: dt, a }, Motion::Still];
    let radius = me.radius;
    let mut probe = |v: f64, w: f64, brake: bool| -> (f64, bool) {
        if let Some(f) = footprint.as_mut() {
            let held = unicycle_poses(
                (me.position, me.heading),
                v,
                w,
                horizon,
                None,
                step,
                horizon,
            );
            let t = f.contact(&Rollout::new(step, held, radius), &moving, true);
            let ok = !brake || {
                let poses = unicycle_poses(
                    (me.position, me.heading),
                    v,
                    w,
                    dt,
                    Some((a, alpha_max)),
                    step / 2.0,
                    horizon,
                );
                f.contact(&Rollout::new(step / 2.0, poses, radius), &stopping, true)
                    .is_infinite()
            };
            return (t, ok);
        }
        let t = arc_points(&points, padded, v, w, horizon);
        let Some(aw) = arc_walls.as_mut() else {
            return (t, true);
        };
        if !aw.any && others.is_empty() {
            (t, true)
        } else {
            let t = t.min(arc_contact(obs, padded, others, aw, v, w, step, horizon));
            (t, true)
        }
    };

    // Recovery: go on backing off, or start when touching something or
    // when standing still facing the goal for STILL_FOR s.
    let rec = &mut dwa.recovery;
    if let Some((until, v, w)) = rec.backing {
        if obs.time < until && backing_clear(&mut probe, v, w, foot, dt) {
            return Command::Unicycle { v, omega: w };
        }
        rec.backing = None;
        rec.still_since = f64::NAN;
    }
    let alpha = wrap(to_goal.y.atan2(to_goal.x) - me.heading);
    let still = v_c.abs() < 0.05 * me.max_speed && w_c.abs() < 0.05 * w_max;
    if at_goal || !still || alpha.abs() > PI / 4.0 {
        rec.still_since = f64::NAN;
    } else if rec.still_since.is_nan() {
        rec.still_since = obs.time;
    }
    let touching = gap < 0.05 * me.radius.max(1e-3);
    if !at_goal && (touching || obs.time - rec.still_since >= STILL_FOR) {
        // Away from the nearest obstacle: backwards if it is ahead, the
        // nose turned away from it; forwards if it is behind.
        let back = 0.5 * me.max_speed;
        let v = if toward.x > 0.0 { -back } else { back };
        let w = if toward.x > 0.0 {
            side_of(toward, Vec2::new(1.0, 0.0)) * 0.5 * w_max
        } else {
            0.0
        };
        let (v, w) = if foot {
            // A footprint's corners swing as it turns: the back-off as
            // planned, else straight, else turning in place, else still,
            // whichever is clear.
            [(v, w), (v, 0.0), (0.0, w)]
                .into_iter()
                .find(|&(v, w)| backing_clear(&mut probe, v, w, true, dt))
                .unwrap_or((0.0, 0.0))
        } else if backing_clear(&mut probe, v, 0.0, false, dt) {
            (v, w)
        } else {
            (0.0, w)
        };
        rec.backing = Some((obs.time + BACK_OFF_FOR, v, w));
        rec.still_since = f64::NAN;
        return Command::Unicycle { v, omega: w };
    }

    // Blocked: no progress (half a radius) for STALL_FOR s, facing the
    // goal, something near ahead and in the way. Go round it for up to
    // DETOUR_FOR s.
    let (hs, hc) = me.heading.sin_cos();
    let toward_world = Vec2::new(hc * toward.x - hs * toward.y, hs * toward.x + hc * toward.y);
    let goal_dir = if d_goal > 1e-12 {
        to_goal / d_goal
    } else {
        Vec2::new(hc, hs)
    };
    if rec.mark.1.is_nan() || (me.position - rec.mark.0).norm() >= 0.5 * me.radius {
        rec.mark = (me.position, obs.time);
    }
    let between = toward_world.dot(&goal_dir) > 0.0;
    if let Some((until, _)) = rec.detour
        && (at_goal || obs.time >= until || !between || gap >= 2.0 * me.radius)
    {
        rec.detour = None;
    }
    if rec.detour.is_none()
        && scan
        && !at_goal
        && between
        && gap < me.radius
        && toward.x > 0.0
        && alpha.abs() <= PI / 4.0
        && obs.time - rec.mark.1 >= STALL_FOR
    {
        rec.detour = Some((obs.time + DETOUR_FOR, side_of(toward_world, goal_dir)));
        rec.mark.1 = obs.time;
    }
    // The heading to aim for: the goal's, or going round, along the
    // nearest obstacle's edge on the detour's side.
    let aim = rec.detour.map(|(_, side)| {
        let t = Vec2::new(-side * toward_world.y, side * toward_world.x);
        t.y.atan2(t.x)
    });
    // From the scan, meeting something in the way that is not a wall: aim
    // to the right of the goal (keeping right).
    let target = if aim.is_none() { meeting } else { None };
    let goal = target.unwrap_or(obs.goal);
    let alpha = match (aim, target) {
        (Some(g), _) => wrap(g - me.heading),
        (None, Some(t)) => wrap((t - me.position).y.atan2((t - me.position).x) - me.heading),
        (None, None) => alpha,
    };

    // The speed to aim for: the top speed, less near the goal (a braking
    // profile), less when the goal is off the heading (the arc through the
    // goal needs v <= omega_max d / (2 |sin alpha|), or the robot circles
    // it), none when it is more than a right angle off (turn in place).
    let v_turn = if alpha.sin().abs() < 1e-9 {
        f64::INFINITY
    } else {
        w_max * d_goal / (2.0 * alpha.sin().abs())
    };
    let v_goal = me
        .max_speed
        .min((2.0 * a * d_goal).sqrt())
        .min(d_goal / dt)
        .min(v_turn)
        * alpha.cos().max(0.0);
    let (v_lo, v_hi) = (
        (v_c - a * dt).max(0.0),
        (v_c + a * dt).clamp(0.0, me.max_speed),
    );
    let (w_lo, w_hi) = (
        (w_c - alpha_max * dt).max(-w_max),
        (w_c + alpha_max * dt).min(w_max),
    );
    // From a scan, any return may be a robot coming this way: the robot
    // keeps to half the gap to each (its direction's cosine off the
    // heading, and the gap to the padded disc). On true states the arcs
    // are checked against the others moving, which covers them.
    let ahead: Vec<(f64, f64)> = points
        .iter()
        .map(|q| (q.x / q.norm().max(1e-12), q.norm() - padded))
        .collect();
    let n = dwa.samples;
    let at = |k: usize, lo: f64, hi: f64| lo + (hi - lo) * k as f64 / (n - 1) as f64;
    let mut scored: Vec<(f64, f64, f64)> = Vec::with_capacity(n * n);
    let mut least_bad = (f64::NEG_INFINITY, 0.0, w_c.clamp(w_lo, w_hi));
    for i in 0..n {
        for j in 0..n {
            let (v, w) = (at(i, v_lo, v_hi.max(v_lo)), at(j, w_lo, w_hi.max(w_lo)));
            let (t_c, stops) = probe(v, w, true);
            // Least bad: furthest contact, then slowest.
            if t_c > least_bad.0 || (t_c == least_bad.0 && v < least_bad.1) {
                least_bad = (t_c, v, w);
            }
            // V_a: can stop before the contact, v <= sqrt(2 (v t_c) a).
            // From a scan, whatever is seen may be a robot coming the other
            // way as fast: both must stop within the gap after a tick's
            // delay each, v^2 / a <= v (t_c - 2 dt).
            let brake = if scan {
                a * (t_c - 2.0 * dt)
            } else {
                2.0 * a * t_c
            };
            if t_c.is_finite() && v > brake {
                continue;
            }
            if !reciprocal_stop(&ahead, v, a, dt) {
                continue;
            }
            // On true states: at rest, after a tick and braking, before
            // touching another robot that goes on for a tick and brakes.
            if !scan && !foot && !braking.both_stop(others, &turns, v, w) {
                continue;
            }
            // A footprint: at rest, after a tick and braking, clear of
            // everything (turning in place too: its corners swing).
            if !stops {
                continue;
            }
            let score = if at_goal {
                -(v + w.abs() * me.radius.max(0.1))
            } else {
                let (p, th) = arc(me.position, me.heading, v, w, dt);
                let ahead = goal - p;
                let heading = if let Some(g) = aim {
                    1.0 - wrap(g - th).abs() / PI
                } else if ahead.norm() <= f64::EPSILON {
                    1.0
                } else {
                    1.0 - wrap(ahead.y.atan2(ahead.x) - th).abs() / PI
                };
                let clearance = t_c.min(dwa.horizon) / dwa.horizon;
                let speed = 1.0 - (v - v_goal).abs() / me.max_speed;
                dwa.w_heading * heading + dwa.w_clearance * clearance + dwa.w_speed * speed
            };
            scored.push((score, v, w));
        }
    }
    let scale = if at_goal {
        me.max_speed + w_max * me.radius.max(0.1)
    } else {
        dwa.w_heading + dwa.w_clearance + dwa.w_speed
    };
    let best = rightmost_best(&scored, TIE * scale.max(f64::MIN_POSITIVE));
    // No admissible sample: a disc takes the one whose contact is
    // furthest off; a footprint brakes as hard as it can, turning too
    // (the furthest contact of its held motions can be a turn that swings
    // a corner into what is within its padding already).
    let fallback = if foot {
        (v_lo, 0.0f64.clamp(w_lo, w_hi.max(w_lo)))
    } else {
        (least_bad.1, least_bad.2)
    };
    let (v, omega) = best.map_or(fallback, |(_, v, w)| (v, w));
    Command::Unicycle { v, omega }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SelfState;
    use crate::testkit::{RobotModel, observation, robot};

    const ROBOT: RobotModel = RobotModel::unit(0.25);

    /// The unicycle at rest at the origin, heading `heading`.
    fn me(heading: f64) -> SelfState {
        ROBOT.unicycle(Vec2::zeros(), Vec2::zeros(), heading, 0.0, 2.0, 4.0)
    }

    #[test]
    fn the_arc_of_a_quarter_turn_ends_where_the_circle_says() {
        // v = 1, omega = 1 for pi/2 s: a quarter of the unit circle.
        let (p, th) = arc(Vec2::zeros(), 0.0, 1.0, 1.0, PI / 2.0);
        assert!((p - Vec2::new(1.0, 1.0)).norm() < 1e-12 && (th - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_robot_facing_away_from_its_goal_turns_towards_it_within_its_window() {
        let obs = observation(me(PI), Vec2::new(5.0, 0.0), &[]);
        let Command::Unicycle { v, omega } = crate::Planner::plan(&mut Dwa::default(), &obs) else {
            panic!("dwa answers a unicycle robot in (v, omega)");
        };
        assert!(
            omega.abs() > 0.39 && omega.abs() <= 4.0 * 0.1 + 1e-12,
            "{omega}"
        );
        assert!((0.0..=0.2 + 1e-12).contains(&v), "{v}");
    }

    #[test]
    fn a_robot_driving_at_a_near_wall_brakes() {
        let walls = [Segment {
            a: Vec2::new(0.3, -2.0),
            b: Vec2::new(0.3, 2.0),
        }];
        let mut s = me(0.0);
        s.velocity = Vec2::new(0.6, 0.0);
        let mut obs = observation(s, Vec2::new(5.0, 0.0), &[]);
        obs.walls = &walls;
        let Command::Unicycle { v, .. } = crate::Planner::plan(&mut Dwa::default(), &obs) else {
            panic!("unicycle command expected");
        };
        // Gap 0.05 straight ahead: going on at 0.6 or faster cannot stop
        // in time (v <= 2 a t_c fails), so it slows down.
        assert!(v < 0.6, "{v}");
    }

    #[test]
    fn a_scan_return_on_the_arc_is_met_where_the_circle_says() {
        // Straight on at 1 m/s, a return 2 m ahead, 0.05 off the line,
        // disc radius 0.1: contact after 2 - sqrt(0.1^2 - 0.05^2).
        let t = arc_points(&[Vec2::new(2.0, 0.05)], 0.1, 1.0, 0.0, 10.0);
        assert!((t - (2.0 - 0.0075f64.sqrt())).abs() < 1e-12, "{t}");
        // A quarter turn of radius 1 ends at (1, 1): a return there is met
        // where the chord to it is 0.1, 2 asin(0.05) short of the quarter.
        let t = arc_points(&[Vec2::new(1.0, 1.0)], 0.1, 1.0, 1.0, 10.0);
        let want = PI / 2.0 - 2.0 * 0.05f64.asin();
        assert!((t - want).abs() < 1e-12, "{t} vs {want}");
        // The same turn to the right meets its mirror image; backwards,
        // the return behind.
        let t = arc_points(&[Vec2::new(1.0, -1.0)], 0.1, 1.0, -1.0, 10.0);
        assert!((t - want).abs() < 1e-12, "{t}");
        let t = arc_points(&[Vec2::new(-2.0, 0.0)], 0.1, -1.0, 0.0, 10.0);
        assert!((t - 1.9).abs() < 1e-12, "{t}");
        // Turning in place meets nothing.
        assert!(arc_points(&[Vec2::new(0.15, 0.0)], 0.1, 0.0, 1.0, 10.0).is_infinite());
    }

    #[test]
    fn a_robot_within_its_padding_of_a_wall_of_short_segments_drives_along_it() {
        // A wall of 5 cm segments (a map's traced outline) 0.29 from the
        // centre, inside the padded radius 0.3125: each segment ahead is
        // nearer than its padded radius, but driving along the wall comes no
        // nearer to it than the robot is.
        let walls: Vec<Segment> = (0..80)
            .map(|k| Segment {
                a: Vec2::new(-1.0 + 0.05 * k as f64, -0.29),
                b: Vec2::new(-0.95 + 0.05 * k as f64, -0.29),
            })
            .collect();
        let obs = Observation {
            walls: &walls,
            ..observation(me(0.0), Vec2::new(5.0, -0.29), &[])
        };
        let Command::Unicycle { v, .. } = crate::Planner::plan(&mut Dwa::default(), &obs) else {
            panic!("unicycle command expected");
        };
        assert!(v > 0.1, "{v}");
    }

    #[test]
    fn among_equal_scores_the_right_turn_is_taken_whatever_rounding_says() {
        // A turn and its mirror image, scored within rounding of each other
        // either way round: the right turn (negative omega) both times.
        let tie = TIE * 2.4;
        for eps in [1e-12, -1e-12] {
            let scored = [(1.0, 0.1, 0.5), (1.0 + eps, 0.1, -0.5), (0.5, 0.0, 0.0)];
            assert_eq!(rightmost_best(&scored, tie).map(|b| b.2), Some(-0.5));
        }
        // A clearly better left turn is still taken.
        let scored = [(1.1, 0.1, 0.5), (1.0, 0.1, -0.5)];
        assert_eq!(rightmost_best(&scored, tie).map(|b| b.2), Some(0.5));
        // Something straight in the way (within 10 degrees) is passed on the
        // right; one off to a side, on the side away from it.
        let along = Vec2::new(1.0, 0.0);
        assert_eq!(side_of(Vec2::new(1.0, 1e-9), along), -1.0);
        assert_eq!(side_of(Vec2::new(1.0, -1e-9), along), -1.0);
        assert_eq!(side_of(Vec2::new(1.0, -0.5), along), 1.0);
        assert_eq!(side_of(Vec2::new(1.0, 0.5), along), -1.0);
    }

    #[test]
    fn a_robot_touching_another_ahead_backs_off_turning_away() {
        let other = [robot(1, Vec2::new(0.5, 0.1), Vec2::zeros(), 0.25)];
        let mut obs = observation(me(0.0), Vec2::new(5.0, 0.0), &other);
        obs.time = 1.0;
        let Command::Unicycle { v, omega } = crate::Planner::plan(&mut Dwa::default(), &obs) else {
            panic!("unicycle command expected");
        };
        // Ahead and to the left: backwards, the nose turned right.
        assert!(v < 0.0 && omega < 0.0, "{v} {omega}");
    }

    #[test]
    fn on_true_states_a_robot_meeting_another_head_on_brakes_while_both_can_stop() {
        // Pioneer-like (radius 0.25, 0.6 m/s, 1 m/s^2) at 0.57 m/s, another
        // coming the other way at 0.6 m/s, 0.48 m of gap between the discs
        // (0.41 to the padded disc). Stopping after a tick takes each
        // 0.057 + 0.16 m: the two together no longer fit in the gap. The
        // arc straight on meets the other only in 0.35 s, in which the
        // robot alone could stop (v <= 2 a t_c), but the other keeps
        // coming: it brakes now, and every arc it keeps to comes to rest
        // clear of the other braking too.
        let mut s = ROBOT.unicycle(Vec2::zeros(), Vec2::new(0.57, 0.0), 0.0, 0.0, 1.8, 3.0);
        (s.max_speed, s.max_accel) = (0.6, 1.0);
        let other = [robot(1, Vec2::new(0.976, 0.0), Vec2::new(-0.6, 0.0), 0.25)];
        let obs = observation(s, Vec2::new(5.0, 0.0), &other);
        let Command::Unicycle { v, omega } = crate::Planner::plan(&mut Dwa::default(), &obs) else {
            panic!("unicycle command expected");
        };
        assert!(v < 0.57 - 1e-9, "{v} {omega}");
        let braking = Braking {
            position: Vec2::zeros(),
            heading: 0.0,
            radius: 0.3125,
            a: 1.0,
            dt: 0.1,
        };
        assert!(braking.both_stop(&other, &[0.0], v, omega));
    }

    #[test]
    fn from_the_scan_a_robot_brakes_for_a_return_ahead_and_ignores_true_states() {
        let mut s = me(0.0);
        s.velocity = Vec2::new(0.6, 0.0);
        // A wall 0.6 ahead, seen within 60 degrees of the heading.
        let ranges: Vec<f64> = (0..360)
            .map(|k| {
                let a = -PI + 2.0 * PI * k as f64 / 360.0;
                if a.abs() < PI / 3.0 {
                    0.6 / a.cos()
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        let scan = crate::lidar::LaserScan {
            angle_min: -PI,
            angle_increment: 2.0 * PI / 360.0,
            range_max: 3.0,
            ranges,
        };
        // A body in the true states right ahead, which the scan does not show.
        let hidden = [robot(1, Vec2::new(0.3, 0.0), Vec2::zeros(), 0.25)];
        let mut obs = observation(s, Vec2::new(5.0, 0.0), &hidden);
        obs.scan = Some(&scan);
        let mut dwa = Dwa {
            obstacles: Obstacles::Scan,
            ..Dwa::default()
        };
        let Command::Unicycle { v, .. } = crate::Planner::plan(&mut dwa, &obs) else {
            panic!("unicycle command expected");
        };
        // Free, it would keep 0.6 or speed up; the wall makes it brake
        // (the hidden body, in contact, would have made it back off).
        assert!((0.0..0.6).contains(&v), "{v}");
    }

    #[test]
    fn from_the_scan_a_robot_closing_on_a_return_keeps_to_half_the_gap() {
        // At 0.6 m/s (top speed 1, a = 2), another robot's disc ahead, a
        // gap of 0.3 to the padded disc at its nearest return: arcs
        // bending away from where it stands meet nothing up to 0.8 m/s,
        // but it may come on and swerve the same way. The robot keeps to
        // a speed at which it can stop in half the gap after a tick:
        // v^2 / 4 + v / 10 <= 0.15, v <= 0.6.
        let mut s = me(0.0);
        s.velocity = Vec2::new(0.6, 0.0);
        let (centre, r) = (0.25 + 0.0625 + 0.3 + 0.25, 0.25);
        let ranges: Vec<f64> = (0..360)
            .map(|k| {
                let a = -PI + 2.0 * PI * k as f64 / 360.0;
                // The near side of the disc at `centre` along x.
                let (along, off) = (centre * a.cos(), centre * a.sin());
                let under = r * r - off * off;
                if a.cos() > 0.0 && under >= 0.0 {
                    along - under.sqrt()
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        let scan = crate::lidar::LaserScan {
            angle_min: -PI,
            angle_increment: 2.0 * PI / 360.0,
            range_max: 8.0,
            ranges,
        };
        let mut obs = observation(s, Vec2::new(5.0, 0.0), &[]);
        obs.scan = Some(&scan);
        let mut dwa = Dwa {
            obstacles: Obstacles::Scan,
            ..Dwa::default()
        };
        let Command::Unicycle { v, .. } = crate::Planner::plan(&mut dwa, &obs) else {
            panic!("unicycle command expected");
        };
        assert!((0.4 - 1e-9..=0.6 + 1e-9).contains(&v), "{v}");
        // Beside the robot, the same return does not limit its speed.
        assert!(reciprocal_stop(&[(0.0, 0.3)], 1.0, 2.0, 0.1));
        assert!(!reciprocal_stop(&[(1.0, 0.3)], 1.0, 2.0, 0.1));
        assert!(reciprocal_stop(&[(1.0, 0.3)], 0.6, 2.0, 0.1));
    }
}
