//! What happened between the bodies, computed off the tick loop from every
//! tick's states: the robots' interaction metrics (proxemic times, time to
//! collision, time not moving, jerk, path irregularity, heading change)
//! and the encounters of encounters.csv.
//!
//! People (bodies of kind [`body_kind::PERSON`]) are counted apart: a
//! robot's proxemic times and time to collision are over the robots and
//! obstacles, its `person_` ones over the people, with the discomfort time
//! of CrowdNav ([`DISCOMFORT`]) and the smallest gap to a person.
//!
//! Every per-robot metric is taken over the ticks from the start to the
//! robot's arrival (the tick its `AT_GOAL` flag is first set), or to the
//! end of the run if it never arrives. Neighbours come from one
//! [`NeighbourGrid`] a tick, built for the larger of the social distance
//! and the encounter gap, so the cost grows with the bodies and their
//! neighbours, not with all pairs.

use mrsim_proto::{BodyState, body_kind, flags};
use mrsim_runfolder::metrics::Encounter;
use mrsim_scenario::Scenario;
use mrsim_spatial::NeighbourGrid;
use std::collections::HashMap;

/// Hall's intimate distance, between surfaces, m.
pub const INTIMATE: f64 = 0.45;
/// Hall's personal distance, between surfaces, m.
pub const PERSONAL: f64 = 1.2;
/// Hall's social distance, between surfaces, m.
pub const SOCIAL: f64 = 3.6;
/// A robot is not moving below this fraction of its `max_speed`.
pub const NOT_MOVING: f64 = 0.05;
/// A body gave way in an encounter if it lost at least this fraction of
/// its starting velocity along its starting course ([`Open::yielded`]).
pub const GAVE_WAY: f64 = 0.2;
/// Of two bodies that both gave way, one alone is named if it gave way
/// more than this many times as much as the other.
pub const GAVE_WAY_MORE: f64 = 1.5;
/// Below this speed a body is standing: its direction is undefined.
pub const STANDING: f64 = 1e-3;
/// CrowdNav's discomfort distance between a robot's and a person's
/// surfaces, m (`discomfort_dist` of `crowd_sim.py`, Chen et al. 2019):
/// nearer, the robot makes the person uncomfortable.
pub const DISCOMFORT: f64 = 0.2;

/// One robot's interaction metrics so far.
#[derive(Debug, Clone, Default)]
pub struct RobotInteraction {
    /// Seconds below [`NOT_MOVING`] of its top speed.
    pub time_not_moving: f64,
    /// Smallest time to collision (infinity: never finite).
    pub ttc_min: f64,
    /// Seconds with the smallest gap below [`INTIMATE`].
    pub time_intimate: f64,
    /// ... below [`PERSONAL`].
    pub time_personal: f64,
    /// ... below [`SOCIAL`].
    pub time_social: f64,
    /// The same four over the people alone: smallest time to collision
    /// with a person (infinity: never finite), ...
    pub person_ttc_min: f64,
    /// ... seconds with the smallest gap to a person below [`INTIMATE`],
    pub person_time_intimate: f64,
    /// ... below [`PERSONAL`],
    pub person_time_personal: f64,
    /// ... below [`SOCIAL`].
    pub person_time_social: f64,
    /// Seconds with the smallest gap to a person below [`DISCOMFORT`].
    pub discomfort_time: f64,
    /// Smallest surface gap to a person over the whole run, arrival or
    /// not (infinity before the first person).
    pub person_min_gap: f64,
    jerk_sum: f64,
    jerk_count: u64,
    irregularity_sum: f64,
    irregularity_count: u64,
    /// Sum of the changes of the direction of motion, rad.
    pub heading_change: f64,
    /// The previous tick's velocity and acceleration.
    prev_v: Option<[f64; 2]>,
    prev_a: Option<[f64; 2]>,
    /// Direction of motion at the last tick it moved.
    prev_heading: Option<f64>,
    /// Arrived: nothing more is counted.
    arrived: bool,
}

impl RobotInteraction {
    /// Mean jerk, m/s³ (0 before two accelerations).
    pub fn jerk_mean(&self) -> f64 {
        mean(self.jerk_sum, self.jerk_count)
    }

    /// Mean angle between the direction of motion and the goal, rad.
    pub fn path_irregularity(&self) -> f64 {
        mean(self.irregularity_sum, self.irregularity_count)
    }
}

fn mean(sum: f64, n: u64) -> f64 {
    if n > 0 { sum / n as f64 } else { 0.0 }
}

/// An encounter going on.
#[derive(Debug, Clone)]
struct Open {
    start_tick: u64,
    last_tick: u64,
    min_gap: f64,
    min_ttc: f64,
    kind: &'static str,
    /// What the second body is (`robot`, `obstacle`, `person`).
    b_kind: &'static str,
    /// Each body's velocity at the start.
    start_v: [[f64; 2]; 2],
    /// Each body's largest loss of velocity along its starting course, as
    /// a fraction of its starting speed: 1 - (v . v0) / |v0|², largest
    /// over the encounter (0 keeping course and speed, 1 stopped, 1 -
    /// cos(phi) turned by phi at the same speed); 0 for a body standing at
    /// the start.
    yielded: [f64; 2],
}

impl Open {
    fn gave_way(&self) -> &'static str {
        let [a, b] = self.yielded;
        match (a >= GAVE_WAY, b >= GAVE_WAY) {
            (false, false) => "none",
            (true, false) => "a",
            (false, true) => "b",
            (true, true) if a > GAVE_WAY_MORE * b => "a",
            (true, true) if b > GAVE_WAY_MORE * a => "b",
            (true, true) => "both",
        }
    }
}

/// The kind of an encounter from the bodies' velocities at its start:
/// the angle between them above 135 degrees head-on, 45 to 135 crossing,
/// below 45 overtaking; `standing` when either stands.
pub fn kind(va: [f64; 2], vb: [f64; 2]) -> &'static str {
    let (sa, sb) = (va[0].hypot(va[1]), vb[0].hypot(vb[1]));
    if sa < STANDING || sb < STANDING {
        return "standing";
    }
    let cos = ((va[0] * vb[0] + va[1] * vb[1]) / (sa * sb)).clamp(-1.0, 1.0);
    let deg = cos.acos().to_degrees();
    if deg > 135.0 {
        "head-on"
    } else if deg >= 45.0 {
        "crossing"
    } else {
        "overtaking"
    }
}

/// Time until two discs touch, both keeping their velocities: 0 if they
/// overlap, infinity if they never touch.
pub fn time_to_collision(a: &BodyState, b: &BodyState) -> f64 {
    time_to_reach(a, b, a.radius + b.radius)
}

/// When the centres of `a` and `b`, keeping their velocities, come within
/// `r` of each other: 0 if they are, infinite if they never do.
fn time_to_reach(a: &BodyState, b: &BodyState, r: f64) -> f64 {
    let d = [b.position[0] - a.position[0], b.position[1] - a.position[1]];
    let v = [b.velocity[0] - a.velocity[0], b.velocity[1] - a.velocity[1]];
    let c = d[0] * d[0] + d[1] * d[1] - r * r;
    if c <= 0.0 {
        return 0.0;
    }
    let vv = v[0] * v[0] + v[1] * v[1];
    let dv = d[0] * v[0] + d[1] * v[1];
    // |d + v t| = r: vv t² + 2 dv t + c = 0, the smaller root if real and
    // ahead (closing: dv < 0).
    if dv >= 0.0 || vv == 0.0 {
        return f64::INFINITY;
    }
    let disc = dv * dv - vv * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    (-dv - disc.sqrt()) / vv
}

/// Lowers the smallest gaps and times to collision (`near`) of the robots
/// among `i` and `j` (ids below `n`) to the pair's `g` and `t`.
fn lower(near: (&mut [f64], &mut [f64]), n: usize, (i, j): (usize, usize), (g, t): (f64, f64)) {
    for k in [i, j] {
        if k < n {
            near.0[k] = near.0[k].min(g);
            near.1[k] = near.1[k].min(t);
        }
    }
}

/// A body's pose for its shape.
fn pose(s: &BodyState) -> mrsim_shape::Pose {
    mrsim_shape::Pose::new(s.position, s.heading)
}

/// Surface gap between two discs (negative: overlap).
fn gap(a: &BodyState, b: &BodyState) -> f64 {
    let (dx, dy) = (a.position[0] - b.position[0], a.position[1] - b.position[1]);
    (dx * dx + dy * dy).sqrt() - a.radius - b.radius
}

/// The robots' interaction metrics and the encounters, fed every tick.
#[derive(Debug, Clone)]
pub struct Interaction {
    robots: Vec<RobotInteraction>,
    /// Each robot's goal and its not-moving speed.
    goals: Vec<([f64; 2], f64)>,
    encounter_gap: f64,
    prev_time: Option<f64>,
    grid: NeighbourGrid,
    near: Vec<u32>,
    /// Per robot, this tick's smallest gap and time to collision, to the
    /// robots and obstacles ...
    smallest: Vec<f64>,
    ttc: Vec<f64>,
    /// ... and to the people.
    person_smallest: Vec<f64>,
    person_ttc: Vec<f64>,
    /// The scene has people.
    people: bool,
    /// Every body's shape by id, empty when every body is a disc.
    shapes: Vec<mrsim_shape::Shape>,
    /// Every body's inscribed radius by id (with shapes only).
    inradii: Vec<f64>,
    /// This tick's placed shapes, by body id (with shapes only).
    placed: Vec<mrsim_shape::Placement>,
    /// This tick's pairs of shapes within reach: ids, their circumscribed
    /// discs' gap and time to collision.
    shaped_pairs: Vec<(u32, u32, f64, f64)>,
    /// Per robot, this tick's upper bounds of the smallest gap and time to
    /// collision, to the others and to people.
    bounds: Vec<[f64; 4]>,
    open: HashMap<(u32, u32), Open>,
    /// Encounters ended and not yet taken.
    closed: Vec<(u32, u32, Open)>,
}

impl Interaction {
    /// For the robots of `scenario` (the first bodies of every tick).
    pub fn new(scenario: &Scenario) -> Self {
        let shapes = if scenario.has_shapes() {
            scenario.body_shapes()
        } else {
            Vec::new()
        };
        Self {
            robots: vec![
                RobotInteraction {
                    ttc_min: f64::INFINITY,
                    person_ttc_min: f64::INFINITY,
                    person_min_gap: f64::INFINITY,
                    ..Default::default()
                };
                scenario.robots.len()
            ],
            goals: scenario
                .robots
                .iter()
                .map(|r| (r.goal, NOT_MOVING * r.max_speed))
                .collect(),
            encounter_gap: scenario.output.encounter_gap,
            prev_time: None,
            grid: NeighbourGrid::default(),
            near: Vec::new(),
            smallest: Vec::new(),
            ttc: Vec::new(),
            person_smallest: Vec::new(),
            person_ttc: Vec::new(),
            people: !scenario.people.is_empty(),
            inradii: shapes.iter().map(|b| b.inradius()).collect(),
            shapes,
            placed: Vec::new(),
            shaped_pairs: Vec::new(),
            bounds: Vec::new(),
            open: HashMap::new(),
            closed: Vec::new(),
        }
    }

    /// Every robot's metrics, in scenario order.
    pub fn robots(&self) -> &[RobotInteraction] {
        &self.robots
    }

    /// The scene has people: the `person_` metrics mean something.
    pub fn has_people(&self) -> bool {
        self.people
    }

    /// Takes in tick `tick` at simulated time `time`. The first tick only
    /// says where and how fast everything starts.
    pub fn track(&mut self, tick: u64, time: f64, states: &[BodyState]) {
        let n = self.robots.len().min(states.len());
        let dt = self.prev_time.map(|t| time - t);
        self.prev_time = Some(time);
        for (i, s) in states[..n].iter().enumerate() {
            let r = &mut self.robots[i];
            r.arrived |= s.flags & flags::AT_GOAL != 0;
            let v = s.velocity;
            let prev_v = r.prev_v.replace(v);
            let Some(dt) = dt.filter(|&dt| dt > 0.0) else {
                continue;
            };
            if r.arrived {
                continue;
            }
            let speed = v[0].hypot(v[1]);
            let (goal, slow) = self.goals[i];
            if speed < slow {
                r.time_not_moving += dt;
            }
            if let Some(pv) = prev_v {
                let a = [(v[0] - pv[0]) / dt, (v[1] - pv[1]) / dt];
                if let Some(pa) = r.prev_a {
                    r.jerk_sum += (a[0] - pa[0]).hypot(a[1] - pa[1]) / dt;
                    r.jerk_count += 1;
                }
                r.prev_a = Some(a);
            }
            if speed >= slow.max(STANDING) {
                let heading = v[1].atan2(v[0]);
                let to_goal = (goal[1] - s.position[1]).atan2(goal[0] - s.position[0]);
                r.irregularity_sum += wrap(heading - to_goal).abs();
                r.irregularity_count += 1;
                if let Some(h) = r.prev_heading {
                    r.heading_change += wrap(heading - h).abs();
                }
                r.prev_heading = Some(heading);
            }
        }
        self.neighbours(tick, dt.unwrap_or(0.0).max(0.0), states, n);
    }

    /// The proxemic times, time to collision and encounters of one tick.
    fn neighbours(&mut self, tick: u64, dt: f64, states: &[BodyState], n: usize) {
        let reach = SOCIAL.max(self.encounter_gap);
        let discs = states
            .iter()
            .map(|s| [s.position[0], s.position[1], s.radius]);
        let rmax = states.iter().map(|s| s.radius).fold(0.0, f64::max);
        let built = self.grid.build(discs, reach + rmax);
        let mut near = std::mem::take(&mut self.near);
        // Each pair once (i < j), its gap and time to collision counted for
        // both (they are symmetric): half the pairs of asking every robot.
        let (mut smallest, mut ttc) = (
            std::mem::take(&mut self.smallest),
            std::mem::take(&mut self.ttc),
        );
        let (mut person_smallest, mut person_ttc) = (
            std::mem::take(&mut self.person_smallest),
            std::mem::take(&mut self.person_ttc),
        );
        for v in [
            &mut smallest,
            &mut ttc,
            &mut person_smallest,
            &mut person_ttc,
        ] {
            v.clear();
            v.resize(n, f64::INFINITY);
        }
        // With shapes, every body placed once this tick.
        let mut placed = std::mem::take(&mut self.placed);
        placed.clear();
        if !self.shapes.is_empty() {
            placed.extend(
                states
                    .iter()
                    .zip(&self.shapes)
                    .map(|(s, b)| mrsim_shape::Placement::of(b, pose(s))),
            );
        }
        // The pairs of shapes (not both discs) within reach by their
        // circumscribed discs, measured in a second pass (below).
        let mut shaped_pairs = std::mem::take(&mut self.shaped_pairs);
        shaped_pairs.clear();
        // Per robot, upper bounds of this tick's smallest gap and time to
        // collision to robots and obstacles, and to people: a pair's
        // inscribed discs', where those are within reach (so that the pair
        // surely counts). A shape holds its inscribed disc, so the shapes'
        // gap and time are at most the discs'.
        let mut bounds = std::mem::take(&mut self.bounds);
        bounds.clear();
        bounds.resize(
            if self.shapes.is_empty() { 0 } else { n },
            [f64::INFINITY; 4],
        );
        for i in 0..n {
            let s = &states[i];
            let after = i as u32 + 1;
            if !built
                || !self
                    .grid
                    .near_from(s.position, reach + s.radius, after, &mut near)
            {
                // No grid (a position not finite): every body.
                near.clear();
                near.extend(after..states.len() as u32);
            }
            for &j in &near {
                let j = j as usize;
                let q = &states[j];
                let person = q.kind == body_kind::PERSON;
                // A robot's gap to a person counts among the people's,
                // not the others' (j > i: only j can be a person).
                let (near_gap, near_ttc) = if person {
                    (&mut person_smallest, &mut person_ttc)
                } else {
                    (&mut smallest, &mut ttc)
                };
                let shaped = match (self.shapes.get(i), self.shapes.get(j)) {
                    (Some(a), Some(b)) => !(a.is_disc() && b.is_disc()),
                    _ => false,
                };
                let g = gap(s, q);
                // Farther than the social distance, or not a number.
                if g.partial_cmp(&reach) != Some(std::cmp::Ordering::Less) {
                    continue;
                }
                let t = time_to_collision(s, q);
                if shaped {
                    shaped_pairs.push((i as u32, j as u32, g, t));
                    let inner = self.inradii[i] + self.inradii[j];
                    let outer = s.radius + q.radius;
                    let g_up = g + outer - inner;
                    if g_up < reach {
                        let t_up = time_to_reach(s, q, inner);
                        let at = if person { 2 } else { 0 };
                        for k in [i, j] {
                            if k < n {
                                bounds[k][at] = bounds[k][at].min(g_up);
                                bounds[k][at + 1] = bounds[k][at + 1].min(t_up);
                            }
                        }
                    }
                    continue;
                }
                lower((near_gap, near_ttc), n, (i, j), (g, t));
                if g < self.encounter_gap {
                    self.meet(tick, (i, j), states, g, t);
                }
            }
        }
        for &(i, j, g0, t0) in &shaped_pairs {
            let (i, j) = (i as usize, j as usize);
            let (s, q) = (&states[i], &states[j]);
            let person = q.kind == body_kind::PERSON;
            let (near_gap, near_ttc) = if person {
                (&mut person_smallest, &mut person_ttc)
            } else {
                (&mut smallest, &mut ttc)
            };
            let at = if person { 2 } else { 0 };
            // The circumscribed discs' gap and time are lower bounds of
            // the shapes': a pair whose bounds can lower no robot's
            // smallest gap or time (below this tick's so far, and below
            // the upper bounds) and that meets no encounter changes
            // nothing, and its shapes are not measured.
            let lowers =
                |k: usize, x: f64, of: &[f64], b: usize| k < n && x < of[k] && x < bounds[k][b];
            let meets = g0 < self.encounter_gap;
            let nearer = lowers(i, g0, near_gap, at) || lowers(j, g0, near_gap, at);
            let sooner = lowers(i, t0, near_ttc, at + 1) || lowers(j, t0, near_ttc, at + 1);
            if !(meets || nearer || sooner) {
                continue;
            }
            if meets && !(nearer || sooner) {
                // Surely within the encounter gap (the inscribed discs'
                // gap is at least the shapes'), and an encounter already
                // going on whose least gap and time the circumscribed
                // discs' cannot lower: it goes on, its least gap and time
                // as they are, and the shapes are not measured.
                let inner = self.inradii[i] + self.inradii[j];
                let surely = g0 + (s.radius + q.radius) - inner < self.encounter_gap;
                let lowered = self
                    .open
                    .get(&(s.id, q.id))
                    .is_none_or(|o| g0 < o.min_gap || t0 < o.min_ttc);
                if surely && !lowered {
                    self.meet(tick, (i, j), states, f64::INFINITY, f64::INFINITY);
                    continue;
                }
            }
            let g = mrsim_shape::placed_gap(&placed[i], &placed[j]);
            if g.partial_cmp(&reach) != Some(std::cmp::Ordering::Less) {
                continue;
            }
            // The circumscribed discs touch first: from there, the true
            // shapes' time.
            let t = if meets || sooner {
                let v = [q.velocity[0] - s.velocity[0], q.velocity[1] - s.velocity[1]];
                mrsim_shape::placed_time_to_contact(&placed[i], &placed[j], v, t0)
            } else {
                t0
            };
            lower((near_gap, near_ttc), n, (i, j), (g, t));
            if g < self.encounter_gap {
                self.meet(tick, (i, j), states, g, t);
            }
        }
        self.shaped_pairs = shaped_pairs;
        self.bounds = bounds;
        if self.people {
            // No person within reach: the nearest one is farther, and only
            // the smallest gap over the run wants it, while that is beyond
            // reach too.
            for (i, g) in person_smallest.iter_mut().enumerate() {
                if g.is_infinite() && dt > 0.0 && self.robots[i].person_min_gap >= reach {
                    *g = self.farthest_person(i, states, &placed);
                }
            }
        }
        for i in 0..n {
            let (smallest, ttc) = (smallest[i], ttc[i]);
            let (person_smallest, person_ttc) = (person_smallest[i], person_ttc[i]);
            let r = &mut self.robots[i];
            if dt > 0.0 {
                r.person_min_gap = r.person_min_gap.min(person_smallest);
            }
            if r.arrived || dt <= 0.0 {
                continue;
            }
            r.ttc_min = r.ttc_min.min(ttc);
            r.person_ttc_min = r.person_ttc_min.min(person_ttc);
            for (limit, gap, time) in [
                (INTIMATE, smallest, &mut r.time_intimate),
                (PERSONAL, smallest, &mut r.time_personal),
                (SOCIAL, smallest, &mut r.time_social),
                (INTIMATE, person_smallest, &mut r.person_time_intimate),
                (PERSONAL, person_smallest, &mut r.person_time_personal),
                (SOCIAL, person_smallest, &mut r.person_time_social),
                (DISCOMFORT, person_smallest, &mut r.discomfort_time),
            ] {
                if gap < limit {
                    *time += dt;
                }
            }
        }
        self.smallest = smallest;
        self.ttc = ttc;
        self.person_smallest = person_smallest;
        self.person_ttc = person_ttc;
        self.placed = placed;
        self.near = near;
        // Encounters not seen this tick have ended.
        let closed = &mut self.closed;
        self.open.retain(|&k, o| {
            if o.last_tick == tick {
                return true;
            }
            closed.push((k.0, k.1, o.clone()));
            false
        });
    }

    /// Robot `i`'s smallest gap to a person when none is within the
    /// neighbours' reach: every person's, by shape where the bodies have
    /// shapes (`placed`), else between discs.
    fn farthest_person(
        &self,
        i: usize,
        states: &[BodyState],
        placed: &[mrsim_shape::Placement],
    ) -> f64 {
        let s = &states[i];
        states
            .iter()
            .enumerate()
            .filter(|(_, q)| q.kind == body_kind::PERSON)
            .map(|(j, q)| match (placed.get(i), placed.get(j)) {
                (Some(a), Some(b)) => mrsim_shape::placed_gap(a, b),
                _ => gap(s, q),
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Bodies `i` < `j` are within the encounter gap at `tick`, with gap
    /// `g` and time to collision `t` (infinite: an encounter going on,
    /// its least gap and time not lowered).
    fn meet(&mut self, tick: u64, (i, j): (usize, usize), states: &[BodyState], g: f64, t: f64) {
        let (a, b) = (&states[i], &states[j]);
        let key = (a.id, b.id);
        let o = self.open.entry(key).or_insert_with(|| Open {
            start_tick: tick,
            last_tick: tick,
            min_gap: g,
            min_ttc: t,
            kind: kind(a.velocity, b.velocity),
            b_kind: body_kind::name(b.kind),
            start_v: [a.velocity, b.velocity],
            yielded: [0.0; 2],
        });
        o.last_tick = tick;
        o.min_gap = o.min_gap.min(g);
        o.min_ttc = o.min_ttc.min(t);
        for (k, v) in [a.velocity, b.velocity].into_iter().enumerate() {
            let v0 = o.start_v[k];
            let s2 = v0[0] * v0[0] + v0[1] * v0[1];
            if s2.sqrt() < STANDING {
                continue;
            }
            let lost = 1.0 - (v[0] * v0[0] + v[1] * v0[1]) / s2;
            o.yielded[k] = o.yielded[k].max(lost);
        }
    }

    /// Ends every encounter still going on (the run is over).
    pub fn close_all(&mut self) {
        self.closed
            .extend(self.open.drain().map(|(k, o)| (k.0, k.1, o)));
        self.closed.sort_by_key(|(a, b, o)| (o.start_tick, *a, *b));
    }

    /// Takes the encounters that have ended, named by `names` (body id ->
    /// name), in the order they started.
    pub fn take_closed(&mut self, names: &[String]) -> Vec<Encounter> {
        self.closed.sort_by_key(|(a, b, o)| (o.start_tick, *a, *b));
        let name = |id: u32| {
            names
                .get(id as usize)
                .cloned()
                .unwrap_or_else(|| format!("#{id}"))
        };
        self.closed
            .drain(..)
            .map(|(a, b, o)| Encounter {
                a: name(a),
                b: name(b),
                start_tick: o.start_tick,
                end_tick: o.last_tick,
                min_gap: o.min_gap,
                min_ttc: o.min_ttc.is_finite().then_some(o.min_ttc),
                kind: o.kind.to_string(),
                gave_way: o.gave_way().to_string(),
                b_kind: o.b_kind.to_string(),
            })
            .collect()
    }
}

/// `a` wrapped into (-pi, pi].
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a.rem_euclid(t);
    if w > std::f64::consts::PI { w - t } else { w }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.1;

    fn body(id: u32, p: [f64; 2], v: [f64; 2]) -> BodyState {
        BodyState {
            id,
            kind: body_kind::ROBOT,
            position: p,
            velocity: v,
            radius: 0.5,
            ..Default::default()
        }
    }

    /// Two robots, a (start [0, 0], goal [100, 0]) and b (far away unless
    /// moved), both with max_speed 1.
    fn scene() -> Scenario {
        let toml = r#"
            name = "t"
            [[robot]]
            name = "a"
            start = [0.0, 0.0]
            goal = [100.0, 0.0]
            max_speed = 1.0
            [[robot]]
            name = "b"
            start = [0.0, 50.0]
            goal = [0.0, 60.0]
            max_speed = 1.0
        "#;
        mrsim_scenario::parse(toml, "t.toml")
            .expect("scenario")
            .scenario
    }

    fn run(x: &mut Interaction, ticks: impl IntoIterator<Item = [BodyState; 2]>) {
        for (k, states) in ticks.into_iter().enumerate() {
            x.track(k as u64, k as f64 * DT, &states);
        }
    }

    #[test]
    fn a_robot_that_waits_two_seconds_was_not_moving_for_two_seconds() {
        let mut x = Interaction::new(&scene());
        let far = body(1, [0.0, 50.0], [0.0, 0.0]);
        // Ticks 0-20 standing (20 steps of 0.1 s), then 10 ticks at 1 m/s.
        let mut ticks = Vec::new();
        for k in 0..=20 {
            let _ = k;
            ticks.push([body(0, [0.0, 0.0], [0.0, 0.0]), far]);
        }
        for k in 1..=10 {
            ticks.push([body(0, [0.1 * k as f64, 0.0], [1.0, 0.0]), far]);
        }
        run(&mut x, ticks);
        let a = &x.robots()[0];
        assert!(
            (a.time_not_moving - 2.0).abs() < 1e-9,
            "{}",
            a.time_not_moving
        );
        // Straight at the goal, never turning.
        assert_eq!(a.path_irregularity(), 0.0);
        assert_eq!(a.heading_change, 0.0);
    }

    #[test]
    fn two_discs_head_on_collide_in_gap_over_closing_speed() {
        // Centres 5 m apart, radii 0.5: gap 4 m, closing at 1 + 1.5 m/s.
        let a = body(0, [0.0, 0.0], [1.0, 0.0]);
        let b = body(1, [5.0, 0.0], [-1.5, 0.0]);
        assert!((time_to_collision(&a, &b) - 4.0 / 2.5).abs() < 1e-12);
        // Moving apart or side by side: never.
        let c = body(1, [5.0, 0.0], [1.0, 0.0]);
        assert!(time_to_collision(&a, &c).is_infinite());
        // Overlapping: now.
        let d = body(1, [0.8, 0.0], [0.0, 0.0]);
        assert_eq!(time_to_collision(&a, &d), 0.0);
        // Over a run the smallest is the one nearest before contact: they
        // start 4.2 m apart (gap 3.2, within the social distance) and
        // close 0.25 m a tick.
        let mut x = Interaction::new(&scene());
        run(
            &mut x,
            (0..10).map(|k| {
                let s = 0.1 * k as f64;
                [
                    body(0, [s, 0.0], [1.0, 0.0]),
                    body(1, [4.2 - 1.5 * s, 0.0], [-1.5, 0.0]),
                ]
            }),
        );
        let last_gap = 4.2 - 2.5 * 0.9 - 1.0;
        let t = x.robots()[0].ttc_min;
        assert!((t - last_gap / 2.5).abs() < 1e-9, "{t}");
    }

    #[test]
    fn passing_another_at_a_known_gap_counts_the_proxemic_times() {
        // b stands at [10, 1.5]; a passes along y = 0 at 1 m/s: surface gap
        // sqrt((x - 10)² + 1.5²) - 1, below 1.2 m (personal) for |x - 10| <
        // sqrt(2.2² - 1.5²) and below 3.6 m (social) for |x - 10| <
        // sqrt(4.6² - 1.5²); never below 0.45 m (intimate).
        let mut x = Interaction::new(&scene());
        let b = body(1, [10.0, 1.5], [0.0, 0.0]);
        run(
            &mut x,
            (0..=200).map(|k| [body(0, [0.1 * k as f64, 0.0], [1.0, 0.0]), b]),
        );
        let a = &x.robots()[0];
        let half = |g: f64| ((g + 1.0f64).powi(2) - 1.5f64.powi(2)).sqrt();
        // Ticks at x = 0.1 k: the count of k within the band, times dt.
        let count = |g: f64| {
            (1..=200)
                .filter(|&k| (0.1 * k as f64 - 10.0).abs() < half(g))
                .count() as f64
                * DT
        };
        assert_eq!(a.time_intimate, 0.0);
        assert!((a.time_personal - count(PERSONAL)).abs() < 1e-9);
        assert!((a.time_social - count(SOCIAL)).abs() < 1e-9);
        // About 2 x 1.63 m and 2 x 4.35 m at 1 m/s.
        assert!((a.time_personal - 2.0 * half(PERSONAL)).abs() <= 0.1 + 1e-9);
        assert!((a.time_social - 2.0 * half(SOCIAL)).abs() <= 0.1 + 1e-9);
    }

    #[test]
    fn constant_acceleration_has_no_jerk_and_a_step_in_it_has_its_size() {
        let far = body(1, [0.0, 50.0], [0.0, 0.0]);
        let mut x = Interaction::new(&scene());
        // v = 0.5 t: a = 0.5 every tick, jerk 0.
        run(
            &mut x,
            (0..30).map(|k| [body(0, [0.0, 0.0], [0.05 * k as f64, 0.0]), far]),
        );
        assert!(x.robots()[0].jerk_mean().abs() < 1e-9);
        // a = 0.5 for ticks 1-10, then 0: one jump of 0.5 / dt = 5 m/s³
        // among 19 jerk samples (ticks 2-20).
        let mut x = Interaction::new(&scene());
        run(
            &mut x,
            (0..=20).map(|k| {
                let v = 0.05 * (k.min(10)) as f64;
                [body(0, [0.0, 0.0], [v, 0.0]), far]
            }),
        );
        let j = x.robots()[0].jerk_mean();
        assert!((j - 5.0 / 19.0).abs() < 1e-9, "{j}");
    }

    #[test]
    fn turning_away_from_the_goal_shows_in_irregularity_and_heading_change() {
        let far = body(1, [0.0, 50.0], [0.0, 0.0]);
        let mut x = Interaction::new(&scene());
        // Ticks 1-10 straight at the goal (+x), ticks 11-20 at 90 degrees.
        run(
            &mut x,
            (0..=20).map(|k| {
                let v = if k <= 10 { [1.0, 0.0] } else { [0.0, 1.0] };
                [body(0, [0.0, 0.0], v), far]
            }),
        );
        let a = &x.robots()[0];
        let quarter = std::f64::consts::FRAC_PI_2;
        assert!((a.path_irregularity() - quarter / 2.0).abs() < 1e-9);
        assert!((a.heading_change - quarter).abs() < 1e-9);
    }

    /// Encounters of `a` and `b` moving at constant velocities for `ticks`
    /// (b's velocity changed to `b_then` from tick `turn` on).
    fn encounters(
        a: ([f64; 2], [f64; 2]),
        b: ([f64; 2], [f64; 2]),
        b_then: Option<(u64, [f64; 2])>,
        ticks: u64,
    ) -> Vec<Encounter> {
        let mut x = Interaction::new(&scene());
        let (mut pa, mut pb) = (a.0, b.0);
        let mut vb = b.1;
        for k in 0..ticks {
            if let Some((turn, v)) = b_then
                && k >= turn
            {
                vb = v;
            }
            x.track(k, k as f64 * DT, &[body(0, pa, a.1), body(1, pb, vb)]);
            pa = [pa[0] + a.1[0] * DT, pa[1] + a.1[1] * DT];
            pb = [pb[0] + vb[0] * DT, pb[1] + vb[1] * DT];
        }
        x.close_all();
        x.take_closed(&["a".into(), "b".into()])
    }

    #[test]
    fn encounters_are_named_by_the_angle_between_the_velocities() {
        // Head-on along y = 0 and y = 0.4 (they would touch).
        let e = encounters(
            ([0.0, 0.0], [1.0, 0.0]),
            ([6.0, 0.4], [-1.0, 0.0]),
            None,
            60,
        );
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].kind, "head-on");
        assert_eq!((e[0].a.as_str(), e[0].b.as_str()), ("a", "b"));
        assert!(e[0].min_gap < 0.0 && e[0].min_ttc == Some(0.0));
        // Crossing at right angles: both reach [5, 0] at t = 5 s.
        let e = encounters(
            ([0.0, 0.0], [1.0, 0.0]),
            ([5.0, -5.0], [0.0, 1.0]),
            None,
            100,
        );
        assert_eq!(e[0].kind, "crossing");
        // Overtaking: b faster behind a, 1.5 m to its side (gap 0.5).
        let e = encounters(
            ([0.0, 0.0], [0.5, 0.0]),
            ([-3.0, 1.5], [1.5, 0.0]),
            None,
            80,
        );
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].kind, "overtaking");
        assert!((e[0].min_gap - 0.5).abs() < 1e-9);
        assert_eq!(e[0].min_ttc, None);
        assert_eq!(e[0].gave_way, "none");
        // A gap never below the encounter gap: no encounter.
        let e = encounters(
            ([0.0, 0.0], [1.0, 0.0]),
            ([6.0, 2.5], [-1.0, 0.0]),
            None,
            60,
        );
        assert!(e.is_empty());
    }

    #[test]
    fn the_robot_that_stops_gave_way() {
        // Head-on on lines 1.2 m apart: the gap falls below 1 m once the
        // centres are within 1.6 m along x (tick 18); b stops at tick 20
        // and a passes it, 0.2 m off, at its own speed.
        let e = encounters(
            ([0.0, 0.0], [1.0, 0.0]),
            ([5.0, 1.2], [-1.0, 0.0]),
            Some((20, [0.0, 0.0])),
            60,
        );
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].kind, "head-on");
        assert_eq!(e[0].gave_way, "b");
        assert!((e[0].min_gap - 0.2).abs() < 1e-9);
    }
}
