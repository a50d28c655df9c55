//! Homing navigation: Chung, Jin, Park, Lee & Lee, "Real Time Navigation
//! Strategy of a Mobile Robot Using Artificial Potential Field", eq (2).
//!
//! f = f_c e / ||e|| - alpha g(r'),  e = r_g - r,  and f = 0 when e = 0.
//!
//! Reading of the garbled text (see shared/papers/README.md): the paper
//! prints <r', g(r')> < 0, which would make -alpha g accelerate the robot;
//! the prose ("the oscillatory behaviour depends on alpha") and Fig. 1 need
//! a damping term, so we take g(v) = v, for which <v, g(v)> > 0.
//! With eq (1)'s friction b, the robot oscillates through the goal with a
//! decaying amplitude that falls as alpha grows.
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
    use crate::{SelfState, Vec2};

    fn obs(pos: Vec2, vel: Vec2) -> Observation<'static> {
        Observation {
            tick: 0,
            time: 0.0,
            dt: 0.1,
            me: SelfState {
                id: 0,
                position: pos,
                velocity: vel,
                radius: 0.0,
                mass: 1.0,
                damping: 0.1,
                max_speed: 10.0,
                max_accel: 100.0,
            },
            goal: Vec2::new(10.0, 0.0),
            goal_tolerance: 0.1,
            others: &[],
            walls: &[],
            path: None,
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
}
