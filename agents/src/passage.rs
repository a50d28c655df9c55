//! Taking turns at narrow passages: a robot on its route (`route =
//! "shortest"`, [`crate::route::Routed`]) holds short of a passage too
//! narrow for two of it side by side (a door) while another robot comes
//! through it the other way, and backs off when it stands nose to nose
//! with another or with a wall.
//!
//! **The passages.** When a route is planned (and whenever it is planned
//! again), its narrow stretches are marked ([`narrow`]): every point of
//! the route, a quarter of the grid's cell apart, whose free width across
//! the route (from the point along the route's normal to the walls on
//! either side, over the route's clearance grid, by sphere tracing) is
//! less than [`need`], three widths of the robot's footprint (two of it
//! side by side, and half a width beside and between them), is narrow;
//! runs of such points nearer than the footprint's length are one
//! stretch. A 1.2 m door is such a stretch for a 0.6 m wide AGV (it needs
//! 1.8 m); a 2 m corridor, where two pass, is not.
//!
//! **Giving way.** Two robots meeting in a door stop face to face, neither
//! able to turn: a deadlock no local planner on its own resolves. Robots
//! on their routes take the door in turn, each by one rule applied to what
//! it senses, without communication, as cars do at crossings
//! ([`crate::car_route`], "Giving way"). Before the next narrow stretch of
//! its route (within [`HORIZON`] s at its top speed) each robot looks at
//! the robots it senses. One contends for the stretch if it is in it (its
//! centre within its radius of the stretch lengthwise, and within half the
//! stretch's width and half its radius across) unless it goes through it
//! the robot's own way (within 45 degrees), or if it is on the stretch's
//! far side and heads for its middle (within 45 degrees), or stands or
//! comes within [`near`] of it. The robot and each contender are taken to
//! drive straight to the stretch's middle from their speed towards it,
//! speeding up at the robot's own acceleration to its own top speed (as
//! one of its fleet would); one in the stretch is there already. The first
//! to arrive goes first (one in the stretch is waited for whatever the
//! ids); arriving within [`MARGIN_TIME`] of each other, or
//! face to face (each heading for the other within 45 degrees: the other
//! may be making for a passage of its own facing this one, as the doors
//! on either side of a corridor do, and time itself to that), the lower id
//! goes first. Both see the same positions, speeds and ids, so only one of
//! the two holds. The robot that holds is shown by its route, as its
//! planner's goal, the route's point [`hold_back`] short of the stretch
//! (two radii of its footprint, so that the other comes out past it), or,
//! already nearer, where it stood when it began to hold; the planner is
//! unchanged (it stops there and still avoids what comes). A robot within
//! its radius and its braking distance of the stretch goes on (it is
//! committed; the other, seeing it there, holds). A robot that has stood
//! for [`crate::route::PATIENCE`] s while the robot holds for it is not
//! coming (parked at its goal, say) and is no longer waited for. While it
//! holds, the robot is not stuck (its route is not planned again) and does
//! not give way by the yielding rule of [`crate::route`].
//!
//! **Backing off.** A local planner that turns a rectangle only where its
//! padded footprint stays clear leaves a robot that meets another nose to
//! nose, or noses up to a jamb, standing for good (every turn is
//! inadmissible, and it samples no motion backwards). A robot taking turns
//! that has stood [`crate::route::BACK_AFTER`] s with another robot ahead
//! within both their radii and 0.3 m, or with its footprint within 0.15 m
//! of a wall ahead, backs straight off at
//! [`crate::route::BACK_SPEED`] for [`crate::route::BACK_FOR`] s, if its
//! true footprint, moved back along its heading by half a metre, keeps
//! 3 cm from every wall and 5 cm, grown by how far each goes meanwhile,
//! from every other body; each tick it backs only while the next 0.1 m
//! behind stays so clear.
//!
//! Only unicycles whose route has a narrow stretch, and whose planner
//! plans their (v, omega) itself from the others' states
//! (`Planner::plans_unicycle`: dwa, not from the laser scan alone), take
//! turns and back off: with orca through the look-ahead point, which
//! passes the office's doors without them, holding made its AGVs slower
//! and fewer of them arrived (docs/shapes.md). The diagnostic `route_hold`
//! is 1 while a robot holds (`route_holds` counts the times).

use mrsim_planners::{BodyKind, Sensed};
use mrsim_route::{Clearance, P, Path};

/// How far ahead in time, at its top speed, a robot looks for the next
/// narrow stretch of its route, s.
pub const HORIZON: f64 = 8.0;

/// Two arrivals at a stretch less than this apart are together, s.
pub const MARGIN_TIME: f64 = 1.0;

/// A body heading within 45 degrees of a direction goes along it: the
/// cosine.
const WITHIN_45: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The free width across a route below which robot of footprint width
/// `width` (twice its inscribed radius) cannot pass another there: three
/// widths.
pub fn need(width: f64) -> f64 {
    3.0 * width
}

/// How far short of a stretch's start a robot of circumscribed radius
/// `extent` holds: two radii.
pub fn hold_back(extent: f64) -> f64 {
    2.0 * extent
}

/// How near a stretch's middle a body on its far side contends for it
/// whatever its heading (unless it moves away): its width and two radii.
pub fn near(width: f64, extent: f64) -> f64 {
    width + 2.0 * extent
}

/// A narrow stretch of a route.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretch {
    /// Where it begins along the route, m.
    pub from: f64,
    /// Where it ends along the route, m.
    pub to: f64,
    /// Its middle point.
    pub mid: P,
    /// The route's direction through it (a unit vector).
    pub dir: P,
    /// Its least free width across the route, m.
    pub width: f64,
}

/// How far from `q` along the unit vector `n` the first wall is on `grid`,
/// up to `cap`: sphere tracing over the clearance (each step the clearance
/// there, less a cell's diagonal for the grid's rounding).
fn ray(grid: &Clearance, q: P, n: P, cap: f64) -> f64 {
    let res = grid.resolution();
    let mut a = 0.0;
    while a < cap {
        let d = grid.at([q[0] + n[0] * a, q[1] + n[1] * a]);
        if d < res {
            return a + d;
        }
        a += (d - res * std::f64::consts::SQRT_2).max(res / 4.0);
    }
    cap
}

/// The unit direction of `path` at `s` (over a stretch `h` either side).
fn direction(path: &Path, s: f64, h: f64) -> Option<P> {
    let (a, b) = (path.at(s - h), path.at(s + h));
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = dx.hypot(dy);
    (l > 1e-9).then(|| [dx / l, dy / l])
}

/// The free width across `path` at `s` on `grid`, up to `cap`.
fn width_at(grid: &Clearance, path: &Path, s: f64, cap: f64) -> f64 {
    let q = path.at(s);
    if grid.at(q) >= cap / 2.0 {
        return cap;
    }
    let Some(t) = direction(path, s, 2.0 * grid.resolution()) else {
        return cap;
    };
    let n = [-t[1], t[0]];
    let left = ray(grid, q, n, cap);
    let right = ray(grid, q, [-n[0], -n[1]], cap);
    (left + right).min(cap)
}

/// The narrow stretches of `path` on `grid` (module documentation): where
/// the free width across it is less than `need`, runs nearer than `join`
/// made one.
pub fn narrow(grid: &Clearance, path: &Path, need: f64, join: f64) -> Vec<Stretch> {
    let len = path.length();
    let step = grid.resolution() / 4.0;
    let mut runs: Vec<(f64, f64, f64)> = Vec::new();
    let mut s = 0.0;
    while s <= len {
        let w = width_at(grid, path, s, need);
        if w < need {
            match runs.last_mut() {
                Some(r) if s - r.1 <= join => {
                    r.1 = s;
                    r.2 = r.2.min(w);
                }
                _ => runs.push((s, s, w)),
            }
        }
        s += step;
    }
    runs.into_iter()
        .map(|(from, to, width)| {
            let h = (2.0 * grid.resolution()).max((to - from) / 2.0);
            let mid = (from + to) / 2.0;
            Stretch {
                from,
                to,
                mid: path.at(mid),
                dir: direction(path, mid, h).unwrap_or([1.0, 0.0]),
                width,
            }
        })
        .collect()
}

/// The narrow stretches of `path` on `grid` for a footprint of width
/// `width` and circumscribed radius `extent`: narrower than [`need`], runs
/// nearer than the footprint's length one stretch.
pub fn marked(grid: &Clearance, path: &Path, width: f64, extent: f64) -> Vec<Stretch> {
    narrow(grid, path, need(width), 2.0 * extent)
}

/// The time to drive `d` from speed `v0`, accelerating at `accel` up to
/// `cap`.
pub fn time_to(d: f64, v0: f64, cap: f64, accel: f64) -> f64 {
    let d = d.max(0.0);
    let v0 = v0.clamp(0.0, cap);
    if accel <= 0.0 || v0 >= cap {
        return if v0 > 0.0 { d / v0 } else { f64::INFINITY };
    }
    let t_acc = (cap - v0) / accel;
    let d_acc = (v0 + cap) / 2.0 * t_acc;
    if d <= d_acc {
        ((v0 * v0 + 2.0 * accel * d).sqrt() - v0) / accel
    } else {
        t_acc + (d - d_acc) / cap
    }
}

/// The robot deciding, as its rule sees itself.
#[derive(Debug, Clone, Copy)]
pub struct Me {
    /// Its id.
    pub id: u32,
    /// Where it is.
    pub position: P,
    /// Its velocity.
    pub velocity: P,
    /// Its heading, rad.
    pub heading: f64,
    /// Its top speed.
    pub cap: f64,
    /// Its acceleration.
    pub accel: f64,
    /// Slower than this is standing.
    pub slow: f64,
    /// Its footprint's width (twice its inscribed radius).
    pub width: f64,
    /// Its footprint's circumscribed radius.
    pub extent: f64,
}

/// The direction a body goes: its velocity's, or, slower than `slow`, its
/// heading's.
fn going(v: P, heading: f64, slow: f64) -> P {
    let n = v[0].hypot(v[1]);
    if n >= slow {
        [v[0] / n, v[1] / n]
    } else {
        [heading.cos(), heading.sin()]
    }
}

/// Whether robot `o` contends for stretch `st` (module documentation):
/// the time it takes to get to its middle if so (0 in it: waited for
/// whatever the ids).
fn contends(st: &Stretch, me: &Me, o: &Sensed) -> Option<f64> {
    let rel = [o.position.x - st.mid[0], o.position.y - st.mid[1]];
    let along = rel[0] * st.dir[0] + rel[1] * st.dir[1];
    let across = (rel[0] * st.dir[1] - rel[1] * st.dir[0]).abs();
    let v = o.velocity.norm();
    let moving = v >= me.slow;
    let u = if moving {
        [o.velocity.x / v, o.velocity.y / v]
    } else {
        [o.heading.cos(), o.heading.sin()]
    };
    let half = (st.to - st.from) / 2.0;
    if along.abs() <= half + o.radius && across <= st.width / 2.0 + o.radius / 2.0 {
        // In it: going through it this robot's way, it is followed.
        let same = moving && u[0] * st.dir[0] + u[1] * st.dir[1] > WITHIN_45;
        return (!same).then_some(0.0);
    }
    let dist = rel[0].hypot(rel[1]);
    if dist > me.cap * HORIZON || dist <= 0.0 {
        return None;
    }
    let toward = [-rel[0] / dist, -rel[1] / dist];
    let closing = o.velocity.x * toward[0] + o.velocity.y * toward[1];
    let heads = u[0] * toward[0] + u[1] * toward[1] > WITHIN_45;
    let by = dist <= near(me.width, me.extent);
    if along <= 0.0 {
        return None;
    }
    (heads || (by && closing > -me.slow)).then(|| time_to(dist, closing.max(0.0), me.cap, me.accel))
}

/// The robot `me` holds short of stretch `st` for, if any, of `others`
/// (module documentation): the first to get to it, ties to the lower id.
/// `ignored` says whom it no longer waits for.
pub fn hold_for(
    st: &Stretch,
    me: &Me,
    others: &[Sensed],
    ignored: &dyn Fn(&Sensed) -> bool,
) -> Option<u32> {
    let rel = [st.mid[0] - me.position[0], st.mid[1] - me.position[1]];
    let dist = rel[0].hypot(rel[1]);
    let closing = if dist > 0.0 {
        (me.velocity[0] * rel[0] + me.velocity[1] * rel[1]) / dist
    } else {
        0.0
    };
    let t_me = time_to(dist, closing.max(0.0), me.cap, me.accel);
    let mine = going(me.velocity, me.heading, me.slow);
    let first = |o: &Sensed, t_o: f64| {
        // Face to face (each heading for the other): the lower id goes
        // first, whatever the times (the other may be making for a
        // passage of its own facing this one, and time its own).
        let d = [o.position.x - me.position[0], o.position.y - me.position[1]];
        let n = d[0].hypot(d[1]).max(1e-9);
        let theirs = going([o.velocity.x, o.velocity.y], o.heading, me.slow);
        let face = (mine[0] * d[0] + mine[1] * d[1]) / n > WITHIN_45
            && -(theirs[0] * d[0] + theirs[1] * d[1]) / n > WITHIN_45;
        if face || (t_o - t_me).abs() <= MARGIN_TIME {
            o.id < me.id
        } else {
            t_o < t_me
        }
    };
    others
        .iter()
        .filter(|o| o.kind == BodyKind::Robot && o.id != me.id && !ignored(o))
        .filter_map(|o| contends(st, me, o).map(|t| (o, t)))
        .filter(|&(o, t_o)| t_o <= 0.0 || first(o, t_o))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.id.cmp(&b.0.id)))
        .map(|(o, _)| o.id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_route::Scene;

    /// A wall across y = 0 from x = -5 to 5 with a gap `door` wide at
    /// x = 0, and a corridor `corridor` wide along y from -5 to -1
    /// (walls at x = -corridor/2 and +corridor/2) below it.
    fn walls(door: f64, corridor: f64) -> Vec<[P; 2]> {
        vec![
            [[-5.0, 0.0], [-door / 2.0, 0.0]],
            [[door / 2.0, 0.0], [5.0, 0.0]],
            [[-corridor / 2.0, -5.0], [-corridor / 2.0, -1.0]],
            [[corridor / 2.0, -5.0], [corridor / 2.0, -1.0]],
        ]
    }

    /// The clearance grid of `walls` round the route of the tests.
    fn clearance(walls: &[[P; 2]]) -> Clearance {
        Clearance::build(&Scene {
            walls,
            discs: &[],
            points: &[[0.0, -4.5], [0.0, 4.0]],
            resolution: 0.05,
            pad: 1.0,
        })
    }

    #[test]
    fn a_door_on_the_route_is_a_narrow_stretch_and_a_wide_corridor_is_not() {
        let w = walls(1.2, 2.0);
        let grid = clearance(&w);
        // Up the corridor's middle, through the door, into the room.
        let path = Path::new(vec![[0.0, -4.5], [0.0, 4.0]]);
        let found = narrow(&grid, &path, need(0.6), 0.9);
        assert_eq!(found.len(), 1, "{found:?}");
        let st = found[0];
        // The door is at 4.5 m along the route; the stretch holds it and
        // not the corridor (which ends at 3.5 m).
        assert!(st.from > 3.6 && st.from <= 4.5, "{st:?}");
        assert!(st.to >= 4.5 && st.to < 5.4, "{st:?}");
        assert!((st.width - 1.2).abs() < 0.1, "{st:?}");
        assert!(st.mid[1].abs() < 0.3 && st.mid[0].abs() < 1e-9, "{st:?}");
        assert!((st.dir[1] - 1.0).abs() < 1e-9, "{st:?}");
        // A door as wide as the need is not narrow.
        let w = walls(1.9, 2.0);
        let grid = clearance(&w);
        assert!(narrow(&grid, &path, need(0.6), 0.9).is_empty());
        // A corridor narrower than the need is narrow along its length.
        let w = walls(1.9, 1.4);
        let grid = clearance(&w);
        let found = narrow(&grid, &path, need(0.6), 0.9);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].from < 0.1 && found[0].to > 3.4, "{found:?}");
    }

    fn robot(id: u32, p: P, v: P, heading: f64) -> Sensed {
        use mrsim_planners::Vec2;
        Sensed {
            heading,
            ..Sensed::disc(
                id,
                BodyKind::Robot,
                Vec2::new(p[0], p[1]),
                Vec2::new(v[0], v[1]),
                0.54,
            )
        }
    }

    #[test]
    fn the_first_to_reach_a_door_goes_first_and_ties_or_face_to_face_the_lower_id() {
        use std::f64::consts::{FRAC_1_SQRT_2 as H, FRAC_PI_2, FRAC_PI_4};
        // A door at the origin, taken upwards by robot 1 and downwards by
        // the other.
        let up = Stretch {
            from: 4.4,
            to: 4.6,
            mid: [0.0, 0.0],
            dir: [0.0, 1.0],
            width: 1.2,
        };
        let down = Stretch {
            dir: [0.0, -1.0],
            ..up
        };
        let me = |id: u32, p: P, v: P, heading: f64| Me {
            id,
            position: p,
            velocity: v,
            heading,
            cap: 0.8,
            accel: 0.8,
            slow: 0.08,
            width: 0.6,
            extent: 0.54,
        };
        let none = |_: &Sensed| false;
        // Robot 1 comes along the corridor below, 3.1 m from the door;
        // robot 2 comes down to it from the side above, 2.1 m from it:
        // robot 2 arrives first, robot 1 holds, robot 2 goes.
        let a = me(1, [-3.0, -0.8], [0.8, 0.0], 0.0);
        let a_seen = robot(1, [-3.0, -0.8], [0.8, 0.0], 0.0);
        let (bp, bv) = ([-1.5, 1.5], [0.8 * H, -0.8 * H]);
        let b = me(2, bp, bv, -FRAC_PI_4);
        let b_seen = robot(2, bp, bv, -FRAC_PI_4);
        assert_eq!(hold_for(&up, &a, &[b_seen], &none), Some(2));
        assert_eq!(hold_for(&down, &b, &[a_seen], &none), None);
        // As far from it both (3.1 m): the lower id goes first.
        let (bp, bv) = ([-2.2, 2.2], [0.8 * H, -0.8 * H]);
        let b = me(2, bp, bv, -FRAC_PI_4);
        let b_seen = robot(2, bp, bv, -FRAC_PI_4);
        assert_eq!(hold_for(&up, &a, &[b_seen], &none), None);
        assert_eq!(hold_for(&down, &b, &[a_seen], &none), Some(1));
        // Face to face, each heading for the other through the door: the
        // lower id goes first though the other is nearer.
        let a = me(1, [0.0, -3.0], [0.0, 0.8], FRAC_PI_2);
        let a_seen = robot(1, [0.0, -3.0], [0.0, 0.8], FRAC_PI_2);
        let b = me(2, [0.0, 1.5], [0.0, -0.8], -FRAC_PI_2);
        let b_seen = robot(2, [0.0, 1.5], [0.0, -0.8], -FRAC_PI_2);
        assert_eq!(hold_for(&up, &a, &[b_seen], &none), None);
        assert_eq!(hold_for(&down, &b, &[a_seen], &none), Some(1));
        // One going through it this robot's way is followed; one beyond it
        // going away, or passing it by far off, is not waited for.
        let ahead = robot(2, [0.0, 0.1], [0.0, 0.8], FRAC_PI_2);
        let away = robot(3, [0.0, 2.5], [0.0, 0.8], FRAC_PI_2);
        let by = robot(4, [-3.0, 2.5], [0.8, 0.0], 0.0);
        assert_eq!(hold_for(&up, &a, &[ahead, away, by], &none), None);
        // One standing in it is waited for, unless it is no longer.
        let standing = robot(5, [0.0, 0.1], [0.0, 0.0], -FRAC_PI_2);
        assert_eq!(hold_for(&up, &a, &[standing], &none), Some(5));
        assert_eq!(hold_for(&up, &a, &[standing], &|o| o.id == 5), None);
    }

    #[test]
    fn each_agv_route_through_the_office_is_narrow_at_its_two_doors_only() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenarios/shapes/agv-swap.toml");
        let s = mrsim_scenario::load(&file).expect("the AGV scene").scenario;
        let scene = crate::route::RouteScene::of(&s);
        for spec in &s.robots {
            let (grid, path) = scene.route(spec).expect("a route");
            let body = spec.body_shape();
            let found = narrow(
                &grid,
                &path,
                need(2.0 * body.inradius()),
                2.0 * body.circumradius(),
            );
            // Out of its room through one door, along the corridor (2 m:
            // not narrow) and in through another: each stretch in a 1.2 m
            // door of the walls at y = +-1.1, doors at x = -9, -3, 3, 9.
            assert_eq!(found.len(), 2, "{}: {found:?}", spec.name);
            for st in &found {
                let door = (st.mid[0] / 3.0).round() * 3.0;
                assert!(
                    (st.mid[0] - door).abs() < 0.1
                        && (door / 3.0).rem_euclid(2.0) == 1.0
                        && (st.mid[1].abs() - 1.1).abs() < 0.1,
                    "{}: {st:?}",
                    spec.name
                );
                assert!((st.width - 1.2).abs() < 0.1, "{}: {st:?}", spec.name);
                assert!(st.dir[1].abs() > 0.99, "{}: {st:?}", spec.name);
            }
        }
    }
}
