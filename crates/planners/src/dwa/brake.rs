//! Whether both could stop: dwa's admissibility on true states against
//! other robots (module documentation of `dwa`, "Both could stop").
//!
//! Fox, Burgard & Thrun admit an arc when the robot can stop before the
//! first obstacle on it, the obstacle standing still. Among robots that
//! move, stopping alone is not enough (the other keeps coming), and each
//! command is held for a tick before the next can brake. Following the
//! passive-friendly motion safety of Macek, Vasquez, Fraichard & Siegwart
//! (2009) and Bouraine, Fraichard & Salhi (2012), an arc is admitted only
//! if the robot, driving it for a tick and then braking as hard as it can
//! along the same curve, is at rest before it could touch any other body,
//! each other robot also going on for a tick as it moves (along the arc
//! its turn rate, estimated from its velocity's direction over successive
//! ticks, gives, and straight on) and then braking as hard as this robot
//! can; a scripted obstacle does not brake. A contact after the robot has
//! stopped, or one in which it is not driving towards the other (the other
//! runs into it from behind or the side), is not one it could avoid by
//! choosing another arc: were it counted, another robot coming on would
//! forbid every arc, driving away included.

use super::contact::time_to_disc;
use super::unicycle::arc;
use crate::{BodyKind, Sensed, Vec2};
use std::collections::HashMap;

/// Steps per tick at which the braking motions are compared (each step's
/// chords exactly).
const STEPS_PER_TICK: f64 = 4.0;

/// Position after travelling `s` along the curve of curvature `k` from
/// `p`, heading `th`: the unicycle's arc at speed `s` and turn rate `k s`
/// for a second.
fn along(p: Vec2, th: f64, k: f64, s: f64) -> Vec2 {
    arc(p, th, s, k * s, 1.0).0
}

/// Distance travelled by time `t` at speed `u` held for `delay`, then
/// braking at `a` to rest (`a` <= 0: never braking).
pub(super) fn braking_distance(u: f64, a: f64, delay: f64, t: f64) -> f64 {
    if t <= delay || a <= 0.0 {
        return u * t;
    }
    let tb = (t - delay).min(u / a);
    u * delay + u * tb - 0.5 * a * tb * tb
}

/// The turn rates of the others, estimated from their velocity's direction
/// over successive ticks (per body id).
#[derive(Debug, Clone, Default)]
pub(super) struct TurnRates {
    /// Per id: when last seen, and its velocity then.
    last: HashMap<u32, (f64, Vec2)>,
}

impl TurnRates {
    /// The turn rate of each of `others` at `time` (0 when it was not seen
    /// one to two ticks ago, or is too slow for its direction to tell),
    /// at most `w_max` either way; remembers this tick's velocities.
    pub(super) fn update(&mut self, others: &[Sensed], time: f64, dt: f64, w_max: f64) -> Vec<f64> {
        let slow = 1e-3;
        let rates = others
            .iter()
            .map(|o| match self.last.get(&o.id) {
                Some(&(t0, u0))
                    if time - t0 > 0.0
                        && time - t0 <= 2.0 * dt + 1e-9
                        && u0.norm() > slow
                        && o.velocity.norm() > slow =>
                {
                    let turn = u0.perp(&o.velocity).atan2(u0.dot(&o.velocity));
                    (turn / (time - t0)).clamp(-w_max, w_max)
                }
                _ => 0.0,
            })
            .collect();
        self.last
            .retain(|_, &mut (t0, _)| time - t0 <= 2.0 * dt + 1e-9);
        for o in others {
            self.last.insert(o.id, (time, o.velocity));
        }
        rates
    }
}

/// The robot: where it is, its heading, its padded radius, the braking
/// it can do, and the tick.
pub(super) struct Braking {
    /// Position.
    pub(super) position: Vec2,
    /// Heading, rad.
    pub(super) heading: f64,
    /// The radius its arcs are checked with (padded).
    pub(super) radius: f64,
    /// Its deceleration, also assumed of the other robots.
    pub(super) a: f64,
    /// The control period: how long a command is held.
    pub(super) dt: f64,
}

impl Braking {
    /// Whether, driving (v, omega) for a tick and then braking along the
    /// same curve, the robot comes to rest before touching any of
    /// `others` (each with its estimated turn rate in `turns`) going on
    /// for a tick, robots then braking, straight on and along their arc.
    pub(super) fn both_stop(&self, others: &[Sensed], turns: &[f64], v: f64, omega: f64) -> bool {
        if v <= 0.0 || self.a <= 0.0 {
            // Turning in place (the disc does not move), or no brakes to
            // reason with.
            return true;
        }
        let k = omega / v;
        let t_me = self.dt + v / self.a;
        let h = self.dt / STEPS_PER_TICK;
        let reach_me = braking_distance(v, self.a, self.dt, t_me);
        others.iter().zip(turns).all(|(o, &turn)| {
            let u = o.velocity.norm();
            let a_o = if o.kind == BodyKind::Robot {
                self.a
            } else {
                0.0
            };
            let reach_o = braking_distance(u, a_o, self.dt, t_me);
            let gap = (o.position - self.position).norm() - self.radius - o.radius;
            if gap > reach_me + reach_o {
                return true;
            }
            let dir = if u > 1e-12 {
                o.velocity.y.atan2(o.velocity.x)
            } else {
                0.0
            };
            let k_o = if u > 1e-12 { turn / u } else { 0.0 };
            let curves: &[f64] = if k_o == 0.0 { &[0.0] } else { &[0.0, k_o] };
            curves.iter().all(|&k_o| {
                let me_at = |t: f64| {
                    along(
                        self.position,
                        self.heading,
                        k,
                        braking_distance(v, self.a, self.dt, t),
                    )
                };
                let o_at =
                    |t: f64| along(o.position, dir, k_o, braking_distance(u, a_o, self.dt, t));
                let mut t = 0.0;
                let (mut p, mut q) = (self.position, o.position);
                while t < t_me {
                    let t2 = (t + h).min(t_me);
                    let (p2, q2) = (me_at(t2), o_at(t2));
                    let rel = ((p2 - p) - (q2 - q)) / (t2 - t);
                    // A contact counts when the robot is closing on the
                    // other itself (one that runs into it from behind or
                    // the side as it drives away is not one it causes).
                    if let Some(c) = time_to_disc(p - q, rel, self.radius + o.radius)
                        && c <= t2 - t
                    {
                        let f = c / (t2 - t);
                        let between = (q + (q2 - q) * f) - (p + (p2 - p) * f);
                        if (p2 - p).dot(&between) > 0.0 {
                            return false;
                        }
                    }
                    (t, p, q) = (t2, p2, q2);
                }
                true
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::robot;

    fn me() -> Braking {
        Braking {
            position: Vec2::zeros(),
            heading: 0.0,
            radius: 0.3125,
            a: 1.0,
            dt: 0.1,
        }
    }

    #[test]
    fn braking_covers_the_held_tick_and_the_stop() {
        // 0.6 m/s held 0.1 s, then 0.6^2 / 2 at 1 m/s^2.
        let s = braking_distance(0.6, 1.0, 0.1, 10.0);
        assert!((s - (0.06 + 0.18)).abs() < 1e-12, "{s}");
        assert!((braking_distance(0.6, 1.0, 0.1, 0.05) - 0.03).abs() < 1e-12);
        // A body that does not brake goes on.
        assert!((braking_distance(0.5, 0.0, 0.1, 2.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn two_robots_head_on_may_close_only_while_both_could_stop() {
        // Another Pioneer-like robot coming the other way at 0.6 m/s. Each
        // needs 0.24 m to stop after a tick: 0.48 of gap between them.
        let b = me();
        for (gap, ok) in [(0.6, true), (0.4, false)] {
            let x = gap + 0.3125 + 0.25;
            let other = [robot(1, Vec2::new(x, 0.0), Vec2::new(-0.6, 0.0), 0.25)];
            assert_eq!(b.both_stop(&other, &[0.0], 0.6, 0.0), ok, "gap {gap}");
            // Turning in place is always admitted.
            assert!(b.both_stop(&other, &[0.0], 0.0, 1.0));
        }
    }

    #[test]
    fn another_robot_turning_into_the_arc_is_seen_along_its_turn() {
        // Another robot 0.45 m ahead and 0.58 m to the left, coming back
        // at 0.5 m/s: straight on it passes beside (0.58 > 0.3125 + 0.25);
        // turning to its left at 2 rad/s as it brakes it comes across the
        // robot's way.
        let b = me();
        let other = [robot(1, Vec2::new(0.45, 0.58), Vec2::new(-0.5, 0.0), 0.25)];
        assert!(b.both_stop(&other, &[0.0], 0.6, 0.0));
        assert!(!b.both_stop(&other, &[2.0], 0.6, 0.0));
    }

    #[test]
    fn a_turn_rate_is_the_change_of_direction_over_the_tick() {
        let mut rates = TurnRates::default();
        let o = |vx: f64, vy: f64| [robot(3, Vec2::zeros(), Vec2::new(vx, vy), 0.2)];
        assert_eq!(rates.update(&o(1.0, 0.0), 0.0, 0.1, 2.0), vec![0.0]);
        let w = rates.update(&o(0.1f64.cos(), 0.1f64.sin()), 0.1, 0.1, 2.0)[0];
        assert!((w - 1.0).abs() < 1e-9, "{w}");
        // Bounded by the turn-rate limit given; forgotten when not seen.
        let w = rates.update(&o(0.0, 1.0), 0.2, 0.1, 2.0)[0];
        assert_eq!(w, 2.0);
        assert_eq!(rates.update(&o(1.0, 0.0), 1.0, 0.1, 2.0), vec![0.0]);
    }
}
