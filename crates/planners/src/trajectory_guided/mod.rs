//! Trajectory-guided obstacle avoidance: Zhu & Loh, "Modeling and Control
//! Strategies for Dynamical Obstacle Avoidance by Mobile Robots", section
//! 3.1 (b) and the "Trajectory Guided Procedure" of section 3.3 (b), with
//! the motion policy of section 4 and the predictions of section 3.2
//! ([`crate::prediction`]).
//!
//! Every tick, over the horizon `t` (`horizon`, s) in steps of the control
//! period Δt (K = ceil(t / Δt) steps):
//!
//! - Step 1: form the candidate trajectories S_i, each a direction, a speed
//!   and an acceleration, and order them by priority (below).
//! - Step 2: for each candidate in that order, explore the robot's positions
//!   R(t0 + kΔt, S_i), k = 1..K. The robot starts from its current position
//!   and velocity and changes velocity toward the candidate's at its maximum
//!   acceleration (eq 2.26b, constant acceleration within each interval).
//! - Step 3: intersect the robot's point set I_R(t0 + kΔt, S_i) with every
//!   body's predicted one I_Oj(t0 + kΔt). We take I_R as the disc swept "as
//!   the robot moves to" R(t0 + kΔt): both motions are linear within the
//!   interval, so the closest approach in the interval is checked, not only
//!   the sample instants (a fast crossing cannot tunnel between samples).
//!   With the probabilistic prediction the occupancy at that closest approach
//!   is compared with `occupancy_threshold`. Walls are static point sets.
//! - Step 4: on an intersection, record k (the collision-free steps reached)
//!   and go on with the next candidate.
//! - Step 5: the first candidate free for all k is taken. If none is, the
//!   one that stays free longest (the first such in priority order).
//!
//! The command is the chosen candidate's velocity ([`Command::Velocity`]);
//! the world's actuator limits and velocity lag then produce the
//! acceleration of Step 5.
//!
//! Candidates and priorities (the paper names the inherited trajectory and
//! the one toward the goal or subgoal and leaves the rest open). Section 4's
//! policy is "travel as fast as possible" and "change the velocity smoothly
//! and as little as possible":
//!
//! 1. toward the goal at the fastest speed from which the robot can still
//!    stop at the goal, `min(max_speed, sqrt(2 max_accel d), d / Δt)`;
//! 2. the inherited trajectory: the velocity chosen at t0 - Δt when that was
//!    not the goal candidate (a detour or a stop);
//! 3. `n` directions evenly spread around the circle from the goal direction,
//!    each at `max_speed` and at half of it, and standing still, ordered by
//!    how close to the goal each leaves the robot at the end of the horizon
//!    (policy 1), ties broken by the smaller change of velocity (policy 2).
//!
//! `candidates` is the total count: n = ceil((candidates - 1) / 2)
//! directions are generated and only the `candidates` of highest priority
//! are kept (the ones that back away from the goal fall off).
//!
//! Reading chosen against "inherited first": tried first, an
//! inherited trajectory is always collision-free in an empty scene, so a
//! robot at rest (inherited velocity zero) would never start and a robot
//! that made a detour would never turn back to its goal. The goal candidate
//! therefore comes first; the inherited one comes right after it, so that
//! while the way to the goal is blocked the robot keeps the detour it chose
//! instead of switching between equally good ones (policy 2).
//!
//! Parameters: `horizon` (s, default 2.0; the paper gives none),
//! `candidates` (default 32, at least 5), and the prediction's
//! (`prediction`, `accel_sigma`, `occupancy_threshold`, `extended_fallback`,
//! `vote_tolerance`, see [`crate::prediction`]). Speed and acceleration
//! limits are the robot's own.
//!
//! Cost per tick: O(candidates x K x bodies) intersection tests, stopping at
//! the first free candidate.

#[cfg(test)]
mod tests;

use crate::prediction::{Motion, Prediction};
use crate::{
    Command, Diagnostic, Observation, ParamError, ParamReader, Params, Planner, Segment, Vec2,
};

/// Where a candidate comes from (its priority class).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// Toward the goal at the speed that can still stop there.
    Goal,
    /// The non-goal velocity chosen at the previous tick.
    Inherited,
    /// One of the evenly spread directions, at full or half speed.
    Direction,
    /// Standing still.
    Stop,
}

/// One candidate trajectory: the velocity the robot changes to at its
/// maximum acceleration and then holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Target velocity.
    pub velocity: Vec2,
    /// Priority class.
    pub origin: Origin,
}

/// The outcome of one tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// The candidate taken.
    pub candidate: Candidate,
    /// Its place in the priority order (0 = first).
    pub rank: usize,
    /// Collision-free steps it reaches (`steps` when entirely free).
    pub free_steps: usize,
    /// Steps in the horizon.
    pub steps: usize,
}

/// Zhu & Loh's trajectory-guided procedure (section 3.3 b).
#[derive(Debug, Clone)]
pub struct TrajectoryGuided {
    /// Planning horizon t, s.
    pub horizon: f64,
    /// Number of candidate trajectories.
    pub candidates: usize,
    /// How bodies are predicted.
    pub prediction: Prediction,
    /// Occupancy probability from which a point counts as occupied.
    pub occupancy_threshold: f64,
    inherited: Option<Vec2>,
    last: Option<Choice>,
    motions: Vec<Motion>,
    centers: Vec<Vec2>,
    path: Vec<Vec2>,
    order: Vec<(Candidate, i64, f64)>,
}

/// The robot's positions at t0, t0 + Δt, ..., t0 + KΔt when it changes its
/// velocity from `v0` toward `u` at acceleration `accel` (speed capped at
/// `vmax`), constant acceleration within each step (eq 2.26b).
#[allow(clippy::too_many_arguments)]
fn rollout(
    p0: Vec2,
    v0: Vec2,
    u: Vec2,
    accel: f64,
    vmax: f64,
    dt: f64,
    steps: usize,
    out: &mut Vec<Vec2>,
) {
    out.clear();
    out.push(p0);
    let (mut p, mut v) = (p0, v0);
    let dv_max = accel * dt;
    for _ in 0..steps {
        let dv = u - v;
        let n = dv.norm();
        let mut nv = if n > dv_max { v + dv * (dv_max / n) } else { u };
        let s = nv.norm();
        if s > vmax {
            nv *= vmax / s;
        }
        p += (v + nv) * (0.5 * dt);
        v = nv;
        out.push(p);
    }
}

/// Smallest distance between segments [a0, a1] and [b0, b1].
fn segment_distance(a0: Vec2, a1: Vec2, b0: Vec2, b1: Vec2) -> f64 {
    let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
    let (da, db) = (a1 - a0, b1 - b0);
    let denom = cross(da, db);
    if denom.abs() > f64::EPSILON {
        let s = cross(b0 - a0, db) / denom;
        let t = cross(b0 - a0, da) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            return 0.0;
        }
    }
    let on = |p: Vec2, a: Vec2, b: Vec2| (Segment { a, b }.closest_point(p) - p).norm();
    on(a0, b0, b1)
        .min(on(a1, b0, b1))
        .min(on(b0, a0, a1))
        .min(on(b1, a0, a1))
}

impl TrajectoryGuided {
    /// A planner with the given parameters and no inherited trajectory.
    pub fn new(
        horizon: f64,
        candidates: usize,
        prediction: Prediction,
        occupancy_threshold: f64,
    ) -> Self {
        Self {
            horizon,
            candidates: candidates.max(5),
            prediction,
            occupancy_threshold,
            inherited: None,
            last: None,
            motions: Vec::new(),
            centers: Vec::new(),
            path: Vec::new(),
            order: Vec::new(),
        }
    }

    /// Reads `horizon`, `candidates` and the prediction's parameters.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new("trajectory-guided", params);
        let horizon = r.positive("horizon", 2.0)?;
        let candidates = r.count("candidates", 32, 5)?;
        let (prediction, threshold) = Prediction::read(&mut r, params)?;
        r.finish()?;
        Ok(Self::new(horizon, candidates, prediction, threshold))
    }

    /// The outcome of the last `plan` call.
    pub fn last_choice(&self) -> Option<Choice> {
        self.last
    }

    /// Steps in the horizon for control period `dt`.
    fn steps(&self, dt: f64) -> usize {
        ((self.horizon / dt).ceil() as usize).clamp(1, 10_000)
    }

    /// Step 1: the candidates in priority order.
    pub fn candidates_in_order(&mut self, obs: &Observation) -> Vec<Candidate> {
        self.order_candidates(obs);
        self.order.iter().map(|(c, _, _)| *c).collect()
    }

    fn order_candidates(&mut self, obs: &Observation) {
        let me = &obs.me;
        let dt = obs.dt;
        let steps = self.steps(dt);
        let to_goal = obs.goal - me.position;
        let d = to_goal.norm();
        let goal_dir = if d > 1e-12 {
            to_goal / d
        } else if me.velocity.norm() > 1e-12 {
            me.velocity.normalize()
        } else {
            Vec2::new(1.0, 0.0)
        };
        let vmax = me.max_speed.max(0.0);
        self.order.clear();
        // 1. Toward the goal, as fast as still lets the robot stop there.
        let s_goal = vmax.min((2.0 * me.max_accel * d).sqrt()).min(d / dt);
        self.order.push((
            Candidate {
                velocity: goal_dir * s_goal,
                origin: Origin::Goal,
            },
            i64::MIN,
            0.0,
        ));
        // 2. The trajectory inherited from t0 - Δt.
        if let Some(u) = self.inherited {
            self.order.push((
                Candidate {
                    velocity: u,
                    origin: Origin::Inherited,
                },
                i64::MIN + 1,
                0.0,
            ));
        }
        // 3. Spread directions at full and half speed, and standing still,
        // by closeness to the goal at the horizon, then by velocity change.
        let n_dir = self.candidates.saturating_sub(1).div_ceil(2).max(1);
        let quantum = 1e-9 * (vmax * self.horizon).max(1e-9);
        let mut rest = Vec::with_capacity(2 * n_dir + 1);
        for i in 0..n_dir {
            let (sin, cos) = (i as f64 * std::f64::consts::TAU / n_dir as f64).sin_cos();
            let dir = Vec2::new(
                goal_dir.x * cos - goal_dir.y * sin,
                goal_dir.x * sin + goal_dir.y * cos,
            );
            for speed in [vmax, 0.5 * vmax] {
                rest.push(Candidate {
                    velocity: dir * speed,
                    origin: Origin::Direction,
                });
            }
        }
        rest.push(Candidate {
            velocity: Vec2::zeros(),
            origin: Origin::Stop,
        });
        for c in rest {
            rollout(
                me.position,
                me.velocity,
                c.velocity,
                me.max_accel,
                vmax,
                dt,
                steps,
                &mut self.path,
            );
            let end = self.path.last().copied().unwrap_or(me.position);
            let key = ((obs.goal - end).norm() / quantum).round() as i64;
            self.order.push((c, key, (c.velocity - me.velocity).norm()));
        }
        self.order[1..].sort_by(|a, b| a.1.cmp(&b.1).then(a.2.total_cmp(&b.2)));
        // Keep the `candidates` of highest priority.
        self.order.truncate(self.candidates);
    }

    /// Steps 2-4 for one candidate: how many steps it stays collision-free.
    fn free_steps(&mut self, obs: &Observation, c: &Candidate, steps: usize) -> usize {
        let me = &obs.me;
        let dt = obs.dt;
        rollout(
            me.position,
            me.velocity,
            c.velocity,
            me.max_accel,
            me.max_speed.max(0.0),
            dt,
            steps,
            &mut self.path,
        );
        let n = self.motions.len();
        let probabilistic = matches!(self.prediction, Prediction::Probabilistic { .. });
        for k in 1..=steps {
            let (r0, r1) = (self.path[k - 1], self.path[k]);
            // Step 3: the robot's swept disc against each predicted body.
            for j in 0..n {
                let (c0, c1) = (self.centers[(k - 1) * n + j], self.centers[k * n + j]);
                let m = &self.motions[j];
                let q0 = r0 - c0;
                let dq = (r1 - r0) - (c1 - c0);
                let dq2 = dq.norm_squared();
                let tau = if dq2 > 0.0 {
                    (-q0.dot(&dq) / dq2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let hit = if probabilistic {
                    let t = (k as f64 - 1.0 + tau) * dt;
                    m.at(t)
                        .occupied(r0 + (r1 - r0) * tau, me.radius, self.occupancy_threshold)
                } else {
                    (q0 + dq * tau).norm() <= m.radius + me.radius
                };
                // Step 4: collision at step k.
                if hit {
                    return k - 1;
                }
            }
            // Static walls.
            if obs
                .walls
                .iter()
                .any(|w| segment_distance(r0, r1, w.a, w.b) <= me.radius)
            {
                return k - 1;
            }
        }
        steps
    }
}

impl Planner for TrajectoryGuided {
    fn plan(&mut self, obs: &Observation) -> Command {
        if obs.dt.is_nan() || obs.dt <= 0.0 {
            return Command::Velocity(Vec2::zeros());
        }
        let dt = obs.dt;
        let steps = self.steps(dt);
        // Predictions (section 3.2) of every body at every step.
        self.prediction.observe(obs.time, obs.others);
        self.motions.clear();
        self.motions
            .extend(obs.others.iter().map(|b| self.prediction.motion(b)));
        let n = self.motions.len();
        self.centers.clear();
        for k in 0..=steps {
            let t = k as f64 * dt;
            for j in 0..n {
                let at = self.motions[j].at(t);
                self.centers.push(at.center);
            }
        }
        // Step 1.
        self.order_candidates(obs);
        let order = std::mem::take(&mut self.order);
        let mut best: Option<Choice> = None;
        // Steps 2-4, in priority order.
        for (rank, (c, _, _)) in order.iter().enumerate() {
            let free = self.free_steps(obs, c, steps);
            if best.is_none_or(|b| free > b.free_steps) {
                best = Some(Choice {
                    candidate: *c,
                    rank,
                    free_steps: free,
                    steps,
                });
            }
            // Step 5: the first entirely free candidate is taken.
            if free == steps {
                break;
            }
        }
        self.order = order;
        let Some(choice) = best else {
            return Command::Velocity(Vec2::zeros());
        };
        self.inherited = match choice.candidate.origin {
            Origin::Goal => None,
            _ => Some(choice.candidate.velocity),
        };
        self.last = Some(choice);
        Command::Velocity(choice.candidate.velocity)
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        let Some(c) = self.last else {
            return Vec::new();
        };
        vec![
            Diagnostic {
                name: "candidate_rank".into(),
                value: c.rank as f64,
            },
            Diagnostic {
                name: "free_steps".into(),
                value: c.free_steps as f64,
            },
        ]
    }
}
