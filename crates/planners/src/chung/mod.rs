//! Navigation among moving obstacles: Chung, Jin, Park, Lee & Lee, "Real
//! Time Navigation Strategy of a Mobile Robot Using Artificial Potential
//! Field", Strategies I, II and III,
//! eqs (3), (4) and (5), for the point mass of eq (1), m r'' + b r' = f.
//!
//! One method, three strategies that share their terms:
//!
//! ```text
//! f_i = f_g (r_g - r_i)/||r_g - r_i||                       attraction   (3)-(5)
//!     - f_g alpha g(r_i')                                    damping      (3)-(5)
//!     + sum_j f_m [ (r_i - r_j)/||r_i - r_j||^3
//!                 - (r_g - r_j)/||r_g - r_j||^3 ]            position repulsion (3)-(5)
//!     + sum_j f_v [ (v_i - v_j)/D_j^3 - (v_g - v_j)/G_j^3 ]  velocity repulsion (4), (5)
//! ```
//!
//! Strategy I (`chung-1`) has no velocity term. Strategy II (`chung-2`,
//! eq 4) has D_j = ||v_i - v_j|| and G_j = ||v_g - v_j||. Strategy III
//! (`chung-3`, eq 5) has D_j = ||r_i - r_j|| and G_j = ||r_g - r_j||.
//!
//! The sum runs over every body in `obs.others`, i.e. every body the robot
//! senses (the world applies the sensing range and field of view), robots
//! and obstacles alike: every other robot is a moving obstacle. Distances are
//! between centres (the paper's objects are point masses, section 2).
//!
//! Readings of the paper's text where it is garbled or misprinted:
//! - Damping: eqs (3)-(5) print `- f_g alpha g(r_i)` and eq (2) requires
//!   `<r', g(r')> < 0`; both are typos for a damping term in the velocity,
//!   so g(v) = v and the term is `- f_g alpha v` (note the factor f_g,
//!   which eq (2), the `homing` planner, does not have).
//! - Strategy III: eq (5) is printed identical to eq (4). The prose says "the
//!   relative positions replace the relative velocities in the repulsive
//!   term"; we keep (v_i - v_j) in the numerator and take the cube of the
//!   relative *position* distance as the denominator, so the term fades with
//!   distance instead of exploding when the relative speed is small.
//! - The goal's velocity v_g is zero (a fixed goal).
//! - The goal counter-terms (those in r_g and v_g) make the goal an
//!   equilibrium whatever the obstacles do; they are kept as printed.
//!
//! Singular cases: a term whose denominator is below `1e-9` (a body at the
//! robot's centre, at the goal, or, in Strategy II, moving with exactly
//! the robot's velocity or exactly at rest) is left out: the printed
//! expression is 0/0 or infinite there. Just above it, Strategy II's terms
//! are unbounded, and the world's `max_accel` clamp is what limits them:
//! when the sensed bodies are at rest, Strategy II's term becomes
//! `f_v v_i/||v_i||^3`, a push along the robot's own velocity that grows as
//! the robot slows down, which is why Strategy II cannot come to rest at
//! its goal (section 4) and Strategy III can.
//!
//! Parameters (defaults: the paper's figure captions): `f_g` (the paper's
//! f_c, 1), `alpha` (0.8), `f_m` (the captions' f_r: 20 for Strategy I as
//! in Fig. 2, 10 for II and III as in Figs. 3-4), `f_v` (the captions' v_f:
//! 0.1 for Strategy II, Fig. 3; 20 for Strategy III, Fig. 4; not accepted
//! by Strategy I).

#[cfg(test)]
mod tests;

use crate::{Command, Observation, ParamError, ParamReader, Params, Planner, Vec2};

/// Below this a denominator is taken as zero and its term left out.
const SINGULAR: f64 = 1e-9;

/// Which of the paper's three strategies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// Eq (3): relative positions only.
    I,
    /// Eq (4): relative positions and velocities, velocity term over
    /// ||v_i - v_j||^3.
    II,
    /// Eq (5) (our reading): velocity term over ||r_i - r_j||^3.
    III,
}

impl Strategy {
    /// The planner's name in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::I => "chung-1",
            Strategy::II => "chung-2",
            Strategy::III => "chung-3",
        }
    }
}

/// Chung et al. eqs (3)-(5).
#[derive(Debug, Clone)]
pub struct Chung {
    /// Which strategy.
    pub strategy: Strategy,
    /// Attractive force magnitude (the paper's f_c / f_gi).
    pub f_g: f64,
    /// Damping rate alpha.
    pub alpha: f64,
    /// Position-repulsion constant f_m.
    pub f_m: f64,
    /// Velocity-repulsion constant f_v (unused by Strategy I).
    pub f_v: f64,
}

/// `a / ||a||^3`, or zero when `||a||` is singular.
fn inverse_square(a: Vec2) -> Vec2 {
    let n = a.norm();
    if n < SINGULAR {
        Vec2::zeros()
    } else {
        a / (n * n * n)
    }
}

impl Chung {
    /// Reads `f_g`, `alpha`, `f_m` and (Strategies II, III) `f_v`.
    pub fn from_params(strategy: Strategy, params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new(strategy.name(), params);
        let f_g = r.positive("f_g", 1.0)?;
        let alpha = r.non_negative("alpha", 0.8)?;
        let f_m = r.non_negative("f_m", if strategy == Strategy::I { 20.0 } else { 10.0 })?;
        let f_v = match strategy {
            Strategy::I => 0.0,
            Strategy::II => r.non_negative("f_v", 0.1)?,
            Strategy::III => r.non_negative("f_v", 20.0)?,
        };
        r.finish()?;
        Ok(Self {
            strategy,
            f_g,
            alpha,
            f_m,
            f_v,
        })
    }
}

impl Planner for Chung {
    fn plan(&mut self, obs: &Observation) -> Command {
        let r_i = obs.me.position;
        let v_i = obs.me.velocity;
        let r_g = obs.goal;
        let e = r_g - r_i;
        let dist = e.norm();
        // Attraction: constant magnitude f_g towards the goal, none at the
        // goal itself (eq 2's second case carried over).
        let mut f = if dist > SINGULAR {
            e * (self.f_g / dist)
        } else {
            Vec2::zeros()
        };
        // Damping: - f_g alpha g(v), g(v) = v.
        f -= v_i * (self.f_g * self.alpha);
        for o in obs.others {
            let r_j = o.position;
            let v_j = o.velocity;
            // Position repulsion, minus its value at the goal.
            f += (inverse_square(r_i - r_j) - inverse_square(r_g - r_j)) * self.f_m;
            match self.strategy {
                // Strategy I: positions only.
                Strategy::I => {}
                // Strategy II: relative velocities over their own norms
                // cubed; the goal is at rest (v_g = 0).
                Strategy::II => {
                    f += (inverse_square(v_i - v_j) - inverse_square(-v_j)) * self.f_v;
                }
                // Strategy III: relative velocities over the relative
                // position distances cubed.
                Strategy::III => {
                    let d_i = (r_i - r_j).norm();
                    let d_g = (r_g - r_j).norm();
                    if d_i >= SINGULAR {
                        f += (v_i - v_j) * (self.f_v / (d_i * d_i * d_i));
                    }
                    if d_g >= SINGULAR {
                        f -= -v_j * (self.f_v / (d_g * d_g * d_g));
                    }
                }
            }
        }
        Command::Force(f)
    }
}
