//! Velocity and acceleration of sensed bodies from their successive observed
//! positions, as a camera would give them: Zhu & Loh, "Modeling and Control
//! Strategies for Dynamical Obstacle Avoidance by Mobile Robots", section
//! 2.1, eqs (2.9)-(2.12), and section 2.2.
//!
//! ```text
//! v(t) = (s(t) - s(t - Δt)) / Δt          (2.9), (2.10)
//! a(t) = (v(t) - v(t - Δt)) / Δt          (2.11), (2.12)
//! ```
//!
//! Two frames give the velocity, a third the acceleration (section 2.2).
//! Δt is the time between the two observations actually used, so a body
//! observed every tick gets the sampling interval of the paper.
//!
//! The agent runs one [`VelocityEstimator`] per robot when the robot's
//! `velocity_source = "differenced"`, and calls [`VelocityEstimator::apply`]
//! on the sensed bodies (after field of view, sensing range and position
//! noise) before the planner sees them. Choices where the paper is silent:
//!
//! - A body seen for the first time has velocity and acceleration zero (one
//!   frame says nothing about motion); after its second sighting it has a
//!   velocity and zero acceleration; from the third on, both.
//! - A body missing from a call to `apply` (it left the field of view or the
//!   sensing range) is forgotten: when it comes back it is a new track, as a
//!   tracker that lost it would treat it. Differencing across the gap would
//!   otherwise report the mean velocity over the gap as the current one.
//! - A second observation at the same or an earlier time changes nothing and
//!   returns the previous estimate (Δt must be positive).
//!
//! Deterministic: no randomness here; noise is the agent's business.

use std::collections::BTreeMap;

use crate::{Sensed, Vec2};

/// Velocity and acceleration of one body, eqs (2.9)-(2.12).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Velocity by eqs (2.9)-(2.10); zero until two observations.
    pub velocity: Vec2,
    /// Acceleration by eqs (2.11)-(2.12); zero until three observations.
    pub acceleration: Vec2,
    /// How many observations of this track were used (1, 2, or 3 = "3 or
    /// more").
    pub samples: u8,
}

#[derive(Debug, Clone, Copy)]
struct Track {
    time: f64,
    position: Vec2,
    estimate: Estimate,
}

/// Per body id, velocity and acceleration from successive observed
/// positions (eqs 2.9-2.12). See the module documentation.
#[derive(Debug, Clone, Default)]
pub struct VelocityEstimator {
    tracks: BTreeMap<u32, Track>,
}

impl VelocityEstimator {
    /// An estimator that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records body `id` at `position` at `time` and returns its estimate.
    pub fn observe(&mut self, id: u32, position: Vec2, time: f64) -> Estimate {
        match self.tracks.get_mut(&id) {
            // First frame: no motion known yet.
            None => {
                let estimate = Estimate {
                    velocity: Vec2::zeros(),
                    acceleration: Vec2::zeros(),
                    samples: 1,
                };
                self.tracks.insert(
                    id,
                    Track {
                        time,
                        position,
                        estimate,
                    },
                );
                estimate
            }
            Some(track) => {
                let dt = time - track.time;
                // Same (or earlier) time: nothing new to difference.
                if dt.is_nan() || dt <= 0.0 {
                    return track.estimate;
                }
                // Eqs (2.9)-(2.10): velocity from the last two positions.
                let velocity = (position - track.position) / dt;
                let estimate = if track.estimate.samples >= 2 {
                    // Eqs (2.11)-(2.12): acceleration from the last two
                    // velocities (three frames).
                    Estimate {
                        velocity,
                        acceleration: (velocity - track.estimate.velocity) / dt,
                        samples: 3,
                    }
                } else {
                    // Second frame: velocity only.
                    Estimate {
                        velocity,
                        acceleration: Vec2::zeros(),
                        samples: 2,
                    }
                };
                *track = Track {
                    time,
                    position,
                    estimate,
                };
                estimate
            }
        }
    }

    /// Replaces the velocity and acceleration of every body in `others` by
    /// the estimate from its observed positions, and forgets the bodies that
    /// are not in `others` any more.
    pub fn apply(&mut self, time: f64, others: &mut [Sensed]) {
        self.tracks
            .retain(|id, _| others.iter().any(|o| o.id == *id));
        for o in others.iter_mut() {
            let e = self.observe(o.id, o.position, time);
            o.velocity = e.velocity;
            o.acceleration = e.acceleration;
        }
    }

    /// Forgets every track.
    pub fn clear(&mut self) {
        self.tracks.clear();
    }

    /// The current estimate of body `id`, if it is tracked.
    pub fn get(&self, id: u32) -> Option<Estimate> {
        self.tracks.get(&id).map(|t| t.estimate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BodyKind;

    fn close(a: Vec2, b: Vec2) -> bool {
        (a - b).norm() < 1e-9
    }

    #[test]
    fn first_sighting_has_no_motion_second_has_velocity_third_has_acceleration() {
        let mut e = VelocityEstimator::new();
        let a = Vec2::new(2.0, -1.0);
        let pos = |t: f64| Vec2::new(1.0, 1.0) + Vec2::new(0.5, 0.0) * t + a * (0.5 * t * t);
        let first = e.observe(7, pos(0.0), 0.0);
        assert_eq!(first.samples, 1);
        assert_eq!(first.velocity, Vec2::zeros());
        let second = e.observe(7, pos(0.1), 0.1);
        assert_eq!(second.samples, 2);
        // Eq (2.9)-(2.10): the backward difference is the true velocity at
        // the middle of the interval, t = 0.05.
        assert!(close(second.velocity, Vec2::new(0.5, 0.0) + a * 0.05));
        assert_eq!(second.acceleration, Vec2::zeros());
        let third = e.observe(7, pos(0.2), 0.2);
        assert_eq!(third.samples, 3);
        assert!(close(third.velocity, Vec2::new(0.5, 0.0) + a * 0.15));
        // Eq (2.11)-(2.12): a constant acceleration is recovered exactly.
        assert!(close(third.acceleration, a));
    }

    #[test]
    fn constant_velocity_gives_exact_velocity_and_zero_acceleration() {
        let mut e = VelocityEstimator::new();
        let v = Vec2::new(-3.0, 4.0);
        let mut last = None;
        for k in 0..6 {
            let t = k as f64 * 0.25;
            last = Some(e.observe(1, v * t, t));
        }
        let last = last.unwrap();
        assert!(close(last.velocity, v));
        assert!(close(last.acceleration, Vec2::zeros()));
    }

    #[test]
    fn repeated_time_keeps_the_previous_estimate() {
        let mut e = VelocityEstimator::new();
        e.observe(1, Vec2::new(0.0, 0.0), 0.0);
        let before = e.observe(1, Vec2::new(1.0, 0.0), 1.0);
        let again = e.observe(1, Vec2::new(5.0, 0.0), 1.0);
        assert_eq!(before, again);
    }

    #[test]
    fn apply_overwrites_motion_and_forgets_bodies_out_of_view() {
        let body = |id: u32, x: f64| Sensed {
            acceleration: Vec2::new(99.0, 99.0),
            ..Sensed::disc(
                id,
                BodyKind::Obstacle,
                Vec2::new(x, 0.0),
                Vec2::new(99.0, 99.0),
                0.1,
            )
        };
        let mut e = VelocityEstimator::new();
        e.apply(0.0, &mut [body(1, 0.0), body(2, 0.0)]);
        let mut seen = [body(1, 1.0), body(2, 2.0)];
        e.apply(0.5, &mut seen);
        assert!(close(seen[0].velocity, Vec2::new(2.0, 0.0)));
        assert!(close(seen[1].velocity, Vec2::new(4.0, 0.0)));
        assert_eq!(seen[0].acceleration, Vec2::zeros());
        // Body 2 leaves the view for one tick, then comes back far away: it
        // is a new track, not a teleport.
        e.apply(1.0, &mut [body(1, 2.0)]);
        assert!(e.get(2).is_none());
        let mut back = [body(1, 3.0), body(2, 50.0)];
        e.apply(1.5, &mut back);
        assert_eq!(back[1].velocity, Vec2::zeros());
        assert!(close(back[0].velocity, Vec2::new(2.0, 0.0)));
    }
}
