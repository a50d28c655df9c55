//! Virtual distance function (VDF) potential field: Ko & Choi, "A New
//! Approach to Moving Obstacle Avoidance Problem of a Mobile Robot"
//! eqs (1)-(22).
//!
//! Per sensed body o (robots and obstacles alike):
//!
//! ```text
//! d     = ||P_o - P|| - r_o                      distance             (1)
//! v_or  = P_o' . (P_o - P)/||P_o - P||           outward speed        (2)
//! vd    = alpha d / (beta - v_or)                virtual distance     (3)
//! U_o   = eta/2 (1/vd - 1/eps_vd)^2, vd <= eps_vd; 0 beyond          (7)
//! U_g   = zeta/2 ||P - P_g||^2                                        (8)
//! F_art = -grad_P (sum_o U_o + U_g)                                   (6), (9)
//! ```
//!
//! The gradient is taken with respect to the robot's position P, including
//! the dependence of v_or on P through the unit vector u = (P_o - P)/|P_o - P|:
//!
//! ```text
//! grad d    = -u
//! grad v_or = -(I - u u^T) P_o' / ||P_o - P||
//! grad vd   = alpha [ (beta - v_or) grad d + d grad v_or ] / (beta - v_or)^2
//! grad U_o  = -eta (1/vd - 1/eps_vd) / vd^2 * grad vd
//! ```
//!
//! Driving force, eqs (10)-(21): the paper's robot keeps the acceleration of
//! the previous period, P''(t_i), and adds F_art/m to it (eq 11, the
//! carried-over inertial term). F_art is scaled by the largest k in [0, 1]
//! that keeps ||P''(t_i) + k F_art/m|| <= a_max (eq 13), giving a_acc (eq 15).
//! If the velocity v + s a_acc would pass v_max at s = t_v - t_i inside the
//! period (eqs 16-18), the acceleration is a_acc until t_v and zero after
//! (eq 19), so the acceleration carried into the next period is zero.
//! m, a_max and v_max are the robot's own (`obs.me`).
//!
//! Eq (22), the goal test: once the robot has been within the goal
//! tolerance (`obs.goal_tolerance`, the paper's eps_d) for N + 1 consecutive
//! ticks, the planner stops driving and brakes to rest, and stays so.
//!
//! Readings and choices where the text is garbled, silent or self-
//! contradictory:
//! - Eq (1)'s robot is a point; for a robot with a radius we subtract it
//!   too (d is the surface-to-surface gap).
//! - Eq (2) uses the obstacle's own velocity, not the velocity relative to
//!   the robot, although the abstract says "relative to the robot"; we
//!   follow the equation.
//! - Eq (4) requires beta > |v_or|, which the paper's own cases 1-3 break
//!   (beta = 5 cm/s, obstacle speed 11.2-14.9 cm/s). For v_or <= -beta the
//!   formula is still positive and is used as printed. For v_or >= beta (the
//!   body recedes at least as fast as beta) vd would be infinite or
//!   negative; we take vd = +infinity there, the limit of eq (3) as v_or
//!   rises to beta, i.e. no repulsion from a body that moves away that
//!   fast. Its diagnostic `vd_<id>` is then `inf`.
//! - Inside a body (d <= 0: a collision, where the paper stops the robot,
//!   Step 5), d is floored at a tiny positive value so the robot is pushed
//!   straight out instead of the potential flipping sign.
//! - The world holds one force for the whole tick and cannot switch at t_v.
//!   When the speed limit falls inside the period we command the constant
//!   acceleration a_acc (t_v - t_i)/dt, which ends the tick at exactly the
//!   paper's velocity P'(t_v) (eq 17-19) without touching the limit on the
//!   way; only the position within the tick differs from eq (21). A robot
//!   already at v_max whose a_acc has no component against its velocity
//!   has t_v = t_i: it coasts, as eq (19) says.
//! - The world's force is m r'' + b r' = f (Chung eq 1); the paper has no
//!   friction, so the planner adds b v to its force to cancel the damping
//!   at the start of the tick (exact when b = 0, as in the paper's cases).
//! - The paper's eq (11) dynamics are third order (force changes the
//!   acceleration) and undamped, and eq (19) zeroes the acceleration at
//!   the speed limit, so a robot at top speed cannot turn unless the force
//!   has a component against its velocity. Together they never let the
//!   robot settle: in cases 1-3, after the encounter, it circles the goal
//!   at top speed on a slowly widening path (30-90 cm away after two
//!   minutes) and eq (22) never holds. The unit tests below measure that
//!   rather than hide it; the scenario files say so.
//! - Eq (22)'s N is the robot's `goal_hold_ticks` and eps_d its
//!   `goal_tolerance`, both from the observation. As printed, eq (22)
//!   asks for N + 1 consecutive samples (k = i+1-N, ..., i+1), and the
//!   planner follows it; the world's `reached_goal` metric counts N
//!   samples, so it is recorded one tick before this planner brakes.
//!
//! Parameters (defaults: section 5.1, cases 1-3, in cm): `alpha` (5),
//! `beta` (5), `eta` (1000), `zeta` (2), `eps_vd` (40).

use crate::{Command, Diagnostic, Observation, ParamError, ParamReader, Params, Planner, Vec2};

/// Floor of the gap d inside a body.
const D_MIN: f64 = 1e-9;

/// Ko & Choi's VDF planner (and, with the outward speed ignored, Khatib's).
#[derive(Debug, Clone)]
pub struct Vdf {
    /// Scale of the virtual distance, eq (3).
    pub alpha: f64,
    /// Outward-speed offset, eq (3).
    pub beta: f64,
    /// Repulsive coefficient, eq (7).
    pub eta: f64,
    /// Attractive coefficient, eq (8).
    pub zeta: f64,
    /// Limit (virtual) distance of the repulsive field, eq (7).
    pub eps_vd: f64,
    /// False for Khatib's field: vd = d, the outward speed ignored.
    pub use_outward_speed: bool,
    /// Prefix of the per-body diagnostic (`vd_` or `d_`).
    diag_prefix: &'static str,
    /// P''(t_i): the acceleration carried into the next period (eq 11).
    accel: Vec2,
    /// Consecutive ticks within the goal tolerance.
    ticks_in_tolerance: u32,
    /// Eq (22) has held: brake and stay.
    arrived: bool,
    /// (body id, virtual distance) from the last `plan`.
    vds: Vec<(u32, f64)>,
}

/// One body's contribution: its virtual distance and its repulsive force
/// -grad U_o (zero beyond eps_vd).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Repulsion {
    /// Virtual distance vd (eq 3), +infinity when v_or >= beta.
    pub vd: f64,
    /// F_o = -grad_P U_o (eqs 7, 9).
    pub force: Vec2,
}

impl Vdf {
    /// A planner with the given coefficients and no history.
    pub fn new(alpha: f64, beta: f64, eta: f64, zeta: f64, eps_vd: f64) -> Self {
        Self {
            alpha,
            beta,
            eta,
            zeta,
            eps_vd,
            use_outward_speed: true,
            diag_prefix: "vd_",
            accel: Vec2::zeros(),
            ticks_in_tolerance: 0,
            arrived: false,
            vds: Vec::new(),
        }
    }

    /// Khatib's classic field (vd = d): the case-7 limit alpha = beta -> inf.
    pub fn khatib(eta: f64, zeta: f64, eps_d: f64) -> Self {
        let mut v = Self::new(1.0, 1.0, eta, zeta, eps_d);
        v.use_outward_speed = false;
        v.diag_prefix = "d_";
        v
    }

    /// Reads `alpha`, `beta`, `eta`, `zeta`, `eps_vd`.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new("vdf", params);
        let alpha = r.positive("alpha", 5.0)?;
        let beta = r.positive("beta", 5.0)?;
        let eta = r.non_negative("eta", 1000.0)?;
        let zeta = r.non_negative("zeta", 2.0)?;
        let eps_vd = r.positive("eps_vd", 40.0)?;
        r.finish()?;
        Ok(Self::new(alpha, beta, eta, zeta, eps_vd))
    }

    /// The acceleration carried into the next period, P''(t_{i+1}).
    pub fn carried_acceleration(&self) -> Vec2 {
        self.accel
    }

    /// Virtual distance (eq 3) of a body at `p_o` with velocity `v_o` and
    /// radius `r_o`, seen from a robot of radius `r_me` at `p`.
    pub fn virtual_distance(&self, p: Vec2, r_me: f64, p_o: Vec2, v_o: Vec2, r_o: f64) -> f64 {
        self.repulsion(p, r_me, p_o, v_o, r_o).vd
    }

    /// The repulsive potential U_o (eq 7) at `p`.
    pub fn potential(&self, p: Vec2, r_me: f64, p_o: Vec2, v_o: Vec2, r_o: f64) -> f64 {
        let vd = self.virtual_distance(p, r_me, p_o, v_o, r_o);
        if vd <= self.eps_vd {
            0.5 * self.eta * (1.0 / vd - 1.0 / self.eps_vd).powi(2)
        } else {
            0.0
        }
    }

    /// Eqs (1)-(3), (7), (9) for one body: vd and -grad_P U_o.
    pub fn repulsion(&self, p: Vec2, r_me: f64, p_o: Vec2, v_o: Vec2, r_o: f64) -> Repulsion {
        let rel = p_o - p;
        let dist = rel.norm();
        if dist <= D_MIN {
            // At the body's centre: no direction to push; nothing defined.
            return Repulsion {
                vd: 0.0,
                force: Vec2::zeros(),
            };
        }
        let u = rel / dist;
        // Eq (1): the gap, floored inside the body.
        let d = (dist - r_o - r_me).max(D_MIN);
        let grad_d = -u;
        let (vd, grad_vd) = if self.use_outward_speed {
            // Eq (2): the outward speed of the body.
            let v_or = v_o.dot(&u);
            let denom = self.beta - v_or;
            // Eq (4) broken on the receding side: vd = +infinity.
            if denom <= 0.0 {
                return Repulsion {
                    vd: f64::INFINITY,
                    force: Vec2::zeros(),
                };
            }
            // grad v_or = -(I - u u^T) v_o / dist.
            let grad_v = -(v_o - u * v_or) / dist;
            let vd = self.alpha * d / denom;
            let grad_vd = (grad_d * denom + grad_v * d) * (self.alpha / (denom * denom));
            (vd, grad_vd)
        } else {
            // Khatib: the real distance.
            (d, grad_d)
        };
        // Eq (7): outside eps_vd the body exerts nothing.
        if vd > self.eps_vd {
            return Repulsion {
                vd,
                force: Vec2::zeros(),
            };
        }
        // Eq (9): F_o = -grad U_o = eta (1/vd - 1/eps) / vd^2 grad vd.
        let coef = self.eta * (1.0 / vd - 1.0 / self.eps_vd) / (vd * vd);
        Repulsion {
            vd,
            force: grad_vd * coef,
        }
    }

    /// F_art (eq 9) at the robot's position, recording each body's vd.
    fn artificial_force(&mut self, obs: &Observation) -> Vec2 {
        let p = obs.me.position;
        // Eq (8): attraction -zeta (P - P_g).
        let mut f = (obs.goal - p) * self.zeta;
        self.vds.clear();
        for o in obs.others {
            let rep = self.repulsion(p, obs.me.radius, o.position, o.velocity, o.radius);
            self.vds.push((o.id, rep.vd));
            f += rep.force;
        }
        f
    }
}

/// Eq (13): the largest k in [0, 1] with ||a + k g|| <= a_max, given
/// ||a|| <= a_max.
fn scale_to_accel_limit(a: Vec2, g: Vec2, a_max: f64) -> f64 {
    if (a + g).norm() <= a_max {
        return 1.0;
    }
    let gg = g.norm_squared();
    let ag = a.dot(&g);
    let c = a.norm_squared() - a_max * a_max;
    let disc = ag * ag - gg * c;
    if gg <= 0.0 || disc < 0.0 {
        return 0.0;
    }
    ((-ag + disc.sqrt()) / gg).clamp(0.0, 1.0)
}

/// Eq (18): the first s in (0, dt] where ||v + s a|| reaches v_max while
/// rising, or None if the speed stays within the limit over the period.
fn time_to_speed_limit(v: Vec2, a: Vec2, v_max: f64, dt: f64) -> Option<f64> {
    if (v + a * dt).norm() <= v_max {
        return None;
    }
    let aa = a.norm_squared();
    if aa <= 0.0 {
        return None;
    }
    let va = v.dot(&a);
    let c = v.norm_squared() - v_max * v_max;
    let disc = (va * va - aa * c).max(0.0);
    // Largest root: where the speed leaves the limit ball (0 if already out
    // and rising, i.e. at the limit with no component against v).
    let s = (-va + disc.sqrt()) / aa;
    Some(s.clamp(0.0, dt))
}

impl Planner for Vdf {
    fn plan(&mut self, obs: &Observation) -> Command {
        let me = obs.me;
        let m = me.mass;
        let dt = obs.dt;
        let f_art = self.artificial_force(obs);
        // Eq (22): N + 1 consecutive samples within eps_d of the goal.
        if (me.position - obs.goal).norm() <= obs.goal_tolerance {
            self.ticks_in_tolerance = self.ticks_in_tolerance.saturating_add(1);
        } else {
            self.ticks_in_tolerance = 0;
        }
        if self.ticks_in_tolerance > obs.goal_hold_ticks {
            self.arrived = true;
        }
        if self.arrived {
            // Goal reached: stop driving, brake to rest within the limit.
            let mut a = -me.velocity / dt;
            if a.norm() > me.max_accel {
                a *= me.max_accel / a.norm();
            }
            self.accel = Vec2::zeros();
            return Command::Force(a * m + me.velocity * me.damping);
        }
        // Eqs (10)-(13): the carried acceleration plus k F_art/m within a_max.
        let mut carried = self.accel;
        if carried.norm() > me.max_accel {
            carried *= me.max_accel / carried.norm();
        }
        let g = f_art / m;
        let k = scale_to_accel_limit(carried, g, me.max_accel);
        // Eq (15): a_acc.
        let a_acc = carried + g * k;
        // Eqs (16)-(19): the velocity limit within the period.
        let a_cmd = match time_to_speed_limit(me.velocity, a_acc, me.max_speed, dt) {
            // Speed stays within v_max: a_acc for the whole period.
            None => {
                self.accel = a_acc;
                a_acc
            }
            // Speed reaches v_max at t_v: a_acc until t_v, zero after, so
            // the acceleration carried over is zero; the world holds one
            // force, so command the mean acceleration that ends the tick at
            // P'(t_v).
            Some(t_v) => {
                self.accel = Vec2::zeros();
                a_acc * (t_v / dt)
            }
        };
        // Eq (20), in the world's m r'' + b r' = f.
        Command::Force(a_cmd * m + me.velocity * me.damping)
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.vds
            .iter()
            .map(|&(id, vd)| Diagnostic {
                name: format!("{}{id}", self.diag_prefix),
                value: vd,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BodyKind, SelfState, Sensed};

    fn me(pos: Vec2, vel: Vec2) -> SelfState {
        SelfState {
            id: 0,
            position: pos,
            velocity: vel,
            radius: 0.0,
            mass: 0.1,
            damping: 0.0,
            max_speed: 30.0,
            max_accel: 500.0,
            heading: 0.0,
            angular_velocity: 0.0,
            kinematics: crate::Kinematics::Holonomic,
        }
    }

    fn body(id: u32, pos: Vec2, vel: Vec2, r: f64) -> Sensed {
        Sensed {
            id,
            kind: BodyKind::Obstacle,
            position: pos,
            velocity: vel,
            acceleration: Vec2::zeros(),
            radius: r,
        }
    }

    fn obs<'a>(me: SelfState, goal: Vec2, others: &'a [Sensed]) -> Observation<'a> {
        Observation {
            goal_tolerance: 1.0,
            ..crate::testkit::observation(me, goal, others)
        }
    }

    #[test]
    fn gradient_matches_central_finite_differences() {
        let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let p_o = Vec2::new(20.0, 5.0);
        let cases = [
            (Vec2::new(3.0, 1.0), Vec2::new(-5.0, -10.0)),
            (Vec2::new(10.0, 12.0), Vec2::new(2.0, -3.0)),
            (Vec2::new(15.0, -2.0), Vec2::new(-1.0, 4.0)),
            (Vec2::new(12.0, 6.0), Vec2::new(0.0, 0.0)),
        ];
        for (p, v_o) in cases {
            let rep = v.repulsion(p, 0.0, p_o, v_o, 5.0);
            assert!(rep.vd < v.eps_vd && rep.vd.is_finite(), "{p}: {}", rep.vd);
            let h = 1e-5;
            let u = |q: Vec2| v.potential(q, 0.0, p_o, v_o, 5.0);
            let gx = (u(p + Vec2::new(h, 0.0)) - u(p - Vec2::new(h, 0.0))) / (2.0 * h);
            let gy = (u(p + Vec2::new(0.0, h)) - u(p - Vec2::new(0.0, h))) / (2.0 * h);
            let fd = -Vec2::new(gx, gy);
            let rel = (rep.force - fd).norm() / fd.norm().max(1e-12);
            assert!(rel < 1e-6, "at {p}: analytic {} vs fd {fd}", rep.force);
            // And the outward-speed part matters: the force with v_or's own
            // dependence on P dropped (grad vd = alpha grad d / (beta - v_or),
            // eq 3 with v_or held fixed) differs from the finite difference
            // wherever the body moves across the line of sight.
            let rel = p_o - p;
            let u = rel / rel.norm();
            let across = (v_o - u * v_o.dot(&u)).norm();
            if across > 0.0 {
                let denom = v.beta - v_o.dot(&u);
                let coef = v.eta * (1.0 / rep.vd - 1.0 / v.eps_vd) / (rep.vd * rep.vd);
                let d_only = -u * (v.alpha / denom) * coef;
                let miss = (d_only - fd).norm() / fd.norm();
                assert!(
                    miss > 1e-3,
                    "at {p}: v_or's gradient changes the force by {miss}"
                );
            }
        }
    }

    #[test]
    fn eq_7_has_the_hand_computed_values() {
        // Robot (a point) at the origin, a body of radius 5 at (20, 0), so
        // d = 15 and u = (1, 0); alpha = beta = 5, eta = 1000, eps_vd = 40.
        // Approaching at (-3, 0): v_or = -3, vd = 5 * 15 / 8 = 9.375,
        //   U = 500 (1/9.375 - 1/40)^2 = 3.3347222,
        //   grad vd = 5 (-1, 0)/8, F = 1000 (1/9.375 - 1/40)/9.375^2 grad vd
        //     = (-0.5807407, 0).
        // Crossing at (0, 4): v_or = 0, vd = 15, U = 500 (1/15 - 1/40)^2
        //   = 0.8680556; grad v_or = -(0, 4)/20, grad vd = 5 [5 (-1, 0)
        //   + 15 (0, -0.2)]/25 = (-1, -0.6), F = 1000 (1/15 - 1/40)/225
        //   (-1, -0.6) = (-0.1851852, -0.1111111).
        // Receding at (3, 0): vd = 37.5, U = 0.0013889; at (3.5, 0): vd = 50
        //   is beyond eps_vd, U = 0 and no force.
        let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let p_o = Vec2::new(20.0, 0.0);
        let cases = [
            ((-3.0, 0.0), 9.375, 3.3347222, (-0.5807407, 0.0)),
            ((0.0, 4.0), 15.0, 0.8680556, (-0.1851852, -0.1111111)),
            ((3.0, 0.0), 37.5, 0.0013889, (-0.0029630, 0.0)),
            ((3.5, 0.0), 50.0, 0.0, (0.0, 0.0)),
        ];
        for ((vx, vy), vd, u, (fx, fy)) in cases {
            let v_o = Vec2::new(vx, vy);
            let rep = v.repulsion(Vec2::zeros(), 0.0, p_o, v_o, 5.0);
            assert!((rep.vd - vd).abs() < 1e-12, "{v_o}: vd {}", rep.vd);
            let pot = v.potential(Vec2::zeros(), 0.0, p_o, v_o, 5.0);
            assert!((pot - u).abs() < 1e-7, "{v_o}: U {pot}");
            assert!(
                (rep.force - Vec2::new(fx, fy)).norm() < 1e-7,
                "{v_o}: {}",
                rep.force
            );
        }
    }

    #[test]
    fn gradient_includes_the_outward_speed_dependence_on_position() {
        // Robot beside a body moving across the line of sight: moving the
        // robot sideways changes v_or, so the force has a sideways part the
        // distance alone would not give.
        let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let p_o = Vec2::new(10.0, 0.0);
        let rep = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(0.0, -4.0), 1.0);
        assert!(rep.force.x < 0.0);
        assert!(
            rep.force.y.abs() > 1e-3 * rep.force.x.abs(),
            "{}",
            rep.force
        );
        let still = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::zeros(), 1.0);
        assert!(still.force.y.abs() < 1e-12);
    }

    #[test]
    fn repulsion_grows_as_obstacle_nears() {
        let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let mut last = 0.0;
        for x in [40.0, 30.0, 20.0, 12.0, 8.0, 6.0] {
            let rep = v.repulsion(
                Vec2::zeros(),
                0.0,
                Vec2::new(x, 0.0),
                Vec2::new(-3.0, 0.0),
                5.0,
            );
            let push = -rep.force.x;
            assert!(push >= last, "at {x}: {push} < {last}");
            last = push;
        }
        assert!(last > 0.0);
    }

    #[test]
    fn outward_speed_raises_the_virtual_distance() {
        let v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let p_o = Vec2::new(20.0, 0.0);
        let vd = |vx: f64| v.virtual_distance(Vec2::zeros(), 0.0, p_o, Vec2::new(vx, 0.0), 5.0);
        assert!(
            vd(-4.0) < vd(-1.0) && vd(-1.0) < vd(0.0) && vd(0.0) < vd(2.0) && vd(2.0) < vd(4.9)
        );
        // Stationary: vd = (alpha/beta) d.
        assert!((vd(0.0) - 15.0).abs() < 1e-12);
        // Eq (4) broken on the receding side: infinite, no force.
        assert_eq!(vd(5.0), f64::INFINITY);
        assert_eq!(vd(7.0), f64::INFINITY);
    }

    #[test]
    fn khatib_ignores_the_outward_speed() {
        let k = Vdf::khatib(1e4, 2.0, 40.0);
        let p_o = Vec2::new(20.0, 0.0);
        let a = k.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(-10.0, 3.0), 5.0);
        let b = k.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(10.0, 0.0), 5.0);
        assert_eq!(a, b);
        assert!((a.vd - 15.0).abs() < 1e-12);
        // Case 7's huge alpha = beta gives the same field.
        let v = Vdf::new(1e8, 1e8, 1e4, 2.0, 40.0);
        let c = v.repulsion(Vec2::zeros(), 0.0, p_o, Vec2::new(-10.0, 3.0), 5.0);
        assert!((c.force - a.force).norm() < 1e-5 * a.force.norm());
    }

    #[test]
    fn acceleration_stays_within_the_limit_including_the_carried_term() {
        // eq (12): ||P''(t_i) + F_acc/m|| <= a_max, every tick, whatever the force.
        let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let others = [body(1, Vec2::new(8.0, 1.0), Vec2::new(-5.0, -3.0), 5.0)];
        let mut vel = Vec2::new(3.0, 0.0);
        for i in 0..20 {
            let s = me(Vec2::new(i as f64 * 0.1, 0.0), vel);
            let f = v.plan(&obs(s, Vec2::new(80.0, -40.0), &others)).vector();
            let a = f / s.mass;
            assert!(a.norm() <= s.max_accel * (1.0 + 1e-12), "{}", a.norm());
            assert!(v.carried_acceleration().norm() <= s.max_accel * (1.0 + 1e-12));
            vel += a * 0.1;
            // eq (16): the velocity at the end of the period within v_max.
            assert!(vel.norm() <= s.max_speed * (1.0 + 1e-9), "{}", vel.norm());
        }
    }

    #[test]
    fn the_carried_acceleration_accumulates_the_artificial_force() {
        // eq (11): a small constant F_art adds F_art/m every period.
        let mut v = Vdf::new(5.0, 5.0, 0.0, 2.0, 40.0);
        let s = me(Vec2::zeros(), Vec2::zeros());
        let goal = Vec2::new(10.0, 0.0);
        let mut s_big = s;
        s_big.max_accel = 1e6;
        s_big.max_speed = 1e6;
        let a1 = v.plan(&obs(s_big, goal, &[])).vector() / s.mass;
        let a2 = v.plan(&obs(s_big, goal, &[])).vector() / s.mass;
        assert!((a1.x - 200.0).abs() < 1e-9, "{a1}");
        assert!((a2.x - 400.0).abs() < 1e-9, "{a2}");
    }

    #[test]
    fn scaling_keeps_direction_and_picks_the_largest_k() {
        let a = Vec2::new(300.0, 0.0);
        let g = Vec2::new(0.0, 1000.0);
        let k = scale_to_accel_limit(a, g, 500.0);
        assert!(((a + g * k).norm() - 500.0).abs() < 1e-9);
        assert!((k - 0.4).abs() < 1e-12);
        assert_eq!(scale_to_accel_limit(a, Vec2::new(-100.0, 0.0), 500.0), 1.0);
    }

    #[test]
    fn speed_limit_time_solves_eq_18() {
        let s = time_to_speed_limit(Vec2::new(20.0, 0.0), Vec2::new(500.0, 0.0), 30.0, 0.1);
        assert!((s.unwrap() - 0.02).abs() < 1e-12);
        assert_eq!(
            time_to_speed_limit(Vec2::new(20.0, 0.0), Vec2::new(50.0, 0.0), 30.0, 0.1),
            None
        );
        // At the limit and pushing sideways: coasts (t_v = t_i).
        let s = time_to_speed_limit(Vec2::new(30.0, 0.0), Vec2::new(0.0, 100.0), 30.0, 0.1);
        assert_eq!(s, Some(0.0));
    }

    #[test]
    fn diagnostics_name_each_body_vd() {
        let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let others = [
            body(4, Vec2::new(20.0, 0.0), Vec2::zeros(), 5.0),
            body(9, Vec2::new(0.0, 30.0), Vec2::new(0.0, 10.0), 5.0),
        ];
        v.plan(&obs(
            me(Vec2::zeros(), Vec2::zeros()),
            Vec2::new(80.0, 0.0),
            &others,
        ));
        let d = v.diagnostics();
        assert_eq!(d.len(), 2);
        assert_eq!(d[0].name, "vd_4");
        assert!((d[0].value - 15.0).abs() < 1e-12);
        assert_eq!(d[1].name, "vd_9");
        assert_eq!(d[1].value, f64::INFINITY);
    }

    #[test]
    fn the_goal_test_counts_the_robots_own_goal_hold_ticks() {
        // N = 6 from the observation: the seventh consecutive sample brakes.
        let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let goal = Vec2::new(10.0, 0.0);
        let vel = Vec2::new(2.0, 0.0);
        let s = me(Vec2::new(9.8, 0.0), vel);
        let mut o = obs(s, goal, &[]);
        o.goal_hold_ticks = 6;
        for _ in 0..6 {
            assert!(v.plan(&o).vector().x > 0.0);
        }
        let f = v.plan(&o).vector();
        assert!((f / s.mass - (-vel / 0.1)).norm() < 1e-9, "{f}");
    }

    #[test]
    fn it_brakes_once_the_goal_test_holds() {
        let mut v = Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0);
        let goal = Vec2::new(10.0, 0.0);
        let vel = Vec2::new(2.0, 0.0);
        let s = me(Vec2::new(9.8, 0.0), vel);
        // N = 3: the fourth consecutive sample within tolerance triggers it.
        for _ in 0..3 {
            let f = v.plan(&obs(s, goal, &[])).vector();
            assert!(f.x > 0.0);
        }
        let f = v.plan(&obs(s, goal, &[])).vector();
        assert!((f / s.mass - (-vel / 0.1)).norm() < 1e-9, "{f}");
        // Latched: a later sample outside the tolerance still brakes.
        let far = me(Vec2::new(5.0, 0.0), vel);
        let f = v.plan(&obs(far, goal, &[])).vector();
        assert!(f.x < 0.0);
    }
}

/// Ko & Choi section 5.1, cases 1-3, built from the same numbers as
/// scenarios/papers/ko-choi-case-{1,2,3}.toml and run in the testkit.
#[cfg(test)]
mod ko_choi_cases {
    use super::*;
    use crate::testkit::Sim;

    /// The robot speed limit chosen for the scenario files (cm/s).
    const MAX_SPEED: f64 = 23.3;
    const START: [f64; 2] = [0.0, 2.0];
    const GOAL: [f64; 2] = [80.0, -40.0];
    const OBSTACLE_START: [f64; 2] = [55.0, 3.0];
    const OBSTACLE_RADIUS: f64 = 5.0;
    const CASES: [(&str, [f64; 2]); 3] = [
        (
            include_str!("../../../scenarios/papers/ko-choi-case-1.toml"),
            [-5.0, -10.0],
        ),
        (
            include_str!("../../../scenarios/papers/ko-choi-case-2.toml"),
            [-5.0, -11.0],
        ),
        (
            include_str!("../../../scenarios/papers/ko-choi-case-3.toml"),
            [-5.0, -14.0],
        ),
    ];

    struct Outcome {
        /// Where the robot first crosses the obstacle's line: its offset
        /// along the obstacle's motion from the obstacle's centre (> 0:
        /// in front of it, i.e. ahead).
        crossing_offset: f64,
        /// Sign changes of the along-track velocity before that crossing.
        reversals: usize,
        min_clearance: f64,
        /// Distance to the goal, 10 s to 60 s.
        goal_distance: (f64, f64),
        goal_test_held: bool,
    }

    fn run(max_speed: f64, v_o: [f64; 2]) -> Outcome {
        let mut sim = Sim::new(0.1, 10);
        let goal = Vec2::from(GOAL);
        let start = Vec2::from(START);
        let r = sim.add_robot(
            Box::new(Vdf::new(5.0, 5.0, 1000.0, 2.0, 40.0)),
            start,
            goal,
            0.0,
            0.1,
            0.0,
            max_speed,
            500.0,
        );
        let v_o = Vec2::from(v_o);
        sim.add_obstacle(Vec2::from(OBSTACLE_START), v_o, OBSTACLE_RADIUS);
        let dir = v_o.normalize();
        let normal = Vec2::new(-dir.y, dir.x);
        let track = (goal - start).normalize();
        let mut out = Outcome {
            crossing_offset: f64::NAN,
            reversals: 0,
            min_clearance: f64::INFINITY,
            goal_distance: (f64::INFINITY, 0.0),
            goal_test_held: false,
        };
        let (mut side_prev, mut along_prev, mut within) = (f64::NAN, 0.0, 0);
        for tick in 1..=600 {
            sim.step();
            out.min_clearance = out.min_clearance.min(sim.clearance(r));
            let s = sim.robots[r].state;
            let rel = s.position - sim.obstacles[0].position;
            let side = rel.dot(&normal);
            if out.crossing_offset.is_nan() {
                if side * side_prev < 0.0 {
                    out.crossing_offset = rel.dot(&dir);
                }
                let along = s.velocity.dot(&track);
                if along * along_prev < 0.0 {
                    out.reversals += 1;
                }
                if along != 0.0 {
                    along_prev = along;
                }
            }
            side_prev = side;
            let d = (s.position - goal).norm();
            within = if d <= 1.0 { within + 1 } else { 0 };
            out.goal_test_held |= within > 3;
            if tick >= 100 {
                out.goal_distance = (out.goal_distance.0.min(d), out.goal_distance.1.max(d));
            }
        }
        out
    }

    #[test]
    fn scenario_files_carry_the_numbers_these_tests_use() {
        for (text, v_o) in CASES {
            assert!(text.contains(&format!("max_speed = {MAX_SPEED}")));
            assert!(text.contains(&format!("velocity = [{:?}, {:?}]", v_o[0], v_o[1])));
            assert!(text.contains("start = [0.0, 2.0]") && text.contains("goal = [80.0, -40.0]"));
            assert!(text.contains("start = [55.0, 3.0]") && text.contains("radius = 5.0"));
            assert!(
                text.contains("alpha = 5.0, beta = 5.0, eta = 1000.0, zeta = 2.0, eps_vd = 40.0")
            );
            assert!(text.contains("mass = 0.1") && text.contains("max_accel = 500.0"));
            assert!(text.contains("length_unit = \"cm\""));
        }
    }

    #[test]
    fn case_1_goes_ahead_of_the_obstacle() {
        let o = run(MAX_SPEED, CASES[0].1);
        assert!(o.crossing_offset > 0.0, "{}", o.crossing_offset);
        assert!(o.min_clearance > 0.0);
    }

    #[test]
    fn case_2_moves_back_and_forth_then_takes_the_back_track() {
        let o = run(MAX_SPEED, CASES[1].1);
        assert!(o.crossing_offset < 0.0, "{}", o.crossing_offset);
        assert!(o.reversals >= 4, "{}", o.reversals);
        assert!(o.min_clearance > 0.0);
    }

    #[test]
    fn case_3_detours_slightly_to_the_back() {
        let o = run(MAX_SPEED, CASES[2].1);
        assert!(o.crossing_offset < 0.0, "{}", o.crossing_offset);
        assert_eq!(o.reversals, 0);
        assert!(o.min_clearance > 0.0);
    }

    #[test]
    fn outcomes_hold_across_the_reported_band_and_fail_outside_it() {
        let ok = |v: f64| {
            let (a, b, c) = (run(v, CASES[0].1), run(v, CASES[1].1), run(v, CASES[2].1));
            a.crossing_offset > 0.0
                && b.crossing_offset < 0.0
                && b.reversals >= 2
                && c.crossing_offset < 0.0
                && c.reversals == 0
                && [a.min_clearance, b.min_clearance, c.min_clearance]
                    .iter()
                    .all(|m| *m > 0.0)
        };
        for v in [21.1, 22.0, 22.4, 23.0, 23.7] {
            assert!(ok(v), "{v} should reproduce the paper");
        }
        for v in [20.0, 21.0, 23.8, 25.0] {
            assert!(!ok(v), "{v} should not");
        }
    }

    #[test]
    fn as_printed_the_robot_never_settles_at_the_goal() {
        for (_, v_o) in CASES {
            let o = run(MAX_SPEED, v_o);
            assert!(!o.goal_test_held);
            assert!(o.goal_distance.0 > 5.0, "{}", o.goal_distance.0);
            assert!(o.goal_distance.1 < 200.0, "{}", o.goal_distance.1);
        }
    }
}
