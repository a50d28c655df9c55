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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::Sim;
    use crate::{BodyKind, SelfState, Sensed};

    fn me(pos: Vec2, vel: Vec2) -> SelfState {
        SelfState {
            id: 0,
            position: pos,
            velocity: vel,
            radius: 0.2,
            mass: 10.0,
            damping: 0.5,
            max_speed: 5.0,
            max_accel: 5.0,
            heading: 0.0,
            angular_velocity: 0.0,
            kinematics: crate::Kinematics::Holonomic,
        }
    }

    fn body(id: u32, pos: Vec2, vel: Vec2) -> Sensed {
        Sensed {
            id,
            kind: BodyKind::Robot,
            position: pos,
            velocity: vel,
            acceleration: Vec2::zeros(),
            radius: 0.2,
        }
    }

    fn force(p: &mut Chung, me: SelfState, goal: Vec2, others: &[Sensed]) -> Vec2 {
        p.plan(&crate::testkit::observation(me, goal, others))
            .vector()
    }

    fn chung(strategy: Strategy) -> Chung {
        Chung::from_params(strategy, &Params::new()).unwrap()
    }

    #[test]
    fn defaults_are_the_figure_captions() {
        let c1 = chung(Strategy::I);
        assert_eq!((c1.f_g, c1.alpha, c1.f_m, c1.f_v), (1.0, 0.8, 20.0, 0.0));
        let c2 = chung(Strategy::II);
        assert_eq!((c2.f_m, c2.f_v), (10.0, 0.1));
        let c3 = chung(Strategy::III);
        assert_eq!((c3.f_m, c3.f_v), (10.0, 20.0));
    }

    #[test]
    fn strategy_one_refuses_a_velocity_constant() {
        let mut p = Params::new();
        p.insert("f_v".into(), crate::ParamValue::Number(1.0));
        assert!(Chung::from_params(Strategy::I, &p).is_err());
        assert!(Chung::from_params(Strategy::II, &p).is_ok());
    }

    #[test]
    fn without_bodies_it_is_attraction_minus_f_g_alpha_v() {
        let mut p = chung(Strategy::III);
        p.f_g = 2.0;
        let f = force(
            &mut p,
            me(Vec2::zeros(), Vec2::new(0.0, 1.0)),
            Vec2::new(10.0, 0.0),
            &[],
        );
        assert!((f - Vec2::new(2.0, -1.6)).norm() < 1e-12, "{f}");
    }

    #[test]
    fn repulsion_grows_as_obstacle_nears() {
        for s in [Strategy::I, Strategy::II, Strategy::III] {
            let p = chung(s);
            let goal = Vec2::new(10.0, 0.0);
            let at = |d: f64| {
                let o = [body(1, Vec2::new(d, 0.0), Vec2::new(-0.3, 0.0))];
                force(&mut p.clone(), me(Vec2::zeros(), Vec2::zeros()), goal, &o).x
            };
            // The push back (-x) grows as the obstacle ahead comes nearer.
            assert!(at(1.0) < at(2.0) && at(2.0) < at(4.0), "{s:?}");
            assert!(at(1.0) < 0.0, "{s:?}");
        }
    }

    #[test]
    fn position_repulsion_has_the_hand_computed_value_with_its_goal_counter_term() {
        // Robot at rest at the origin, goal (10, 0), one body at rest at
        // (3, 4); Strategy I, f_g = 1, f_m = 20. By hand:
        //   attraction            (1, 0)
        //   (r_i - r_j)/|.|^3     (-3, -4)/125          = (-0.024, -0.032)
        //   (r_g - r_j)/|.|^3     (7, -4)/65^1.5        = (0.0133576, -0.0076329)
        //   f = (1, 0) + 20 [(-0.024, -0.032) - (0.0133576, -0.0076329)]
        //     = (0.2528483, -0.4873419)
        let mut p = chung(Strategy::I);
        let o = [body(1, Vec2::new(3.0, 4.0), Vec2::zeros())];
        let f = force(
            &mut p,
            me(Vec2::zeros(), Vec2::zeros()),
            Vec2::new(10.0, 0.0),
            &o,
        );
        assert!((f - Vec2::new(0.2528483, -0.4873419)).norm() < 1e-6, "{f}");
    }

    #[test]
    fn strategy_three_velocity_term_has_the_hand_computed_value() {
        // Robot at the origin moving at (0.5, 0), goal (10, 0), one body at
        // (2, 0) moving at (-0.3, 0.4); f_v = 20. Eq (5) as we read it:
        //   (v_i - v_j) f_v / |r_i - r_j|^3 = (0.8, -0.4) 20/8   = (2, -1)
        //   - (v_g - v_j) f_v / |r_g - r_j|^3 = -(0.3, -0.4) 20/512
        //                                     = (-0.01171875, 0.015625)
        // so Strategy III's force is Strategy I's (same f_m) plus
        // (1.98828125, -0.984375); and in full, with attraction (1, 0),
        // damping -0.8 (0.5, 0) and position repulsion
        // 10 [(-2, 0)/8 - (8, 0)/512] = (-2.65625, 0):
        //   (-0.06796875, -0.984375).
        let o = [body(1, Vec2::new(2.0, 0.0), Vec2::new(-0.3, 0.4))];
        let at = me(Vec2::zeros(), Vec2::new(0.5, 0.0));
        let goal = Vec2::new(10.0, 0.0);
        let f3 = force(&mut chung(Strategy::III), at, goal, &o);
        let mut one = chung(Strategy::I);
        one.f_m = 10.0;
        let f1 = force(&mut one, at, goal, &o);
        assert!(
            (f3 - f1 - Vec2::new(1.98828125, -0.984375)).norm() < 1e-12,
            "{}",
            f3 - f1
        );
        assert!(
            (f3 - Vec2::new(-0.06796875, -0.984375)).norm() < 1e-12,
            "{f3}"
        );
    }

    #[test]
    fn the_goal_is_an_equilibrium_because_the_counter_terms_cancel_the_bodies_there() {
        // At the goal at rest each term is its own value minus its value at
        // the goal, so the force vanishes whatever the bodies do. That alone
        // would hold for any kernel; what makes it the paper's equilibrium is
        // that the same bodies push hard 5 cm away (the hand-computed kernel
        // is pinned by the two tests above).
        let goal = Vec2::new(3.0, 1.0);
        let others = [
            body(1, Vec2::new(4.0, 1.5), Vec2::new(0.2, -0.1)),
            body(2, Vec2::new(2.0, 0.0), Vec2::new(-0.4, 0.3)),
        ];
        for s in [Strategy::I, Strategy::II, Strategy::III] {
            let mut p = chung(s);
            let f = force(&mut p, me(goal, Vec2::zeros()), goal, &others);
            assert!(f.norm() < 1e-12, "{s:?}: {f}");
            let near = me(goal + Vec2::new(0.05, 0.0), Vec2::zeros());
            let with = force(&mut chung(s), near, goal, &others);
            let without = force(&mut chung(s), near, goal, &[]);
            assert!((with - without).norm() > 0.1, "{s:?}: {}", with - without);
        }
    }

    #[test]
    fn strategy_two_pushes_along_its_own_velocity_when_bodies_rest() {
        // Sensed body at rest: eq (4)'s term is f_v v_i/||v_i||^3, growing
        // as the robot slows.
        let mut p = chung(Strategy::II);
        p.f_m = 0.0;
        p.alpha = 0.0;
        let goal = Vec2::new(0.0, 0.0);
        let o = [body(1, Vec2::new(5.0, 5.0), Vec2::zeros())];
        let slow = force(&mut p, me(goal, Vec2::new(0.01, 0.0)), goal, &o);
        let fast = force(&mut p, me(goal, Vec2::new(0.1, 0.0)), goal, &o);
        assert!((slow.x - 0.1 / 1e-4).abs() < 1e-6, "{slow}");
        assert!(slow.x > fast.x && fast.x > 0.0);
    }

    #[test]
    fn strategy_three_velocity_term_fades_with_distance() {
        let mut p = chung(Strategy::III);
        p.f_m = 0.0;
        p.alpha = 0.0;
        let goal = Vec2::new(0.0, 0.0);
        let pos = Vec2::new(-20.0, 0.0);
        let near = [body(1, Vec2::new(-19.0, 0.0), Vec2::new(-1.0, 0.0))];
        let far = [body(1, Vec2::new(-16.0, 0.0), Vec2::new(-1.0, 0.0))];
        let attraction = 1.0;
        let fn_ = force(&mut p, me(pos, Vec2::zeros()), goal, &near).x - attraction;
        let ff = force(&mut p, me(pos, Vec2::zeros()), goal, &far).x - attraction;
        assert!(fn_ > ff && ff > 0.0, "{fn_} {ff}");
    }

    #[test]
    fn strategy_one_passes_a_crossing_robot_and_reaches_the_goal() {
        let mut sim = Sim::new(0.1, 10);
        let r0 = sim.add_robot(
            Box::new(chung(Strategy::I)),
            Vec2::zeros(),
            Vec2::new(10.0, 0.0),
            0.2,
            10.0,
            0.5,
            2.0,
            5.0,
        );
        sim.add_obstacle(Vec2::new(5.0, -5.0), Vec2::new(0.0, 0.4), 0.2);
        let mut min_clear = f64::INFINITY;
        for _ in 0..1500 {
            sim.step();
            min_clear = min_clear.min(sim.clearance(r0));
        }
        assert!(min_clear > 0.0, "collided: {min_clear}");
        let end = sim.robots[r0].state.position;
        assert!((end - Vec2::new(10.0, 0.0)).norm() < 0.3, "{end}");
    }

    /// The chung-strategy-{2,3} scenarios: returns the robot's largest
    /// distance to its goal from 200 s to 300 s, the number of sign changes
    /// of x - 10 in that window, and its smallest clearance.
    fn crossing_scenario(strategy: Strategy, f_v: f64) -> (f64, usize, f64) {
        let mut sim = Sim::new(0.1, 10);
        let goal = Vec2::new(10.0, 0.0);
        let mut planner = chung(strategy);
        planner.f_m = 10.0;
        planner.f_v = f_v;
        let r0 = sim.add_robot(
            Box::new(planner),
            Vec2::zeros(),
            goal,
            0.2,
            10.0,
            0.5,
            2.0,
            1.0,
        );
        for (start, end) in [((4.0, -5.0), (4.0, 5.0)), ((7.0, 6.0), (7.0, -4.0))] {
            let h = crate::homing::Homing {
                f_g: 1.0,
                alpha: 0.8,
            };
            sim.add_robot(
                Box::new(h),
                Vec2::new(start.0, start.1),
                Vec2::new(end.0, end.1),
                0.2,
                10.0,
                0.5,
                2.0,
                1.0,
            );
        }
        let (mut dev, mut changes, mut min_clear, mut last) = (0.0f64, 0, f64::INFINITY, 0.0);
        for tick in 1..=3000 {
            sim.step();
            min_clear = min_clear.min(sim.clearance(r0));
            if tick > 2000 {
                let p = sim.robots[r0].state.position;
                dev = dev.max((p - goal).norm());
                let e = p.x - goal.x;
                if e * last < 0.0 {
                    changes += 1;
                }
                if e != 0.0 {
                    last = e;
                }
            }
        }
        (dev, changes, min_clear)
    }

    #[test]
    fn scenario_files_carry_the_numbers_these_tests_use() {
        let two = include_str!("../../../scenarios/papers/chung-strategy-2.toml");
        let three = include_str!("../../../scenarios/papers/chung-strategy-3.toml");
        for (text, f_v) in [(two, "0.1"), (three, "20.0")] {
            assert!(text.contains(&format!("f_g = 1.0, alpha = 0.8, f_m = 10.0, f_v = {f_v}")));
            assert!(text.contains("mass = 10.0") && text.contains("damping = 0.5"));
            assert!(text.contains("max_speed = 2.0") && text.contains("max_accel = 1.0"));
            assert!(text.contains("radius = 0.2") && text.contains("goal = [10.0, 0.0]"));
            assert!(text.contains("start = [4.0, -5.0]") && text.contains("goal = [4.0, 5.0]"));
            assert!(text.contains("start = [7.0, 6.0]") && text.contains("goal = [7.0, -4.0]"));
            assert!(text.contains("params = { f_g = 1.0, alpha = 0.8 }"));
        }
    }

    #[test]
    fn strategy_two_keeps_oscillating_around_the_goal() {
        let (dev, changes, min_clear) = crossing_scenario(Strategy::II, 0.1);
        assert!(dev > 1.0, "{dev}");
        assert!(changes >= 3, "{changes}");
        assert!(min_clear > 0.0);
    }

    #[test]
    fn strategy_three_settles_at_the_goal() {
        let (dev, _, min_clear) = crossing_scenario(Strategy::III, 20.0);
        assert!(dev < 0.1, "{dev}");
        assert!(min_clear > 0.0);
    }
}
