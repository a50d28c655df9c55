//! Homing navigation: Chung, Jin, Park, Lee & Lee, "Real Time Navigation
//! Strategy of a Mobile Robot Using Artificial Potential Field", eq (2).
//!
//! f = f_c e / ||e|| - alpha g(r'),  e = r_g - r,  and f = 0 when e = 0.
//!
//! Reading of the garbled text: the paper
//! prints <r', g(r')> < 0, which would make -alpha g accelerate the robot;
//! the prose ("the oscillatory behaviour depends on alpha") and Fig. 1 need
//! a damping term, so we take g(v) = v, for which <v, g(v)> > 0.
//! With eq (1)'s friction b, the robot oscillates through the goal with an
//! amplitude that falls as alpha grows. It does not die out: the
//! constant-magnitude attraction is held for a whole tick, and the energy
//! gained by overshooting the goal within a tick balances the damping, so
//! a limit cycle remains (Fig. 1 settings, dt = 0.1 s: about 7.6 m for
//! alpha = 0.01, 5.0 m for 0.1, 0.8 m for 1; scenarios/papers/
//! chung-homing-fig1.toml).
//!
//! Parameters: `f_g` (the paper's f_c, default 10 as in Fig. 1), `alpha`
//! (default 0.1, Fig. 1's larger value).

use crate::{Command, Observation, ParamError, ParamReader, Params, Planner};

/// Chung et al. eq (2).
#[derive(Debug, Clone)]
pub struct Homing {
    /// Attractive force magnitude f_c.
    pub f_g: f64,
    /// Damping rate alpha.
    pub alpha: f64,
}

impl Homing {
    /// Reads `f_g` and `alpha` from a robot's params.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new("homing", params);
        let f_g = r.positive("f_g", 10.0)?;
        let alpha = r.non_negative("alpha", 0.1)?;
        r.finish()?;
        Ok(Self { f_g, alpha })
    }
}

impl Planner for Homing {
    fn plan(&mut self, obs: &Observation) -> Command {
        let e = obs.goal - obs.me.position;
        let dist = e.norm();
        // Case e = 0: no force at all (eq 2, second line).
        if dist <= f64::EPSILON {
            return Command::Force(crate::Vec2::zeros());
        }
        // Case e != 0: constant-magnitude attraction minus damping g(v) = v.
        Command::Force(e * (self.f_g / dist) - obs.me.velocity * self.alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec2;
    use crate::testkit::{RobotModel, observation};

    const ROBOT: RobotModel = RobotModel {
        radius: 0.0,
        mass: 1.0,
        damping: 0.1,
        max_speed: 10.0,
        max_accel: 100.0,
    };

    /// The point robot at `pos` moving at `vel`, alone, its goal 10 along x.
    fn obs(pos: Vec2, vel: Vec2) -> Observation<'static> {
        Observation {
            goal_tolerance: 0.1,
            ..observation(ROBOT.at(pos, vel), Vec2::new(10.0, 0.0), &[])
        }
    }

    #[test]
    fn force_points_at_goal_with_magnitude_f_g_when_still() {
        let mut h = Homing {
            f_g: 10.0,
            alpha: 0.1,
        };
        let f = h.plan(&obs(Vec2::new(0.0, 0.0), Vec2::zeros())).vector();
        assert!((f - Vec2::new(10.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn damping_opposes_velocity() {
        let mut h = Homing {
            f_g: 10.0,
            alpha: 0.5,
        };
        let f = h
            .plan(&obs(Vec2::new(0.0, 0.0), Vec2::new(0.0, 4.0)))
            .vector();
        assert!((f.y - -2.0).abs() < 1e-12);
    }

    #[test]
    fn no_force_at_the_goal() {
        let mut h = Homing {
            f_g: 10.0,
            alpha: 0.5,
        };
        let f = h.plan(&obs(Vec2::new(10.0, 0.0), Vec2::zeros())).vector();
        assert_eq!(f, Vec2::zeros());
    }

    #[test]
    fn oscillation_about_the_goal_falls_as_alpha_grows() {
        // scenarios/papers/chung-homing-fig1.toml: m = 1, f_c = 10, b = 0.1.
        let text = include_str!("../../../scenarios/papers/chung-homing-fig1.toml");
        let mut sim = crate::testkit::Sim::new(0.1, 10);
        let alphas = [0.01, 0.1, 1.0];
        for (i, alpha) in alphas.iter().enumerate() {
            assert!(text.contains(&format!("params = {{ f_g = 10.0, alpha = {alpha:?} }}")));
            let y = 3.0 * i as f64;
            let h = Homing {
                f_g: 10.0,
                alpha: *alpha,
            };
            sim.add_robot(
                Box::new(h),
                Vec2::new(0.0, y),
                Vec2::new(10.0, y),
                0.2,
                1.0,
                0.1,
                100.0,
                100.0,
            );
        }
        let mut amplitude = [0.0f64; 3];
        for tick in 1..=1200 {
            sim.step();
            if tick > 300 {
                for (a, r) in amplitude.iter_mut().zip(&sim.robots) {
                    *a = a.max((r.state.position.x - 10.0).abs());
                }
            }
        }
        assert!(
            amplitude[0] > amplitude[1] && amplitude[1] > amplitude[2],
            "{amplitude:?}"
        );
        // As printed and sampled, it does not settle: a limit cycle remains.
        assert!(amplitude[2] > 0.1, "{amplitude:?}");
    }
}
