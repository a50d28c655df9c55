//! Designated-path following with variable-velocity moving-obstacle
//! avoidance: Yamada, Sa & Ohya, "Moving Obstacle Avoidance for Mobile Robot
//! Moving on Designated Path",
//! section 2 (global path following), section 3 (local path planning after
//! Tsubouchi et al. \[9\]) and eq (1).
//!
//! # Global path (section 2)
//! The subgoals are the designated path's vertices, plus, when
//! `subgoal_spacing` > 0, points every `subgoal_spacing` along each segment;
//! the robot's goal is appended as the last subgoal when the path does not
//! already end there. The robot heads for the current subgoal and moves on
//! when it is within `subgoal_threshold` of it. Two rules of section 2:
//! - *Junction*: at a vertex where the path turns, the robot "moves straight
//!   till the end of the junction then only turns": a corner subgoal counts
//!   as reached only once the robot is within the threshold **and** has come
//!   level with the vertex along the incoming segment (projection >= 0), so
//!   it does not cut the corner.
//! - *Blocked subgoal* (fig 3): the sentence is garbled ("give up ... when the
//!   robot is close to subgoal than the threshold value"). We read it as:
//!   when a sensed body, inflated by the robot's radius, comes closer to the
//!   current subgoal than `subgoal_threshold`, the robot cannot reach it, so
//!   it gives that subgoal up and heads for the next one. The final subgoal
//!   (the goal) is never given up.
//!
//! The first subgoal is the one ending the stretch of path nearest the
//! robot (a robot starting on the path's first vertex heads for the second).
//!
//! Without a designated path (`obs.path` is `None`) there is no start in the
//! observation to draw a segment from, so the goal alone is the single
//! subgoal and no boundary applies (every via point is admissible).
//!
//! # Local path in (x, y, t) (section 3)
//! Every sensed body (robots and scripted obstacles alike, from every
//! direction: the paper's point is that the two scanners see behind and to
//! the sides) is predicted at constant velocity u, so in (x, y, t) it is an
//! oblique cylinder of radius R = r_obstacle + r_robot + `margin` whose axis
//! leans by u. `margin` is ours (the paper grazes the cylinder exactly; a
//! small clearance keeps a discretely controlled robot off it).
//!
//! 1. *Straight*: if the straight line to the subgoal at `nominal_speed`
//!    crosses no cylinder, that is the path (command: nominal speed towards
//!    the subgoal).
//! 2. *Via points*: otherwise, for the robot's current speed and for every
//!    speed v in `speeds`, the reachable cone |x - p| = v t has its apex at
//!    the robot p. The *avoiding line* of a cylinder is the generator parallel
//!    to its axis that touches its surface as seen from p; shearing x' = x -
//!    u t makes the cylinder upright, so the two avoiding lines are the two
//!    tangent points T of the circle (c, R) seen from p, carried along by the
//!    obstacle: x(t) = T + u t. Their closest (earliest, t > 0) intersection
//!    with the cone, |T - p + u t| = v t, i.e.
//!    (|u|^2 - v^2) t^2 + 2 (T - p).u t + |T - p|^2 = 0,
//!    is the via point. We generate both avoiding lines (left and right) of
//!    every cylinder the straight line at speed v crosses.
//!    Reading: the paper's aim is to avoid "by speeding up or slowing down";
//!    for a speed at which the straight line crosses no cylinder we keep the
//!    straight line itself as that speed's candidate (step 1 applied per
//!    speed), so a pure speed change competes with the detours.
//! 3. A candidate whose first leg (robot to via point) meets any other
//!    cylinder is dropped (it meets its own only at the tangent point).
//! 4. A via point out of the boundary (farther than `boundary` from the
//!    designated path) is dropped. The best remaining candidate minimises
//!    eq (1): E = k1 Dist + k2 Time + k3 |v - v_nominal| + k4 theta, with
//!    Dist = dist1 + dist2 (robot -> via -> subgoal), Time = Dist / v and
//!    theta the angle between the robot's heading (its velocity, or the
//!    subgoal direction when at rest) and the via point's direction (fig 5).
//!    Tsubouchi's method searches further from a via point whose second leg
//!    (via -> subgoal) is blocked; we stop at one via point but rank
//!    candidates with a clear second leg before those without.
//!    If every candidate is out of the boundary, the robot stays "within the
//!    path boundary as much as possible": the one least out of it is taken.
//!    If there is no candidate at all (the robot is inside an inflated body,
//!    or no speed reaches any avoiding line), the robot stops.
//! 5. This is repeated every tick (every `plan`).
//!
//! Ties in E (a head-on obstacle is exactly symmetric) go to the left
//! (counter-clockwise) detour, as the robot of fig 9b turns left.
//! Speeds above the robot's `max_speed` are not considered.
//! Walls are not considered (the paper has none; its corridor is the
//! boundary).
//!
//! Commands are velocities: the chosen speed towards the via point (or the
//! subgoal), capped on the last subgoal so that the robot stops on the goal.
//!
//! Parameters (defaults = the paper's values, section 3 and 4.2): `speeds`
//! (0.1..0.5 m/s), `nominal_speed` (0.2 m/s), `k1` (0.1), `k2` (0.001), `k3`
//! (0.08), `k4` (0.3); ours, as the paper gives no value: `subgoal_threshold`
//! (0.2 m), `subgoal_spacing` (0 = vertices only), `margin` (0.05 m). The
//! defaults are in metres and seconds.
//!
//! # What eq (1) with the paper's weights gives (fig 8 / fig 9)
//! With k2 = 0.001 the time term is small but favours the faster of two
//! otherwise equal paths, and k3 |v - v_nominal| is symmetric, so slowing
//! down wins only when speeding up is blocked or needs a larger turn. In
//! the unit tests (testkit, constants of scenarios/papers/yamada-*.toml):
//! from behind the robot speeds up (0.3 m/s) on the path and runs ahead;
//! from the front it accelerates (0.5 m/s) while turning left; from the side
//! with the obstacle starting 1 m right and 1 m ahead it slows to 0.1 m/s on
//! the path and lets it pass, as the paper reports. With the side obstacle
//! placed so that both centres would reach the crossing together (2/3 m
//! ahead), the same equations make the robot speed up to 0.5 m/s and pass in
//! front, swerving slightly left, instead: which of the two the paper's fig 8 shows cannot be read
//! from the text.
//!
//! Diagnostics: `speed` (chosen speed), `subgoal` (index of the current
//! subgoal), `avoiding` (1 when a via point or a speed change was chosen).

#[cfg(test)]
mod tests;

use crate::{
    Command, DesignatedPath, Diagnostic, Observation, ParamError, ParamReader, Params, Planner,
    Vec2,
};

/// Distance from `p` to the polyline through `points` (a single point: the
/// distance to it; no points: infinity). The world/report side uses it for
/// the `path_deviation` and `boundary_violations` metrics.
pub fn distance_to_path(points: &[Vec2], p: Vec2) -> f64 {
    match points {
        [] => f64::INFINITY,
        [only] => (p - only).norm(),
        _ => points
            .windows(2)
            .map(|w| (p - closest_on_segment(w[0], w[1], p)).norm())
            .fold(f64::INFINITY, f64::min),
    }
}

fn closest_on_segment(a: Vec2, b: Vec2, p: Vec2) -> Vec2 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 <= f64::EPSILON {
        return a;
    }
    a + ab * ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
}

/// One subgoal on the designated path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Subgoal {
    /// Where it is.
    pub point: Vec2,
    /// Unit direction of the path arriving here, when the path turns here
    /// (a junction): the robot must come level with it before turning.
    pub corner: Option<Vec2>,
}

/// The subgoals of a designated path (section 2, fig 2): its vertices, points
/// every `spacing` along it when `spacing` > 0, and `goal` last when the path
/// does not end within `threshold` of it.
pub fn subgoals(points: &[Vec2], spacing: f64, goal: Vec2, threshold: f64) -> Vec<Subgoal> {
    let mut out: Vec<Subgoal> = Vec::new();
    for (i, &v) in points.iter().enumerate() {
        if i > 0 {
            let a = points[i - 1];
            let len = (v - a).norm();
            if spacing > 0.0 && len > spacing {
                let n = (len / spacing).ceil() as usize;
                for k in 1..n {
                    out.push(Subgoal {
                        point: a + (v - a) * (k as f64 / n as f64),
                        corner: None,
                    });
                }
            }
        }
        // A vertex is a junction when the path turns there.
        let corner = if i > 0 && i + 1 < points.len() {
            let din = v - points[i - 1];
            let dout = points[i + 1] - v;
            let (ni, no) = (din.norm(), dout.norm());
            if ni > f64::EPSILON && no > f64::EPSILON && din.dot(&dout) / (ni * no) < 1.0 - 1e-6 {
                Some(din / ni)
            } else {
                None
            }
        } else {
            None
        };
        out.push(Subgoal { point: v, corner });
    }
    if out
        .last()
        .is_none_or(|s| (s.point - goal).norm() > threshold)
    {
        out.push(Subgoal {
            point: goal,
            corner: None,
        });
    }
    out
}

/// A sensed body as an oblique cylinder in (x, y, t).
#[derive(Debug, Clone, Copy)]
struct Cylinder {
    /// Centre at t = 0.
    c: Vec2,
    /// Velocity (the axis leans by it).
    u: Vec2,
    /// Radius: both radii plus the margin.
    r: f64,
    /// Tangent points seen from the robot, relative to it: [left, right];
    /// `None` when the robot is inside the cylinder.
    tangents: Option<[Vec2; 2]>,
}

impl Cylinder {
    fn new(p: Vec2, c: Vec2, u: Vec2, r: f64) -> Self {
        let d = c - p;
        let l2 = d.norm_squared();
        let tangents = if l2 > r * r {
            // Tangent length m and the half-angle alpha of the view cone:
            // cos alpha = m / L, sin alpha = R / L.
            let l = l2.sqrt();
            let m = (l2 - r * r).sqrt();
            let (ca, sa) = (m / l, r / l);
            let dh = d / l;
            let left = Vec2::new(dh.x * ca - dh.y * sa, dh.x * sa + dh.y * ca) * m;
            let right = Vec2::new(dh.x * ca + dh.y * sa, -dh.x * sa + dh.y * ca) * m;
            Some([left, right])
        } else {
            None
        };
        Self { c, u, r, tangents }
    }

    /// Does the robot, leaving `start` at time `t0` with velocity `vel` for
    /// `dur` seconds, enter the cylinder? Starting inside counts only when
    /// it moves deeper.
    fn blocks(&self, start: Vec2, t0: f64, vel: Vec2, dur: f64) -> bool {
        let r2 = self.r * self.r * (1.0 - 1e-9);
        let d0 = start - (self.c + self.u * t0);
        let dv = vel - self.u;
        if d0.norm_squared() < r2 {
            return d0.dot(&dv) < 0.0;
        }
        let dv2 = dv.norm_squared();
        let t = if dv2 > f64::EPSILON {
            (-d0.dot(&dv) / dv2).clamp(0.0, dur.max(0.0))
        } else {
            0.0
        };
        (d0 + dv * t).norm_squared() < r2
    }
}

/// The earliest t > 0 at which the avoiding line T + u t (with w = T - p)
/// meets the reachable cone |x - p| = v t of apex p: the smallest positive
/// root of (|u|^2 - v^2) t^2 + 2 w.u t + |w|^2 = 0.
pub fn cone_meets_avoiding_line(w: Vec2, u: Vec2, v: f64) -> Option<f64> {
    let a = u.norm_squared() - v * v;
    let b = 2.0 * w.dot(&u);
    let c = w.norm_squared();
    if a.abs() < 1e-12 {
        // Cone and line equally steep: one root, if the line comes closer.
        return (b < 0.0).then(|| -c / b).filter(|t| *t > 0.0);
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let (t1, t2) = ((-b - s) / (2.0 * a), (-b + s) / (2.0 * a));
    let (lo, hi) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
    if lo > 0.0 {
        Some(lo)
    } else if hi > 0.0 {
        Some(hi)
    } else {
        None
    }
}

/// One candidate local path: straight or through a via point, at a speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Speed along the whole path.
    pub speed: f64,
    /// Via point (the subgoal itself for a straight path).
    pub via: Vec2,
    /// Robot -> via -> subgoal length.
    pub dist: f64,
    /// Angle between the heading and the via point's direction, rad.
    pub theta: f64,
    /// How far the via point is out of the boundary (0 = inside).
    pub outside: f64,
    /// Whether the second leg (via -> subgoal) meets a cylinder.
    pub second_leg_blocked: bool,
    /// Signed turn: > 0 when the via point is left of the heading.
    pub turn: f64,
}

/// Weights of eq (1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weights {
    /// k1: per unit of distance.
    pub k1: f64,
    /// k2: per second of travel time.
    pub k2: f64,
    /// k3: per unit of speed away from the nominal.
    pub k3: f64,
    /// k4: per radian between heading and via direction.
    pub k4: f64,
}

impl Candidate {
    /// Eq (1): E = k1 Dist + k2 Time + k3 |v - v_nominal| + k4 theta.
    pub fn cost(&self, w: &Weights, nominal: f64) -> f64 {
        w.k1 * self.dist
            + w.k2 * (self.dist / self.speed)
            + w.k3 * (self.speed - nominal).abs()
            + w.k4 * self.theta
    }
}

/// Step 4: drop candidates out of the boundary (unless all are, then keep
/// the least out), prefer a clear second leg, and take the least E; ties go
/// left. `None` when there is no candidate.
pub fn choose(cands: &[Candidate], w: &Weights, nominal: f64) -> Option<Candidate> {
    let any_inside = cands.iter().any(|c| c.outside <= 0.0);
    let min_out = cands
        .iter()
        .map(|c| c.outside)
        .fold(f64::INFINITY, f64::min);
    let mut best: Option<(Candidate, f64)> = None;
    for c in cands {
        // Via point out of the boundary: removed (or, if all are, only the
        // least-out ones stay).
        if (any_inside && c.outside > 0.0) || (!any_inside && c.outside > min_out) {
            continue;
        }
        let e = c.cost(w, nominal);
        let better = match &best {
            None => true,
            Some((b, be)) => {
                if c.second_leg_blocked != b.second_leg_blocked {
                    !c.second_leg_blocked
                } else if (e - be).abs() <= 1e-9 * be.abs().max(1e-12) {
                    c.turn > b.turn
                } else {
                    e < *be
                }
            }
        };
        if better {
            best = Some((*c, e));
        }
    }
    best.map(|(c, _)| c)
}

/// Yamada, Sa & Ohya: designated path, subgoals, variable-velocity local
/// paths in (x, y, t), eq (1).
#[derive(Debug, Clone)]
pub struct DesignatedPathPlanner {
    /// Speeds tried besides the current one (paper: 0.1 to 0.5 m/s).
    pub speeds: Vec<f64>,
    /// Normal speed v_nominal (paper: 0.2 m/s).
    pub nominal_speed: f64,
    /// Weights of eq (1).
    pub weights: Weights,
    /// Distance at which a subgoal counts as reached.
    pub subgoal_threshold: f64,
    /// Extra subgoals every this distance along the path (0 = none).
    pub subgoal_spacing: f64,
    /// Clearance added to every cylinder's radius.
    pub margin: f64,
    subgoals: Vec<Subgoal>,
    built_for: Option<(Vec<Vec2>, Vec2)>,
    current: usize,
    last_speed: f64,
    avoiding: bool,
    cyl: Vec<Cylinder>,
    cands: Vec<Candidate>,
    trial_speeds: Vec<f64>,
}

impl DesignatedPathPlanner {
    /// A planner with the given parameters and no path seen yet.
    pub fn new(
        speeds: Vec<f64>,
        nominal_speed: f64,
        weights: Weights,
        subgoal_threshold: f64,
        subgoal_spacing: f64,
        margin: f64,
    ) -> Self {
        Self {
            speeds,
            nominal_speed,
            weights,
            subgoal_threshold,
            subgoal_spacing,
            margin,
            subgoals: Vec::new(),
            built_for: None,
            current: 0,
            last_speed: 0.0,
            avoiding: false,
            cyl: Vec::new(),
            cands: Vec::new(),
            trial_speeds: Vec::new(),
        }
    }

    /// Reads the parameters (see the module doc) from a robot's params.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new("designated-path", params);
        let speeds = r.numbers("speeds", &[0.1, 0.2, 0.3, 0.4, 0.5])?;
        if speeds.is_empty() || speeds.iter().any(|s| *s <= 0.0) {
            return Err(r.invalid("speeds", "must be a non-empty list of speeds > 0"));
        }
        let nominal_speed = r.positive("nominal_speed", 0.2)?;
        let weights = Weights {
            k1: r.non_negative("k1", 0.1)?,
            k2: r.non_negative("k2", 0.001)?,
            k3: r.non_negative("k3", 0.08)?,
            k4: r.non_negative("k4", 0.3)?,
        };
        let subgoal_threshold = r.positive("subgoal_threshold", 0.2)?;
        let subgoal_spacing = r.non_negative("subgoal_spacing", 0.0)?;
        let margin = r.non_negative("margin", 0.05)?;
        r.finish()?;
        Ok(Self::new(
            speeds,
            nominal_speed,
            weights,
            subgoal_threshold,
            subgoal_spacing,
            margin,
        ))
    }

    /// Index of the current subgoal.
    pub fn current_subgoal(&self) -> usize {
        self.current
    }

    /// The subgoals in use (empty before the first `plan`).
    pub fn subgoal_list(&self) -> &[Subgoal] {
        &self.subgoals
    }

    fn ensure_subgoals(&mut self, path: Option<&DesignatedPath>, goal: Vec2, p: Vec2) {
        let pts: &[Vec2] = path.map_or(&[], |p| p.points.as_slice());
        let same = self
            .built_for
            .as_ref()
            .is_some_and(|(p, g)| p.as_slice() == pts && *g == goal);
        if same {
            return;
        }
        self.subgoals = subgoals(pts, self.subgoal_spacing, goal, self.subgoal_threshold);
        self.built_for = Some((pts.to_vec(), goal));
        // Start on the stretch of path nearest the robot: the subgoal that
        // ends it is the first one still ahead.
        self.current = self
            .subgoals
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                (
                    i + 1,
                    (p - closest_on_segment(w[0].point, w[1].point, p)).norm(),
                )
            })
            .fold(
                (0, f64::INFINITY),
                |best, c| if c.1 < best.1 { c } else { best },
            )
            .0;
    }

    /// Section 2: move on from reached subgoals and from subgoals an
    /// obstacle sits on (fig 3); never past the last one.
    fn advance_subgoal(&mut self, obs: &Observation) {
        let p = obs.me.position;
        while self.current + 1 < self.subgoals.len() {
            let s = self.subgoals[self.current];
            let near = (p - s.point).norm() <= self.subgoal_threshold;
            // Junction: reached only once level with the vertex.
            let level = s.corner.is_none_or(|dir| (p - s.point).dot(&dir) >= 0.0);
            // Fig 3: an obstacle too close to the subgoal: give it up.
            let blocked = obs.others.iter().any(|o| {
                (o.position - s.point).norm() - (o.radius + obs.me.radius) < self.subgoal_threshold
            });
            if (near && level) || blocked {
                self.current += 1;
            } else {
                break;
            }
        }
    }
}

impl Planner for DesignatedPathPlanner {
    fn plan(&mut self, obs: &Observation) -> Command {
        self.ensure_subgoals(obs.path, obs.goal, obs.me.position);
        self.advance_subgoal(obs);
        let p = obs.me.position;
        let last = self.current + 1 == self.subgoals.len();
        let g = self.subgoals[self.current].point;
        let to_g = g - p;
        let dist_g = to_g.norm();
        self.avoiding = false;
        // At the goal: stop.
        if last && dist_g <= f64::EPSILON.max(1e-9) {
            self.last_speed = 0.0;
            return Command::Velocity(Vec2::zeros());
        }
        let dir_g = to_g / dist_g;
        let max_speed = obs.me.max_speed;
        let nominal = self.nominal_speed.min(max_speed);
        // On the last subgoal, never overshoot the goal within one tick.
        let cap = |v: f64| {
            if last && obs.dt > 0.0 {
                v.min(dist_g / obs.dt)
            } else {
                v
            }
        };

        // The cylinders of every sensed body, from every direction.
        self.cyl.clear();
        for o in obs.others {
            let r = o.radius + obs.me.radius + self.margin;
            self.cyl.push(Cylinder::new(p, o.position, o.velocity, r));
        }

        // Step 1 (straight): the straight line at the nominal speed crosses
        // no cylinder.
        let straight_clear = |cyl: &[Cylinder], v: f64| {
            let dur = dist_g / v;
            !cyl.iter().any(|c| c.blocks(p, 0.0, dir_g * v, dur))
        };
        if straight_clear(&self.cyl, nominal) {
            let v = cap(nominal);
            self.last_speed = v;
            return Command::Velocity(dir_g * v);
        }

        // Heading for theta (fig 5): the velocity, or the subgoal direction.
        let vel = obs.me.velocity;
        let heading = if vel.norm() > 1e-6 {
            vel / vel.norm()
        } else {
            dir_g
        };
        let angle = |d: Vec2| {
            let n = d.norm();
            if n <= f64::EPSILON {
                return (0.0, 0.0);
            }
            let c = (heading.dot(&d) / n).clamp(-1.0, 1.0);
            (c.acos(), heading.x * d.y - heading.y * d.x)
        };
        let outside_of = |x: Vec2| match obs.path {
            Some(path) if !path.points.is_empty() => {
                (distance_to_path(&path.points, x) - path.boundary).max(0.0)
            }
            _ => 0.0,
        };

        // Steps 2-3: the current speed, then every speed of `speeds`.
        self.trial_speeds.clear();
        let current = vel.norm();
        if current > 1e-3 {
            self.trial_speeds.push(current.min(max_speed));
        }
        self.trial_speeds
            .extend(self.speeds.iter().copied().filter(|s| *s <= max_speed));
        self.cands.clear();
        for &v in &self.trial_speeds {
            let mut straight = true;
            for (k, ck) in self.cyl.iter().enumerate() {
                if !ck.blocks(p, 0.0, dir_g * v, dist_g / v) {
                    continue;
                }
                straight = false;
                let Some(tangents) = ck.tangents else {
                    continue;
                };
                // The two avoiding lines of this cylinder: left, right.
                for w in tangents {
                    let Some(t1) = cone_meets_avoiding_line(w, ck.u, v) else {
                        continue;
                    };
                    let via = p + w + ck.u * t1;
                    let leg1 = via - p;
                    let d1 = leg1.norm();
                    if d1 <= f64::EPSILON {
                        continue;
                    }
                    let v1 = leg1 * (v / d1);
                    // First leg meeting another cylinder: dropped.
                    let leg1_blocked = self
                        .cyl
                        .iter()
                        .enumerate()
                        .any(|(j, cj)| j != k && cj.blocks(p, 0.0, v1, t1));
                    if leg1_blocked {
                        continue;
                    }
                    let leg2 = g - via;
                    let d2 = leg2.norm();
                    let second_leg_blocked = d2 > f64::EPSILON && {
                        let v2 = leg2 * (v / d2);
                        self.cyl.iter().any(|cj| cj.blocks(via, t1, v2, d2 / v))
                    };
                    let (theta, turn) = angle(leg1);
                    self.cands.push(Candidate {
                        speed: v,
                        via,
                        dist: d1 + d2,
                        theta,
                        outside: outside_of(via),
                        second_leg_blocked,
                        turn,
                    });
                }
            }
            // A speed at which the straight line is clear: a pure speed
            // change competes with the detours.
            if straight {
                let (theta, turn) = angle(to_g);
                self.cands.push(Candidate {
                    speed: v,
                    via: g,
                    dist: dist_g,
                    theta,
                    outside: 0.0,
                    second_leg_blocked: false,
                    turn,
                });
            }
        }

        // Step 4: the least E among the admissible candidates.
        match choose(&self.cands, &self.weights, nominal) {
            Some(c) => {
                self.avoiding = true;
                let d = c.via - p;
                let n = d.norm();
                let v = if c.via == g { cap(c.speed) } else { c.speed };
                self.last_speed = v;
                if n <= f64::EPSILON {
                    return Command::Velocity(Vec2::zeros());
                }
                Command::Velocity(d * (v / n))
            }
            // No candidate at all: stop.
            None => {
                self.last_speed = 0.0;
                Command::Velocity(Vec2::zeros())
            }
        }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        vec![
            Diagnostic {
                name: "speed".into(),
                value: self.last_speed,
            },
            Diagnostic {
                name: "subgoal".into(),
                value: self.current as f64,
            },
            Diagnostic {
                name: "avoiding".into(),
                value: if self.avoiding { 1.0 } else { 0.0 },
            },
        ]
    }
}
