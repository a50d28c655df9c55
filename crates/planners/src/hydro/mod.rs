//! Hydrodynamic potential: Sugiyama, Yamada & Yoshikawa, "Path Planning of a
//! Mobile Robot for Avoiding Moving Obstacles with Improved Velocity Control
//! by Using the Hydrodynamic Potential".
//!
//! The command is the guiding flow velocity `v = conj(dF/dz)` of a complex
//! potential `F` in `z = x + i y` (section II):
//!
//! - eq (1), a sink of strength `m` at the goal `z_g` and a cylinder of
//!   radius `a_j` at `z_j` by the circle theorem:
//!   `G_j(z) = -m log(z - z_g) - m log(z - z~_j) + m log(z - z_j)`.
//!   The image point is printed as `(z_g - z_j)(z~_j - conj z_j) = a_j^2`,
//!   which is garbled; the circle theorem needs the inverse point
//!   `z~_j = z_j + a_j^2 / conj(z_g - z_j)`, which we use.
//! - eq (2), a doublet for an obstacle moving with `u_j e^{i alpha_j}`:
//!   `D_j(z) = -a_j^2 u_j e^{i alpha_j} / (z - z_j)`, the exact flow of a
//!   cylinder translating in fluid at rest.
//! - eq (3), the speed correction
//!   `h(z) = (1 - e^{-(c_1 |z - z_st| + epsilon)}) |z - z_g| (1 - e^{-c_2 |z - z_g|})`.
//!   As printed the exponent reads `-c_1 |z - z_st| + epsilon`, which makes
//!   `h` negative at the start for any `epsilon > 0` (the robot would be
//!   sent away from its goal); the prose ("epsilon controls the velocity at
//!   the start point, epsilon > 0") needs `epsilon` inside the minus sign.
//!   The factor `|z - z_g|` cancels the sink's `1/|z - z_g|`, so far from
//!   everything the speed is `m (1 - e^{-c_1 s})`: `m` is the nominal speed,
//!   it ramps up from `m (1 - e^{-epsilon})` at the start and falls to zero
//!   like `m c_2 |z - z_g|` at the goal. `z_st` is where the robot was at
//!   its first `plan` call (the observation carries no start).
//! - eq (4), the binary anti-chasing correction: `b_j = 1` when
//!   `|angle(z - z_j) - alpha_j| <= pi/2` (the robot is ahead of the
//!   obstacle), else 0.
//! - eq (5), `conj v = h(z) G_j'(z) + b_j(z) D_j'(z)`.
//!
//! **Smooth correction, eqs (21)-(22).** As printed,
//! `b_j = (1 + cos 2 beta_j) / 2` with `beta_j = angle - (alpha_j + pi/2)`
//! for `pi/2 < |angle - alpha_j| < gamma`, and 0 beyond. It is 1 at
//! `pi/2` (continuous there) but at `gamma` it equals `(1 - cos 2 gamma)/2`,
//! which is 1/2 for the paper's `gamma = 3 pi / 4`: the printed form jumps
//! from 1/2 to 0 and is continuous only for `gamma = pi`. We therefore
//! stretch the cosine over the band, `b_j = (1 + cos(pi (|angle - alpha_j|
//! - pi/2) / (gamma - pi/2))) / 2`, which is eq (21) exactly when
//! `gamma = pi`, goes from 1 at `pi/2` to 0 at `gamma` with zero slope at
//! both ends, and is continuous for every `gamma` in `(pi/2, pi]`.
//!
//! **Ellipse field, section III.** Eqs (14)-(20) are not usable as
//! printed: eq (14) maps a point rather than defining a flow, and the
//! "rotation" matrices (15), (18) have determinant -1 (they are
//! reflections). We build instead the exact potential flow of an elliptic
//! cylinder translating along its major axis, through the Zhukovsky map of
//! eq (7) `w = zeta + c^2 / zeta` in the obstacle's frame
//! `w = e^{-i alpha_j} (z - z_j)` (a true rotation, done on complex numbers):
//! - the circle `|zeta| = R` maps to the ellipse of semi-axes
//!   `R + c^2/R` (along the motion) and `R - c^2/R`; we take `c = d u_j`
//!   (the paper's `(d u_j)^2`, `d` = `ellipse_time`) and choose `R` so that
//!   the minor semi-axis is the avoidance radius `a_j`:
//!   `R = (a_j + sqrt(a_j^2 + 4 c^2)) / 2`, major semi-axis
//!   `sqrt(a_j^2 + (2 d u_j)^2)`, foci at `+-2 d u_j`. The ellipse contains
//!   the avoidance circle and is never wider than it; it grows ahead of and
//!   behind the obstacle with its speed and is the circle at `u_j = 0`.
//! - moving part: `D_j = -u_j (R^2 - c^2) / zeta` (a uniform stream past
//!   the circle in the zeta-plane, seen from the lab frame); at `c = 0` this
//!   is eq (2).
//! - sink part: the circle theorem of eq (1) applied in the zeta-plane
//!   around `|zeta| = R` to the image `zeta_g` of the goal.
//! - derivatives by the chain rule, `dzeta/dw = zeta^2 / (zeta^2 - c^2)`,
//!   `dw/dz = e^{-i alpha_j}`; `zeta` is the root of the inverse map outside
//!   `|zeta| = c`.
//!
//! The flow has no normal component through the ellipse in the obstacle's
//! own frame (checked in the unit tests).
//!
//! **Standing versus moving.** There is no switch and no speed threshold:
//! every body is a cylinder (eq 1) whose doublet (eq 2) is proportional to
//! its speed `u_j`, and whose ellipse shrinks to the circle as `u_j -> 0`
//! (the paper: "the obstacle by a cylinder whether it moves or not"). A
//! standing body is one with zero velocity, and the field is continuous in
//! `u_j`, so a noisy differenced velocity cannot flip a mode.
//!
//! **Avoidance radius (section II).** `a_j = r_j + r_robot + u_j T`: the
//! obstacle's radius grown by the robot's (configuration space) and by the
//! distance the obstacle moves in the robot's time constant `T` (`delay`).
//! The paper says the *diameter* grows by that distance; we grow the
//! radius, the safer of the two.
//!
//! **Several obstacles and walls.** The paper defers both to its ref. 5,
//! which we do not have; it says the fields are superposed with weights,
//! the largest to the nearest obstacle, and that walls are avoided through
//! virtual obstacles that move with the robot along the boundary. We take
//! `conj v = sum_j w_j (h G_j' + b_j D_j') / sum_j w_j` with
//! `w_j = 1 / delta_j^2`, `delta_j` the robot's distance to the avoidance
//! circle of `j` (so next to one obstacle its own exact field dominates,
//! and far from all of them every term is the sink flow). Walls enter as
//! standing cylinders of radius half the segment's length plus the robot's
//! radius: a short wall (robot and goal both outside the circle around the
//! whole segment) is that circle, so the flow goes round it; a long wall
//! (a corridor's or the arena's side) is the paper's virtual obstacle that
//! moves with the robot, a cylinder tangent to the wall at its point
//! nearest to the robot and lying beyond it (it keeps the robot off the
//! wall but, facing the robot head-on, it has a stagnation point: a long
//! wall across the way to the goal is a dead end for this method); a wall
//! whose virtual cylinder would contain the goal is left out.
//!
//! **Cases outside the paper.** Inside an avoidance region the flow is not
//! defined (it is singular at the centre): the robot then leaves radially
//! at speed `m` plus the obstacle's velocity. If the goal lies inside a
//! body's avoidance region the circle theorem does not apply: that body
//! keeps its doublet but its cylinder is dropped (the field jumps when the
//! goal leaves the region; the paper's experiment avoids it by starting
//! the obstacle clear of the goal, as do our scenarios).
//!
//! The paper's experiment (figs 15-20) is in `scenarios/papers/hydro-*.toml`
//! with the measured peak speeds and velocity changes in their descriptions.
//!
//! Parameters: `strength` (the sink `m`, the nominal speed, default 0.5),
//! `c1`, `c2` (default 2.0 each), `epsilon` (default 0.1), `shape` =
//! `"circle"` | `"ellipse"` (default `"ellipse"`), `correction` =
//! `"binary"` | `"smooth"` (default `"smooth"`: the paper's final choice,
//! Fig. 14(d)), `gamma` (default `3 pi / 4`, the paper's value, in
//! `(pi/2, pi]`), `ellipse_time` (the `d` of `d u_j`, s, default 2.0),
//! `delay` (`T`, s, default 0: set it to the robot's `velocity_lag`).
//! The paper prints no value for any of them but `gamma`; the others are
//! ours, for a robot of about 0.5 m/s.

#[cfg(test)]
mod tests;

use crate::{Command, Observation, ParamError, ParamReader, Params, Planner, Vec2};
use nalgebra::Complex;
use std::f64::consts::{FRAC_PI_2, PI};

type C = Complex<f64>;

/// The avoidance region's shape for moving obstacles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// The previous method: a circle (eqs 1, 2).
    Circle,
    /// Section III: the circle mapped to an ellipse along the motion.
    Ellipse,
}

/// The anti-chasing correction `b_j`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Correction {
    /// Eq (4): 1 ahead of the obstacle, 0 behind.
    Binary,
    /// Eqs (21)-(22), continuous (see the module doc).
    Smooth,
}

/// One body as the flow sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowBody {
    /// Centre `z_j`.
    pub center: Vec2,
    /// Avoidance radius `a_j` (the ellipse's minor semi-axis).
    pub radius: f64,
    /// Velocity `u_j e^{i alpha_j}`.
    pub velocity: Vec2,
    /// Zhukovsky constant `c = d u_j` (0 for a circle).
    pub focal: f64,
}

/// Sugiyama, Yamada & Yoshikawa's hydrodynamic potential planner.
#[derive(Debug, Clone)]
pub struct Hydro {
    /// Sink strength `m` (nominal speed).
    pub strength: f64,
    /// `c_1` of eq (3): acceleration from the start.
    pub c1: f64,
    /// `c_2` of eq (3): deceleration at the goal.
    pub c2: f64,
    /// `epsilon` of eq (3): speed at the start.
    pub epsilon: f64,
    /// Circle or ellipse for moving obstacles.
    pub shape: Shape,
    /// Binary or smooth `b_j`.
    pub correction: Correction,
    /// Terminal angle `gamma` of the smooth `b_j`, in `(pi/2, pi]`.
    pub gamma: f64,
    /// `d` of `d u_j`, s.
    pub ellipse_time: f64,
    /// Robot time constant `T`, s.
    pub delay: f64,
    /// Start point `z_st`, set at the first `plan` call.
    pub start: Option<Vec2>,
}

impl Default for Hydro {
    fn default() -> Self {
        Self {
            strength: 0.5,
            c1: 2.0,
            c2: 2.0,
            epsilon: 0.1,
            shape: Shape::Ellipse,
            correction: Correction::Smooth,
            gamma: 3.0 * PI / 4.0,
            ellipse_time: 2.0,
            delay: 0.0,
            start: None,
        }
    }
}

fn cx(v: Vec2) -> C {
    C::new(v.x, v.y)
}

/// The root of `w = zeta + c^2 / zeta` outside `|zeta| = c`.
fn inverse_zhukovsky(w: C, c: f64) -> C {
    let s = (w * w - C::new(4.0 * c * c, 0.0)).sqrt();
    let a = (w + s) * 0.5;
    let b = (w - s) * 0.5;
    if a.norm_sqr() >= b.norm_sqr() { a } else { b }
}

/// What one body contributes at `z`.
enum BodyFlow {
    /// `(G_j', D_j')`: the conjugate velocities of the sink-and-cylinder
    /// potential and of the moving part.
    Outside(C, C),
    /// `z` is inside the avoidance region.
    Inside,
}

impl FlowBody {
    /// `R` of the zeta-plane circle whose image has minor semi-axis `a_j`.
    fn zeta_radius(&self) -> f64 {
        let a = self.radius;
        let c = self.focal;
        0.5 * (a + (a * a + 4.0 * c * c).sqrt())
    }

    fn flow(&self, m: f64, z: C, zg: C) -> BodyFlow {
        let zr = z - cx(self.center);
        let zgr = zg - cx(self.center);
        let u = cx(self.velocity);
        let speed = u.norm();
        if self.focal <= 0.0 || speed <= 0.0 {
            // Case circle (eqs 1, 2), standing or moving.
            let a2 = self.radius * self.radius;
            if zr.norm_sqr() <= a2 {
                return BodyFlow::Inside;
            }
            let zr_inv = zr.inv();
            let g = if zgr.norm_sqr() > a2 {
                // Sink, image sink at the inverse point, source at the centre.
                let image = a2 / zgr.conj();
                m * (-(zr - zgr).inv() - (zr - image).inv() + zr_inv)
            } else {
                // Goal inside the avoidance circle: sink alone.
                -m * (zr - zgr).inv()
            };
            // Doublet derivative: d/dz [-a^2 U / (z - z_j)] = a^2 U / (z - z_j)^2.
            let d = a2 * u * zr_inv * zr_inv;
            return BodyFlow::Outside(g, d);
        }
        // Case ellipse (section III, exact through the Zhukovsky map).
        let rot = u / speed; // e^{i alpha_j}
        let back = rot.conj(); // e^{-i alpha_j} = dw/dz
        let c = self.focal;
        let c2 = c * c;
        let big_r = self.zeta_radius();
        let r2 = big_r * big_r;
        let zeta = inverse_zhukovsky(back * zr, c);
        if zeta.norm_sqr() <= r2 {
            return BodyFlow::Inside;
        }
        let zeta2 = zeta * zeta;
        // dzeta/dw * dw/dz
        let chain = zeta2 / (zeta2 - c2) * back;
        let zeta_inv = zeta.inv();
        let zeta_g = inverse_zhukovsky(back * zgr, c);
        let g = if zeta_g.norm_sqr() > r2 {
            // Circle theorem in the zeta-plane.
            let image = r2 / zeta_g.conj();
            m * (-(zeta - zeta_g).inv() - (zeta - image).inv() + zeta_inv) * chain
        } else {
            -m * (zr - zgr).inv()
        };
        // D = -U (R^2 - c^2) / zeta, dD/dzeta = U (R^2 - c^2) / zeta^2.
        let d = speed * (r2 - c2) * zeta_inv * zeta_inv * chain;
        BodyFlow::Outside(g, d)
    }
}

impl Hydro {
    /// Reads the parameters listed in the module doc.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let d = Self::default();
        let mut r = ParamReader::new("hydro", params);
        let strength = r.positive("strength", d.strength)?;
        let c1 = r.positive("c1", d.c1)?;
        let c2 = r.positive("c2", d.c2)?;
        let epsilon = r.positive("epsilon", d.epsilon)?;
        let shape = match r.choice("shape", &["circle", "ellipse"], "ellipse")? {
            "circle" => Shape::Circle,
            _ => Shape::Ellipse,
        };
        let correction = match r.choice("correction", &["binary", "smooth"], "smooth")? {
            "binary" => Correction::Binary,
            _ => Correction::Smooth,
        };
        let gamma = r.number("gamma", d.gamma)?;
        if !(gamma > FRAC_PI_2 && gamma <= PI + 1e-12) {
            return Err(r.invalid("gamma", format!("must be in (pi/2, pi], got {gamma}")));
        }
        let ellipse_time = r.non_negative("ellipse_time", d.ellipse_time)?;
        let delay = r.non_negative("delay", d.delay)?;
        r.finish()?;
        Ok(Self {
            strength,
            c1,
            c2,
            epsilon,
            shape,
            correction,
            gamma,
            ellipse_time,
            delay,
            start: None,
        })
    }

    /// Eq (3), `h(z)`, for start `z_st` and goal `z_g`.
    pub fn speed_correction(&self, z: Vec2, start: Vec2, goal: Vec2) -> f64 {
        let s = (z - start).norm();
        let r = (z - goal).norm();
        (1.0 - (-(self.c1 * s + self.epsilon)).exp()) * r * (1.0 - (-self.c2 * r).exp())
    }

    /// The anti-chasing correction `b_j(z)`: eq (4), or eq (21) made
    /// continuous (module doc).
    pub fn correction_at(&self, z: Vec2, body: &FlowBody) -> f64 {
        let rel = cx(z - body.center);
        let u = cx(body.velocity);
        if u.norm_sqr() == 0.0 || rel.norm_sqr() == 0.0 {
            return 0.0;
        }
        // |angle(z - z_j) - alpha_j|, in [0, pi].
        let off = (rel * u.conj()).arg().abs();
        if off <= FRAC_PI_2 {
            // Ahead of the obstacle: full doublet.
            return 1.0;
        }
        match self.correction {
            // Eq (4): behind the obstacle, no doublet.
            Correction::Binary => 0.0,
            // Eq (21), band pi/2 < off < gamma: cosine ramp to 0.
            Correction::Smooth if off < self.gamma => {
                0.5 * (1.0 + (PI * (off - FRAC_PI_2) / (self.gamma - FRAC_PI_2)).cos())
            }
            // Eq (21), "for other": behind the band.
            Correction::Smooth => 0.0,
        }
    }

    /// The flow body for a sensed disc of radius `radius` at `center`
    /// moving with `velocity`, seen by a robot of radius `robot_radius`.
    pub fn body(&self, center: Vec2, velocity: Vec2, radius: f64, robot_radius: f64) -> FlowBody {
        let speed = velocity.norm();
        FlowBody {
            center,
            // Section II: grown by the distance moved in T.
            radius: radius + robot_radius + speed * self.delay,
            velocity,
            focal: match self.shape {
                Shape::Circle => 0.0,
                Shape::Ellipse => self.ellipse_time * speed,
            },
        }
    }

    /// The guiding velocity at `z` among `bodies` (robot-specific
    /// avoidance regions already built), start `start`, goal `goal`.
    pub fn velocity_at(&self, z: Vec2, start: Vec2, goal: Vec2, bodies: &[FlowBody]) -> Vec2 {
        let m = self.strength;
        let zc = cx(z);
        let zg = cx(goal);
        if (z - goal).norm_squared() == 0.0 {
            // At the goal: h = 0 and the sink is singular; the limit is 0.
            return Vec2::zeros();
        }
        let h = self.speed_correction(z, start, goal);
        let mut acc = C::new(0.0, 0.0);
        let mut total = 0.0;
        for body in bodies {
            match body.flow(m, zc, zg) {
                BodyFlow::Inside => {
                    // Outside the paper: leave the region radially.
                    let out = z - body.center;
                    let n = out.norm();
                    let dir = if n > 0.0 {
                        out / n
                    } else {
                        Vec2::new(1.0, 0.0)
                    };
                    return dir * m + body.velocity;
                }
                BodyFlow::Outside(g, d) => {
                    // Eq (5) for this body, weighted by its nearness.
                    let b = self.correction_at(z, body);
                    let delta = ((z - body.center).norm() - body.radius).max(1e-9);
                    let w = 1.0 / (delta * delta);
                    acc += (h * g + b * d) * w;
                    total += w;
                }
            }
        }
        let vbar = if total > 0.0 {
            acc / total
        } else {
            // No body: the corrected sink alone.
            -h * m * (zc - zg).inv()
        };
        Vec2::new(vbar.re, -vbar.im)
    }
}

impl Planner for Hydro {
    fn plan(&mut self, obs: &Observation) -> Command {
        let me = obs.me;
        let start = *self.start.get_or_insert(me.position);
        let mut bodies: Vec<FlowBody> = Vec::with_capacity(obs.others.len() + obs.walls.len());
        for o in obs.others {
            bodies.push(self.body(o.position, o.velocity, o.radius, me.radius));
        }
        for wall in obs.walls {
            let mid = (wall.a + wall.b) * 0.5;
            let rv = 0.5 * (wall.b - wall.a).norm();
            let a = rv + me.radius;
            if (me.position - mid).norm() > a && (obs.goal - mid).norm() > a {
                // Case short wall: a standing cylinder around the whole segment.
                bodies.push(FlowBody {
                    center: mid,
                    radius: a,
                    velocity: Vec2::zeros(),
                    focal: 0.0,
                });
                continue;
            }
            // Case long wall (robot or goal within its circumscribed circle):
            // a virtual standing cylinder beyond the wall, tangent at the
            // point nearest to the robot, moving with the robot.
            let q = wall.closest_point(me.position);
            let off = me.position - q;
            let dist = off.norm();
            if dist <= f64::EPSILON {
                continue;
            }
            let center = q - off * (rv / dist);
            if (obs.goal - center).norm() <= a {
                continue;
            }
            bodies.push(FlowBody {
                center,
                radius: a,
                velocity: Vec2::zeros(),
                focal: 0.0,
            });
        }
        Command::Velocity(self.velocity_at(me.position, start, obs.goal, &bodies))
    }
}

/// Constants of the paper's experiment (figs 15-20) as the scenario files
/// in `scenarios/papers/hydro-*.toml` set them, shared with the tests.
#[cfg(test)]
pub(crate) mod experiment {
    use crate::Vec2;
    pub const DT: f64 = 0.05;
    pub const SUBSTEPS: u32 = 10;
    pub const DURATION: f64 = 40.0;
    pub const ROBOT_START: [f64; 2] = [0.0, 0.0];
    pub const ROBOT_GOAL: [f64; 2] = [12.0, 0.0];
    pub const ROBOT_RADIUS: f64 = 0.2;
    pub const MASS: f64 = 1.0;
    pub const MAX_SPEED: f64 = 5.0;
    pub const MAX_ACCEL: f64 = 20.0;
    pub const VELOCITY_LAG: f64 = 0.1;
    pub const GOAL_TOLERANCE: f64 = 0.05;
    pub const OBSTACLE_START: [f64; 2] = [10.0, 0.3];
    pub const OBSTACLE_VELOCITY: [f64; 2] = [-0.5, 0.0];
    pub const OBSTACLE_RADIUS: f64 = 0.3;
    pub const STRENGTH: f64 = 0.5;
    pub const ELLIPSE_TIME: f64 = 2.0;

    pub fn v(p: [f64; 2]) -> Vec2 {
        Vec2::new(p[0], p[1])
    }
}
