//! Social force model: D. Helbing & P. Molnar, "Social force model for
//! pedestrian dynamics", Physical Review E 51(5), 1995, pp. 4282-4286,
//! in the circular form with body radii and the continuous anisotropy of
//! D. Helbing, I. Farkas & T. Vicsek (Nature 407, 2000) and A. Johansson,
//! D. Helbing & P. K. Shukla (Advances in Complex Systems 10, 2007).
//!
//! The robot's acceleration is the sum of
//! - the driving term (H&M eq 2): (v0 e - v) / tau, e the unit vector to the
//!   goal, relaxing the velocity to the desired one within `tau`;
//! - the repulsion of every sensed body j (H&M eqs 3-4, circular form):
//!   a exp((r_i + r_j - d_ij) / b) n_ij w(phi_ij), with d_ij the distance of
//!   the centres, n_ij the unit vector from j to the robot, and the
//!   anisotropy w(phi) = lambda + (1 - lambda) (1 + cos phi) / 2, phi the
//!   angle between the desired direction e and the direction -n_ij to j
//!   (H&M's weight c for bodies outside the field of view, made
//!   continuous: 1 straight ahead, lambda straight behind);
//! - the repulsion of every wall (H&M eq 5): a exp((r_i - d_iW) / b) n_iW,
//!   d_iW the distance to the nearest point of the segment, no anisotropy.
//!
//! H&M's potentials are V0 exp(-b/sigma) (bodies, V0 = 2.1 m^2/s^2, sigma =
//! 0.3 m) and U0 exp(-d/R) (walls, U0 = 10 m^2/s^2, R = 0.2 m), with b the
//! semi-minor axis of an ellipse drawn from the other's step; the force is
//! the gradient, of magnitude (V0 / sigma) exp(-b / sigma). With circular
//! bodies this is our a exp(-gap / b) with a = V0 / sigma = 7 m/s^2 and
//! b = sigma = 0.3 m, used for walls too (one `a`, `b` pair: four parameters in
//! all). Defaults: `tau` = 0.5 s, `a` = 7, `b` =
//! 0.3 (H&M section III); `lambda` = 0.5, the continuous form of H&M's
//! c = 0.5 behind the pedestrian; `pref_speed` (v0) = 1.34 m/s, H&M's mean
//! desired speed.
//!
//! Goal: H&M's pedestrians pass through their destinations. A robot must
//! stop at its goal, so the desired speed is min(v0, d_goal / (4 tau)): with
//! the driving term alone this makes the approach critically damped (x'' =
//! (-x / (4 tau) - x') / tau has a double root at -1 / (2 tau)).
//!
//! Known behaviour: two robots reaching a right-angle crossing at the same
//! instant (mirror-symmetric about the diagonal) settle side by side where
//! repulsion balances the driving terms and stay there (measured in the
//! testkit: both stop about 2.2 and 2.8 units past the start line); the
//! model has no rule that breaks the tie. A staggered crossing passes.
//!
//! The command is the force m a + b_damp v (the world applies
//! m r'' + b_damp r' = f), so the robot's acceleration is the model's.

use crate::{Command, Observation, ParamError, ParamReader, Params, Planner, Vec2};

/// Helbing & Molnar's social force model.
#[derive(Debug, Clone)]
pub struct SocialForce {
    /// Relaxation time of the driving term, s.
    pub tau: f64,
    /// Strength of the repulsion at contact (acceleration).
    pub a: f64,
    /// Range of the repulsion (length).
    pub b: f64,
    /// Anisotropy: weight of bodies straight behind (1 = isotropic).
    pub lambda: f64,
    /// Desired speed v0.
    pub pref_speed: f64,
}

impl Default for SocialForce {
    fn default() -> Self {
        Self {
            tau: 0.5,
            a: 7.0,
            b: 0.3,
            lambda: 0.5,
            pref_speed: 1.34,
        }
    }
}

impl SocialForce {
    /// Reads `tau`, `a`, `b`, `lambda` and `pref_speed`.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let d = Self::default();
        let mut r = ParamReader::new("social-force", params);
        let tau = r.positive("tau", d.tau)?;
        let a = r.non_negative("a", d.a)?;
        let b = r.positive("b", d.b)?;
        let lambda = r.number("lambda", d.lambda)?;
        if !(0.0..=1.0).contains(&lambda) {
            return Err(r.invalid("lambda", format!("must be in [0, 1], got {lambda}")));
        }
        let pref_speed = r.non_negative("pref_speed", d.pref_speed)?;
        r.finish()?;
        Ok(Self {
            tau,
            a,
            b,
            lambda,
            pref_speed,
        })
    }

    /// The model's acceleration for this observation.
    pub fn acceleration(&self, obs: &Observation) -> Vec2 {
        let me = &obs.me;
        let to_goal = obs.goal - me.position;
        let d_goal = to_goal.norm();
        let e = if d_goal > f64::EPSILON {
            to_goal / d_goal
        } else {
            Vec2::zeros()
        };
        // Driving term, with the desired speed falling off near the goal.
        let v0 = self.pref_speed.min(d_goal / (4.0 * self.tau));
        let mut acc = (e * v0 - me.velocity) / self.tau;

        // Repulsion of other bodies, weighted by where they are.
        for o in obs.others {
            let diff = me.position - o.position;
            let d = diff.norm();
            let n = if d > f64::EPSILON {
                diff / d
            } else {
                // Coincident centres: push back from the desired direction.
                -e
            };
            let cos_phi = -n.dot(&e);
            let w = self.lambda + (1.0 - self.lambda) * (1.0 + cos_phi) / 2.0;
            acc += n * (self.a * ((me.radius + o.radius - d) / self.b).exp() * w);
        }

        // Repulsion of walls, from the nearest point of each.
        for wall in obs.walls {
            let diff = me.position - wall.closest_point(me.position);
            let d = diff.norm();
            if d > f64::EPSILON {
                acc += diff / d * (self.a * ((me.radius - d) / self.b).exp());
            }
        }
        acc
    }
}

impl Planner for SocialForce {
    fn plan(&mut self, obs: &Observation) -> Command {
        let acc = self.acceleration(obs);
        Command::Force(acc * obs.me.mass + obs.me.velocity * obs.me.damping)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{RobotModel, Sim, observation, robot};
    use crate::{ParamValue, Segment, Sensed};

    const ROBOT: RobotModel = RobotModel {
        radius: 0.3,
        mass: 2.0,
        damping: 0.5,
        max_speed: 2.0,
        max_accel: 10.0,
    };

    /// The robot at the origin moving at `velocity`, its goal 10 along x.
    fn obs<'a>(velocity: Vec2, others: &'a [Sensed], walls: &'a [Segment]) -> Observation<'a> {
        let me = ROBOT.at(Vec2::zeros(), velocity);
        Observation {
            goal_tolerance: 0.1,
            walls,
            ..observation(me, Vec2::new(10.0, 0.0), others)
        }
    }

    /// Robot 1, standing, of the same size.
    fn body_at(p: Vec2) -> Sensed {
        robot(1, p, Vec2::zeros(), ROBOT.radius)
    }

    #[test]
    fn driving_term_relaxes_velocity_to_the_desired_one_within_tau() {
        let sf = SocialForce::default();
        let acc = sf.acceleration(&obs(Vec2::new(0.0, 1.0), &[], &[]));
        let want = (Vec2::new(1.34, 0.0) - Vec2::new(0.0, 1.0)) / 0.5;
        assert!((acc - want).norm() < 1e-12, "{acc:?}");
    }

    #[test]
    fn force_command_compensates_mass_and_damping() {
        let mut sf = SocialForce::default();
        let v = Vec2::new(0.0, 1.0);
        let o = obs(v, &[], &[]);
        let f = sf.plan(&o).vector();
        assert!((f - (sf.acceleration(&o) * 2.0 + v * 0.5)).norm() < 1e-12);
    }

    #[test]
    fn repulsion_grows_exponentially_as_a_body_nears() {
        let sf = SocialForce::default();
        let base = sf.acceleration(&obs(Vec2::zeros(), &[], &[]));
        let push = |y: f64| {
            let others = [body_at(Vec2::new(0.0, y))];
            (sf.acceleration(&obs(Vec2::zeros(), &others, &[])) - base).y
        };
        // Beside the robot (phi = 90 deg): w = (1 + lambda) / 2.
        let at_contact = push(0.6);
        assert!((at_contact - -7.0 * 0.75).abs() < 1e-12, "{at_contact}");
        let ratio = push(0.6) / push(0.9);
        assert!((ratio - (0.3f64 / 0.3).exp()).abs() < 1e-9, "{ratio}");
    }

    #[test]
    fn bodies_behind_repel_less_than_bodies_ahead() {
        let sf = SocialForce::default();
        let base = sf.acceleration(&obs(Vec2::zeros(), &[], &[]));
        let ahead = [body_at(Vec2::new(1.0, 0.0))];
        let behind = [body_at(Vec2::new(-1.0, 0.0))];
        let front = (sf.acceleration(&obs(Vec2::zeros(), &ahead, &[])) - base).x;
        let back = (sf.acceleration(&obs(Vec2::zeros(), &behind, &[])) - base).x;
        assert!(front < 0.0 && back > 0.0);
        assert!((back / -front - 0.5).abs() < 1e-12, "lambda = 0.5");
    }

    #[test]
    fn wall_pushes_along_its_normal() {
        let sf = SocialForce::default();
        let base = sf.acceleration(&obs(Vec2::zeros(), &[], &[]));
        let walls = [Segment {
            a: Vec2::new(-5.0, 0.5),
            b: Vec2::new(5.0, 0.5),
        }];
        let push = sf.acceleration(&obs(Vec2::zeros(), &[], &walls)) - base;
        assert!(push.x.abs() < 1e-12);
        assert!(
            (push.y - -7.0 * (-0.2f64 / 0.3).exp()).abs() < 1e-12,
            "{push:?}"
        );
    }

    #[test]
    fn lambda_outside_zero_one_is_refused() {
        let mut p = Params::new();
        p.insert("lambda".into(), ParamValue::Number(1.5));
        assert!(SocialForce::from_params(&p).is_err());
    }

    #[test]
    fn two_robots_crossing_at_right_angles_one_behind_the_other_pass_without_contact() {
        let mut sim = Sim::new(0.1, 10);
        // B starts one unit further back: with both reaching the crossing
        // at the same instant the encounter is mirror-symmetric about the
        // diagonal, which this model resolves by no rule of its own.
        let (ra, rb) = (Vec2::new(-5.0, 0.0), Vec2::new(0.0, -6.0));
        for (start, goal) in [(ra, -ra), (rb, Vec2::new(0.0, 5.0))] {
            sim.add_robot(
                Box::new(SocialForce::default()),
                start,
                goal,
                0.3,
                1.0,
                0.0,
                2.0,
                10.0,
            );
        }
        let mut min_gap = f64::INFINITY;
        let mut reached = [false; 2];
        for _ in 0..400 {
            sim.step();
            min_gap = min_gap.min(sim.clearance(0));
            for (k, r) in sim.robots.iter().enumerate() {
                reached[k] |= (r.state.position - r.goal).norm() < 0.2;
            }
        }
        let ends: Vec<Vec2> = sim.robots.iter().map(|r| r.state.position).collect();
        assert!(min_gap > 0.0, "contact: gap {min_gap}");
        assert_eq!(reached, [true, true], "ended at {ends:?}");
    }
}
