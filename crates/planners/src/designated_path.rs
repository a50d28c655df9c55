//! Designated-path following with variable-velocity moving-obstacle
//! avoidance: Yamada, Sa & Ohya, "Moving Obstacle Avoidance for Mobile Robot
//! Moving on Designated Path",
//! section 2 (global path following), section 3 (local path planning after
//! Tsubouchi et al. [9]) and eq (1).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::Sim;
    use crate::{BodyKind, SelfState, Sensed};

    // The fig 8 experiment, with the constants of
    // scenarios/papers/yamada-{behind,front,side}.toml.
    const DT: f64 = 0.1;
    const SUBSTEPS: u32 = 10;
    const ROBOT_RADIUS: f64 = 0.2;
    const OBSTACLE_RADIUS: f64 = 0.2;
    const MAX_SPEED: f64 = 0.5;
    const MAX_ACCEL: f64 = 0.5;
    const NOMINAL: f64 = 0.2;
    const BOUNDARY: f64 = 1.0;
    const GOAL: [f64; 2] = [5.0, 0.0];
    const DURATION: f64 = 40.0;
    // yamada-behind: 1 m behind, 0.5 m right, 0.3 m/s towards the point
    // x = 2.0806 of the path that the robot reaches at nominal speed at the
    // same time (t = 10.4 s).
    const BEHIND: ([f64; 2], [f64; 2]) = ([-1.0, -0.5], [0.296127, 0.048063]);
    // yamada-front: 2 m ahead, head-on at 0.3 m/s.
    const FRONT: ([f64; 2], [f64; 2]) = ([2.0, 0.0], [-0.3, 0.0]);
    // yamada-side: 1 m right, 1 m ahead, 0.3 m/s to the left.
    const SIDE: ([f64; 2], [f64; 2]) = ([1.0, -1.0], [0.0, 0.3]);

    fn v(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    fn planner() -> DesignatedPathPlanner {
        DesignatedPathPlanner::from_params(&Params::new()).unwrap()
    }

    fn body(id: u32, p: Vec2, u: Vec2, r: f64) -> Sensed {
        Sensed {
            id,
            kind: BodyKind::Obstacle,
            position: p,
            velocity: u,
            acceleration: Vec2::zeros(),
            radius: r,
        }
    }

    fn me(p: Vec2, vel: Vec2) -> SelfState {
        SelfState {
            id: 0,
            position: p,
            velocity: vel,
            radius: ROBOT_RADIUS,
            mass: 1.0,
            damping: 0.0,
            max_speed: MAX_SPEED,
            max_accel: MAX_ACCEL,
            heading: 0.0,
            angular_velocity: 0.0,
            kinematics: crate::Kinematics::Holonomic,
        }
    }

    fn obs<'a>(
        me: SelfState,
        goal: Vec2,
        others: &'a [Sensed],
        path: Option<&'a DesignatedPath>,
    ) -> Observation<'a> {
        Observation {
            tick: 0,
            time: 0.0,
            dt: DT,
            me,
            goal,
            goal_tolerance: 0.1,
            goal_hold_ticks: 3,
            others,
            walls: &[],
            path,
            scan: None,
        }
    }

    fn straight_path(boundary: f64) -> DesignatedPath {
        DesignatedPath {
            points: vec![Vec2::zeros(), v(GOAL[0], GOAL[1])],
            boundary,
        }
    }

    fn fig8(case: ([f64; 2], [f64; 2])) -> Sim {
        let mut sim = Sim::new(DT, SUBSTEPS);
        let i = sim.add_robot(
            Box::new(planner()),
            Vec2::zeros(),
            v(GOAL[0], GOAL[1]),
            ROBOT_RADIUS,
            1.0,
            0.0,
            MAX_SPEED,
            MAX_ACCEL,
        );
        sim.robots[i].path = Some(straight_path(BOUNDARY));
        sim.add_obstacle(
            v(case.0[0], case.0[1]),
            v(case.1[0], case.1[1]),
            OBSTACLE_RADIUS,
        );
        sim
    }

    /// Per tick: robot position, robot speed, obstacle position, clearance.
    struct Trace {
        pos: Vec<Vec2>,
        speed: Vec<f64>,
        obstacle: Vec<Vec2>,
        clearance: Vec<f64>,
    }

    fn run(mut sim: Sim, seconds: f64) -> Trace {
        let mut tr = Trace {
            pos: vec![],
            speed: vec![],
            obstacle: vec![],
            clearance: vec![],
        };
        for _ in 0..(seconds / DT).round() as u64 {
            sim.step();
            tr.pos.push(sim.robots[0].state.position);
            tr.speed.push(sim.robots[0].state.velocity.norm());
            tr.obstacle.push(sim.obstacles[0].position);
            tr.clearance.push(sim.clearance(0));
        }
        tr
    }

    /// No contact, never out of the corridor, the goal reached.
    fn assert_safe_and_arrives(tr: &Trace) {
        let min_clearance = tr.clearance.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(min_clearance > 0.0, "collision: clearance {min_clearance}");
        let path = straight_path(BOUNDARY);
        let worst = tr
            .pos
            .iter()
            .map(|p| distance_to_path(&path.points, *p))
            .fold(0.0, f64::max);
        assert!(worst <= BOUNDARY, "left the corridor by {worst}");
        let end = *tr.pos.last().unwrap();
        assert!((end - v(GOAL[0], GOAL[1])).norm() < 0.1, "ended at {end}");
    }

    #[test]
    fn tangent_points_of_a_circle_seen_from_the_robot() {
        // Circle at (2, 0) of radius 1 seen from the origin: tangent length
        // sqrt(3), half-angle 30 degrees.
        let c = Cylinder::new(Vec2::zeros(), v(2.0, 0.0), Vec2::zeros(), 1.0);
        let [left, right] = c.tangents.unwrap();
        let h = 3f64.sqrt() / 2.0;
        assert!((left - v(1.5, h)).norm() < 1e-12, "{left}");
        assert!((right - v(1.5, -h)).norm() < 1e-12, "{right}");
        // From inside there is no tangent.
        assert!(
            Cylinder::new(Vec2::zeros(), v(0.5, 0.0), Vec2::zeros(), 1.0)
                .tangents
                .is_none()
        );
    }

    #[test]
    fn cone_meets_the_avoiding_line_where_computed_by_hand() {
        // Avoiding line through (0, 1) moving at (0.3, 0); cone of 0.5 m/s:
        // 1 + 0.09 t^2 = 0.25 t^2  ->  t = 2.5 s, via point (0.75, 1).
        let t = cone_meets_avoiding_line(v(0.0, 1.0), v(0.3, 0.0), 0.5).unwrap();
        assert!((t - 2.5).abs() < 1e-12, "{t}");
        let via = v(0.0, 1.0) + v(0.3, 0.0) * t;
        assert!((via - v(0.75, 1.0)).norm() < 1e-12);
        assert!((via.norm() - 0.5 * t).abs() < 1e-12, "via is on the cone");
        // At 0.2 m/s the line runs away faster than the cone widens.
        assert!(cone_meets_avoiding_line(v(0.0, 1.0), v(0.3, 0.0), 0.2).is_none());
        // A still line is met at |w| / v.
        let t = cone_meets_avoiding_line(v(3.0, 4.0), Vec2::zeros(), 0.5).unwrap();
        assert!((t - 10.0).abs() < 1e-12);
    }

    #[test]
    fn eq_1_adds_the_four_weighted_terms() {
        let c = Candidate {
            speed: 0.5,
            via: v(1.0, 0.0),
            dist: 5.0,
            theta: 0.1,
            outside: 0.0,
            second_leg_blocked: false,
            turn: 0.0,
        };
        let w = planner().weights;
        // 0.1 * 5 + 0.001 * 10 + 0.08 * 0.3 + 0.3 * 0.1
        assert!((c.cost(&w, 0.2) - 0.564).abs() < 1e-12);
    }

    fn cand(speed: f64, dist: f64, theta: f64, outside: f64) -> Candidate {
        Candidate {
            speed,
            via: v(1.0, theta),
            dist,
            theta,
            outside,
            second_leg_blocked: false,
            turn: 0.0,
        }
    }

    #[test]
    fn eq_1_picks_the_lower_cost_candidate() {
        let w = planner().weights;
        let slow = cand(0.1, 5.0, 0.0, 0.0);
        let fast_turning = cand(0.5, 5.2, 0.4, 0.0);
        assert!(slow.cost(&w, 0.2) < fast_turning.cost(&w, 0.2));
        assert_eq!(choose(&[fast_turning, slow], &w, 0.2), Some(slow));
        let fast_straight = cand(0.3, 5.0, 0.0, 0.0);
        assert!(fast_straight.cost(&w, 0.2) < slow.cost(&w, 0.2));
        assert_eq!(
            choose(&[slow, fast_turning, fast_straight], &w, 0.2),
            Some(fast_straight)
        );
    }

    #[test]
    fn via_points_outside_the_boundary_are_dropped() {
        let w = planner().weights;
        let cheap_but_out = cand(0.2, 5.0, 0.0, 0.3);
        let dear_but_in = cand(0.1, 6.0, 0.5, 0.0);
        assert_eq!(
            choose(&[cheap_but_out, dear_but_in], &w, 0.2),
            Some(dear_but_in)
        );
        // All out: the least out stays.
        let less_out = cand(0.1, 6.0, 0.5, 0.1);
        assert_eq!(choose(&[cheap_but_out, less_out], &w, 0.2), Some(less_out));
    }

    #[test]
    fn head_on_obstacle_is_passed_left_unless_the_left_is_out_of_bounds() {
        let others = [body(1, v(2.0, 0.0), v(-0.3, 0.0), OBSTACLE_RADIUS)];
        let me = me(Vec2::zeros(), v(NOMINAL, 0.0));
        let wide = straight_path(BOUNDARY);
        let cmd = planner()
            .plan(&obs(me, v(5.0, 0.0), &others, Some(&wide)))
            .vector();
        assert!(cmd.y > 0.0, "turns left on a tie: {cmd}");
        // The same path shifted 0.5 m to the right with a 0.8 m boundary:
        // the left via point (y ~ +0.4) is 0.9 m from it, the right one in.
        let shifted = DesignatedPath {
            points: vec![v(0.0, -0.5), v(5.0, -0.5)],
            boundary: 0.8,
        };
        let mut p = planner();
        let cmd = p
            .plan(&obs(me, v(5.0, -0.5), &others, Some(&shifted)))
            .vector();
        assert!(cmd.y < 0.0, "the left detour is out of bounds: {cmd}");
        assert!(
            p.cands.iter().any(|c| c.outside > 0.0),
            "some via point was out"
        );
    }

    #[test]
    fn goes_straight_at_nominal_speed_when_nothing_crosses() {
        // An obstacle behind and moving away crosses nothing.
        let others = [body(1, v(-2.0, 0.5), v(-0.3, 0.0), OBSTACLE_RADIUS)];
        let path = straight_path(BOUNDARY);
        let mut p = planner();
        let cmd = p
            .plan(&obs(
                me(Vec2::zeros(), Vec2::zeros()),
                v(5.0, 0.0),
                &others,
                Some(&path),
            ))
            .vector();
        assert!((cmd - v(NOMINAL, 0.0)).norm() < 1e-12, "{cmd}");
        let d = p.diagnostics();
        assert_eq!(d[0].name, "speed");
        assert!((d[0].value - NOMINAL).abs() < 1e-12);
        assert_eq!(d[1].name, "subgoal");
    }

    fn corner_path() -> DesignatedPath {
        DesignatedPath {
            points: vec![v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0)],
            boundary: 1.0,
        }
    }

    #[test]
    fn a_subgoal_an_obstacle_sits_on_is_skipped() {
        let path = corner_path();
        let at = me(v(1.0, 0.0), v(NOMINAL, 0.0));
        // Free corner: the robot heads for it (subgoal 1).
        let mut p = planner();
        let cmd = p.plan(&obs(at, v(2.0, 2.0), &[], Some(&path))).vector();
        assert_eq!(p.current_subgoal(), 1);
        assert!(cmd.y.abs() < 1e-12 && cmd.x > 0.0, "{cmd}");
        // A standing body on the corner: given up, on to (2, 2).
        let others = [body(1, v(2.0, 0.1), Vec2::zeros(), OBSTACLE_RADIUS)];
        let mut p = planner();
        let cmd = p.plan(&obs(at, v(2.0, 2.0), &others, Some(&path))).vector();
        assert_eq!(p.current_subgoal(), 2);
        assert!(cmd.y > 0.0, "heads for the next subgoal: {cmd}");
    }

    #[test]
    fn at_a_junction_the_robot_goes_to_the_corner_before_turning() {
        let path = corner_path();
        let mut p = planner();
        // Within the threshold but short of the vertex: keep the corner.
        p.plan(&obs(
            me(v(1.9, 0.05), v(NOMINAL, 0.0)),
            v(2.0, 2.0),
            &[],
            Some(&path),
        ));
        assert_eq!(p.current_subgoal(), 1);
        // Level with it: turn.
        let cmd = p
            .plan(&obs(
                me(v(2.01, 0.0), v(NOMINAL, 0.0)),
                v(2.0, 2.0),
                &[],
                Some(&path),
            ))
            .vector();
        assert_eq!(p.current_subgoal(), 2);
        assert!(cmd.y > 0.0);
    }

    #[test]
    fn without_a_path_the_goal_is_the_only_subgoal() {
        let mut p = planner();
        let cmd = p
            .plan(&obs(
                me(Vec2::zeros(), Vec2::zeros()),
                v(0.0, 3.0),
                &[],
                None,
            ))
            .vector();
        assert_eq!(p.subgoal_list().len(), 1);
        assert!((cmd - v(0.0, NOMINAL)).norm() < 1e-12);
    }

    #[test]
    fn distance_to_path_is_to_the_nearest_segment() {
        let pts = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0)];
        assert!((distance_to_path(&pts, v(1.0, 0.5)) - 0.5).abs() < 1e-12);
        assert!((distance_to_path(&pts, v(3.0, 1.0)) - 1.0).abs() < 1e-12);
        assert!((distance_to_path(&pts, v(-3.0, 4.0)) - 5.0).abs() < 1e-12);
        assert!((distance_to_path(&pts[..1], v(3.0, 4.0)) - 5.0).abs() < 1e-12);
        assert_eq!(distance_to_path(&[], v(1.0, 1.0)), f64::INFINITY);
    }

    #[test]
    fn fig_8_from_behind_the_robot_speeds_up_and_runs_ahead() {
        let tr = run(fig8(BEHIND), DURATION);
        assert_safe_and_arrives(&tr);
        // Before the obstacle has come level with the robot.
        let before: Vec<usize> = (0..tr.pos.len())
            .filter(|&k| tr.obstacle[k].x < tr.pos[k].x - 0.5)
            .collect();
        let fastest = before.iter().map(|&k| tr.speed[k]).fold(0.0, f64::max);
        assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
        // Ahead of where nominal speed would have put it at t = 10 s.
        assert!(tr.pos[99].x > NOMINAL * 10.0 + 0.3, "{}", tr.pos[99]);
        // On the path, not around the obstacle.
        assert!(tr.pos.iter().all(|p| p.y.abs() < 0.05));
    }

    #[test]
    fn fig_8_from_the_front_the_robot_turns_left_to_pass() {
        let tr = run(fig8(FRONT), DURATION);
        assert_safe_and_arrives(&tr);
        let left = tr.pos.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        let right = tr.pos.iter().map(|p| p.y).fold(f64::MAX, f64::min);
        assert!(left > 0.2, "deviates left by {left}");
        assert!(right > -0.05, "never right: {right}");
        // Fig 9b: accelerated while turning.
        let fastest = tr.speed.iter().copied().fold(0.0, f64::max);
        assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
    }

    #[test]
    fn fig_8_from_the_side_the_robot_slows_down_and_lets_it_pass() {
        let tr = run(fig8(SIDE), DURATION);
        assert_safe_and_arrives(&tr);
        // While the obstacle has not yet crossed the path (after the first
        // second: from rest the robot reaches nominal speed in 0.4 s).
        let crossing: Vec<usize> = (0..tr.pos.len())
            .filter(|&k| tr.obstacle[k].y < 0.0)
            .collect();
        let slowest = crossing
            .iter()
            .filter(|&&k| k >= 9)
            .map(|&k| tr.speed[k])
            .fold(1.0, f64::min);
        assert!(slowest < NOMINAL - 0.05, "slowest {slowest}");
        // It lets the obstacle pass ahead: behind the crossing line when
        // the obstacle is on the path, and it does not swerve.
        let k = *crossing.last().unwrap();
        assert!(tr.pos[k].x < SIDE.0[0] - 0.4, "at {}", tr.pos[k]);
        assert!(tr.pos.iter().all(|p| p.y.abs() < 0.05));
        // Then resumes the nominal speed.
        assert!((tr.speed[150] - NOMINAL).abs() < 1e-6);
    }

    #[test]
    fn side_obstacle_arriving_together_is_passed_in_front_at_speed() {
        // Not a paper case: the side obstacle 2/3 m ahead, so that both
        // centres would reach the crossing at once at nominal speed.
        let tr = run(fig8(([2.0 / 3.0, -1.0], SIDE.1)), DURATION);
        assert_safe_and_arrives(&tr);
        let k = (0..tr.pos.len())
            .find(|&k| tr.obstacle[k].y >= 0.0)
            .unwrap();
        assert!(tr.pos[k].x > 2.0 / 3.0 + 0.4, "ahead of it: {}", tr.pos[k]);
        let fastest = tr.speed[..k].iter().copied().fold(0.0, f64::max);
        assert!(fastest > NOMINAL + 0.05, "top speed {fastest}");
    }

    #[test]
    fn corner_path_with_an_obstacle_crossing_the_corner() {
        // scenarios/papers/yamada-corners.toml: the path turns at (3, 0) and
        // (3, 3); a body crosses the first corner as the robot reaches it.
        let path = DesignatedPath {
            points: vec![v(0.0, 0.0), v(3.0, 0.0), v(3.0, 3.0), v(6.0, 3.0)],
            boundary: 0.8,
        };
        let mut sim = Sim::new(DT, SUBSTEPS);
        sim.add_robot(
            Box::new(planner()),
            Vec2::zeros(),
            v(6.0, 3.0),
            ROBOT_RADIUS,
            1.0,
            0.0,
            MAX_SPEED,
            MAX_ACCEL,
        );
        sim.robots[0].path = Some(path.clone());
        sim.add_obstacle(v(3.0, -3.0), v(0.0, 0.2), OBSTACLE_RADIUS);
        let mut worst = 0.0f64;
        let mut min_clearance = f64::INFINITY;
        let mut turned_at = None;
        for _ in 0..600 {
            sim.step();
            let p = sim.robots[0].state.position;
            worst = worst.max(distance_to_path(&path.points, p));
            min_clearance = min_clearance.min(sim.clearance(0));
            if turned_at.is_none() && p.y > 0.5 {
                turned_at = Some(p);
            }
        }
        // The body reaches the corner with the robot: the corner subgoal is
        // given up (fig 3), so the robot turns short of the vertex instead
        // of going level with it first.
        let turned_at = turned_at.unwrap();
        assert!(turned_at.x < 3.0, "turned at {turned_at}");
        assert!(min_clearance > 0.0, "collision: {min_clearance}");
        assert!(worst <= path.boundary, "out of the corridor by {worst}");
        let end = sim.robots[0].state.position;
        assert!((end - v(6.0, 3.0)).norm() < 0.1, "ended at {end}");
    }
}
