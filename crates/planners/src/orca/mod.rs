//! Optimal reciprocal collision avoidance (ORCA): J. van den Berg, S. J. Guy,
//! M. Lin & D. Manocha, "Reciprocal n-Body Collision Avoidance", Robotics
//! Research (ISRR 2009), Springer STAR 70, 2011, pp. 3-19; written to behave
//! as the reference implementation RVO2 (`Agent.cc`: `computeNewVelocity`,
//! `linearProgram1/2/3`), whose case names the comments below use.
//!
//! Per tick, for the robot A with position p, velocity v (the observed
//! `obs.me.velocity`, as RVO2 uses the agent's own current velocity), radius
//! r and speed limit v_max:
//!
//! 1. **Static obstacles** (section 5.2 of the paper; RVO2's obstacle lines).
//!    RVO2's obstacles are polygons whose vertices know their neighbours
//!    (a vertex's convexity, and the "foreign" leg along the next edge);
//!    the scenario's walls are segments. The segments are joined where they
//!    share an endpoint (`WallChain::join`): a closed chain (a square drawn
//!    as four walls) is RVO2's polygon, counter-clockwise when the robot is
//!    outside it and clockwise (RVO2's "negative" obstacle, the boundary of
//!    an arena) when inside; an open chain p0..pk is the degenerate polygon
//!    p0..pk..p1, of which a lone segment is RVO2's two-vertex obstacle (two
//!    directed edges, both ends convex). Each directed edge is seen only
//!    from its right-hand side. The edges within `r + time_horizon_obst *
//!    v_max` of p, nearest first, each add one half-plane of admissible
//!    velocities: the velocity obstacle of the edge truncated at
//!    `time_horizon_obst`, with the full responsibility (obstacles do not
//!    move). A unicycle driven through its look-ahead point (observed as
//!    the point, with the radius enlarged by the look-ahead so as to cover
//!    its real disc at any heading) keeps the real disc, not the enlarged
//!    one, off the walls, with half the look-ahead to spare while it
//!    drives along one (`WallRadius`, after the paper's footprint
//!    argument; it lets the robot through doors the enlarged disc just
//!    fills). A rectangle or polygon so driven also keeps its centre's
//!    own motion from closing on a wall faster than the gap over its
//!    braking time (`centre_lines`): a turn moves the look-ahead point
//!    but not the centre, and the walls' lines alone let the centre back
//!    (or drive) into a wall while the turn swings the point away, the
//!    shape's corners grazing it (4.6 mm deep on the AGVs of
//!    `scenarios/shapes/agv-swap.toml`), and keeps its circumscribed disc
//!    a little off the walls (`SHAPE_WALL_SPARE`), where its corner may
//!    point at a jamb. Discs are planned as before.
//!    Other bodies see the enlarged disc. At a non-convex vertex
//!    RVO2 extends the edge's line past the vertex, as the neighbouring
//!    edge carries on from there; a map's outline has open chains (a
//!    polygon of no thickness, there and back), where the robot can see an
//!    edge but not its neighbour, and the vertex is then taken as the
//!    convex end it is from the robot's side (`ObstacleSet::push_lines`).
//! 2. **Other bodies** (section 4, eqs (5)-(6) of the paper). The
//!    `max_neighbors` nearest bodies whose centres are closer than
//!    `neighbor_dist` each give the half-plane ORCA_A|B = {v' : (v' - (v +
//!    c u)) . n >= 0}, where u is the smallest change of the relative
//!    velocity v - v_B that takes it out of the velocity obstacle
//!    VO^tau_A|B truncated at `time_horizon` and n is the outward normal at
//!    the point it reaches. c is the share of the avoidance A takes: 1/2
//!    for another robot ([`BodyKind::Robot`], which runs its own planner and
//!    is assumed to take the other half: the reciprocity of the paper); 1
//!    for a scripted obstacle ([`BodyKind::Obstacle`]), which does not avoid,
//!    so A takes all of it (the paper's section 5.1 suggestion for
//!    non-reciprocating agents; RVO2 itself always uses 1/2); 1/2 for a
//!    person ([`BodyKind::Person`]), whom the robot takes for an RVO2
//!    agent as CrowdNav's ORCA robot does (a person who ignores robots
//!    breaks that assumption, CrowdNav's invisible robot).
//!    When the discs already overlap, RVO2's "collision" case is used: the
//!    velocity obstacle is truncated at one control period `obs.dt` instead.
//! 3. **Linear program** (section 5.1). The new velocity is the point of the
//!    disc |v'| <= v_max inside every half-plane that is closest to the
//!    preferred velocity, found by the incremental randomised-style 2-D
//!    linear program (`linear_program2`, adding one constraint at a time and
//!    solving the 1-D program on its line, `linear_program1`). When the
//!    half-planes have no common point, the 3-D program (`linear_program3`)
//!    keeps the obstacle lines hard and finds the velocity that minimises the
//!    largest violation of the body lines ("the safest possible velocity").
//!    A unicycle driven through its look-ahead point may only pick a
//!    velocity the point can reach within the tick (a box in the robot's
//!    frame, kept hard like the walls: `reach.rs`, after Alonso-Mora et
//!    al.'s NH-ORCA), so that the room ORCA keeps from others is kept by
//!    the motion the robot can make; when the walls leave nothing within
//!    reach, the box is dropped.
//!
//! The preferred velocity points at the goal with length `pref_speed`, and is
//! the goal vector itself once the goal is nearer than `pref_speed` (RVO2's
//! Circle example normalises the goal vector when it is longer than 1 with
//! `pref_speed` = 1; we read "1" as `pref_speed`). With `perturb` > 0 a
//! vector of length uniform in [0, `perturb`) in a uniform direction is
//! added to it every tick, as RVO2's Blocks example does ("to avoid
//! deadlocks due to perfect symmetry", with 0.0001 and C's `rand()`); ours
//! is drawn from a hash of (`seed`, robot id, tick), so a run stays
//! reproducible and the planner pure. The command is a
//! [`Command::Velocity`]: RVO2 sets the velocity exactly, which the world
//! reproduces with `velocity_lag = 0` and a large `max_accel`.
//!
//! Neighbour search: RVO2 builds one k-d tree per step for all its agents and
//! queries it once per agent. Here each robot's agent plans alone, once per
//! tick, over the snapshot it receives: building any spatial index costs at
//! least as much as the single linear pass it would save (O(n log n) to build
//! against O(n) to scan), so the neighbours are found by one pass over
//! `obs.others` keeping those within `neighbor_dist` and a partial selection
//! (`select_nth_unstable_by`) of the `max_neighbors` nearest, O(n) on
//! average. The same goes for the few wall edges.
//!
//! Parameters (RVO2's names; defaults from RVO2's Circle example,
//! `setAgentDefaults(15, 10, 10, 10, 1.5, 2)`, radius and max speed being the
//! robot's own): `neighbor_dist` = 15, `max_neighbors` = 10, `time_horizon` =
//! 10, `time_horizon_obst` = 10, `pref_speed` = 1; `perturb` = 0 (off),
//! `seed` = 0, `radius_margin` = 0.
//!
//! ORCA's guarantee holds only while every program is feasible and every
//! pair sees each other: in a dense crowd (RVO2's Circle, with
//! `max_neighbors` = 10) the 3-D fallback lets discs overlap a little, in
//! RVO2 as here (RVO2's own Circle of 250: overlaps up to 0.91 of a 3.0
//! combined radius). `radius_margin` pads every disc when planning, the
//! safety buffer RVO2's users add; the e2e Circle of 32 uses it.
//!
//! ORCA is local: robots pressed against a wall with crossing goals can
//! come to rest touching, each preferred velocity inside the cone of its
//! constraints' outward normals, a jam that the preferred-velocity
//! perturbation cannot break (RVO2's Blocks example: 2 of 100 seeded runs,
//! in RVO2 as here; BENCHMARKS.md, "ORCA vs RVO2").

mod linear_program;
mod obstacles;
mod reach;
#[cfg(test)]
mod tests;

use crate::{
    BodyKind, Command, Diagnostic, Kinematics, Observation, ParamError, ParamReader, Params,
    Planner, Segment, Sensed, Vec2,
};
use linear_program::{Line, det, linear_program2, linear_program3, normalize_or};
use obstacles::{ObstacleSet, WallChain, WallRadius};

/// ORCA, as in RVO2.
#[derive(Debug, Clone)]
pub struct Orca {
    /// Largest centre distance at which another body is considered.
    pub neighbor_dist: f64,
    /// Most bodies considered, nearest first.
    pub max_neighbors: usize,
    /// Time horizon tau of the velocity obstacles of other bodies, s.
    pub time_horizon: f64,
    /// Time horizon of the velocity obstacles of static obstacles, s.
    pub time_horizon_obst: f64,
    /// Length of the preferred velocity (towards the goal).
    pub pref_speed: f64,
    /// Largest random perturbation added to the preferred velocity each
    /// tick (RVO2's Blocks example: 0.0001); 0 = none.
    pub perturb: f64,
    /// Seed of the perturbation.
    pub seed: u64,
    /// Padding added to every disc's radius when planning (the robot's
    /// own and each other robot's; walls are padded once): RVO2's users'
    /// safety buffer. 0 = RVO2 exactly.
    pub radius_margin: f64,
    // Scratch space, reused across ticks (no effect on the result).
    obstacles: ObstacleSet,
    chains: Vec<WallChain>,
    chains_of: Vec<Segment>,
    chain_points: Vec<Vec2>,
    lines: Vec<Line>,
    proj_lines: Vec<Line>,
    neighbors: Vec<(f64, usize)>,
    obstacle_neighbors: Vec<(f64, usize)>,
    /// The look-ahead l when driving a unicycle through its look-ahead
    /// point ([`Planner::drives_look_ahead`]); 0 otherwise.
    look_ahead: f64,
    last_lines: usize,
    last_infeasible: bool,
}

impl Default for Orca {
    fn default() -> Self {
        Self::new(15.0, 10, 10.0, 10.0, 1.0)
    }
}

impl Planner for Orca {
    fn plan(&mut self, obs: &Observation) -> Command {
        let me = &obs.me;
        let pref = self.preferred_velocity(obs);
        self.lines.clear();

        // 1. Static obstacles (section 5.2; RVO2's "create obstacle ORCA
        //    lines"), first, because they stay hard in the 3-D program.
        if self.chains_of.as_slice() != obs.walls {
            self.chains_of = obs.walls.to_vec();
            self.chains = WallChain::join(obs.walls);
        }
        self.obstacles.clear();
        self.obstacles
            .push_chains(&self.chains, me.position, &mut self.chain_points);
        let radius = me.radius + self.radius_margin;
        // Driven through the look-ahead point, the robot is seen as p with
        // the disc r + l that covers its real disc at any heading; against
        // a wall the real disc, centred l behind p, is the nearer bound
        // unless the robot heads away from the wall ([`WallRadius`]).
        let behind = match me.kinematics {
            Kinematics::Unicycle { .. } => self.look_ahead.clamp(0.0, me.radius),
            Kinematics::Holonomic | Kinematics::Ackermann { .. } => 0.0,
        };
        // A rectangle or polygon so driven keeps its circumscribed disc a
        // little off the walls ([`SHAPE_WALL_SPARE`]).
        let wall_radius = if !me.shape.is_disc() && behind > 0.0 {
            radius + SHAPE_WALL_SPARE * me.radius
        } else {
            radius
        };
        self.select_obstacle_neighbors(me.position, wall_radius, me.max_speed);
        let (sin, cos) = me.heading.sin_cos();
        let walls = WallRadius {
            radius: wall_radius,
            behind,
            heading: Vec2::new(cos, sin),
        };
        self.push_obstacle_lines(me.position, me.velocity, walls);
        // A rectangle or polygon driven through its look-ahead point: its
        // centre's own motion along the heading kept off the walls too
        // (`centre_lines`).
        if !me.shape.is_disc() && behind > 0.0 {
            let real = wall_radius - behind;
            self.lines.extend(centre_lines(
                obs.walls,
                me.position - walls.heading * behind,
                walls.heading,
                real,
                me.max_speed * self.time_horizon_obst,
                // The gap closed no faster than the robot can brake from
                // top speed (a tick at least).
                (me.max_speed / me.max_accel.max(1e-9)).max(obs.dt),
            ));
        }
        let num_wall_lines = self.lines.len();
        // Driven through the look-ahead point, only the velocities the
        // point can reach within the tick, hard like the walls (`reach`).
        if let Some(reach) = reach::reachable(me, self.look_ahead, obs.dt) {
            self.lines.extend(reach);
        }
        let mut num_obst_lines = self.lines.len();

        // 2. Other bodies, nearest first (section 4, eqs (5)-(6); RVO2's
        //    "create agent ORCA lines"), each taking its share of the
        //    avoidance: half for a reciprocating robot, all of it for a
        //    scripted obstacle.
        self.select_neighbors(obs);
        let inv_tau = 1.0 / self.time_horizon;
        let dt = if obs.dt > 0.0 { obs.dt } else { 1.0 };
        for &(_, k) in &self.neighbors {
            let other = &obs.others[k];
            let share = match other.kind {
                BodyKind::Robot | BodyKind::Person => 0.5,
                BodyKind::Obstacle => 1.0,
            };
            self.lines.push(body_line(
                me.position,
                me.velocity,
                // Both discs padded.
                radius + self.radius_margin,
                other,
                inv_tau,
                dt,
                share,
            ));
        }

        // 3. The velocity closest to the preferred one in every half-plane
        //    (section 5.1; RVO2's linearProgram2), else the one that least
        //    violates the body lines, obstacle lines (and the reach) kept
        //    hard (the 3-D program, RVO2's linearProgram3).
        let mut v = Vec2::zeros();
        let mut fail = linear_program2(&self.lines, me.max_speed, pref, false, &mut v);
        if fail < num_obst_lines && num_obst_lines > num_wall_lines {
            // The walls leave nothing within reach (the robot is carried
            // towards one faster than it can brake): plan as RVO2 does,
            // over the whole speed disc, and let the world clamp.
            self.lines.drain(num_wall_lines..num_obst_lines);
            num_obst_lines = num_wall_lines;
            fail = linear_program2(&self.lines, me.max_speed, pref, false, &mut v);
        }
        self.last_infeasible = fail < self.lines.len();
        if self.last_infeasible {
            linear_program3(
                &self.lines,
                num_obst_lines,
                fail,
                me.max_speed,
                &mut v,
                &mut self.proj_lines,
            );
        }
        self.last_lines = self.lines.len();
        Command::Velocity(v)
    }

    fn drives_look_ahead(&mut self, lookahead: f64) {
        self.look_ahead = lookahead;
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut d = Vec::with_capacity(2);
        self.diagnostics_into(&mut d);
        d
    }

    fn diagnostics_into(&self, out: &mut Vec<Diagnostic>) {
        out.extend([
            Diagnostic {
                name: "orca_lines".into(),
                value: self.last_lines as f64,
            },
            Diagnostic {
                name: "orca_infeasible".into(),
                value: if self.last_infeasible { 1.0 } else { 0.0 },
            },
        ]);
    }
}

impl Orca {
    /// An ORCA planner with the given RVO2 parameters.
    pub fn new(
        neighbor_dist: f64,
        max_neighbors: usize,
        time_horizon: f64,
        time_horizon_obst: f64,
        pref_speed: f64,
    ) -> Self {
        Self {
            neighbor_dist,
            max_neighbors,
            time_horizon,
            time_horizon_obst,
            pref_speed,
            perturb: 0.0,
            seed: 0,
            radius_margin: 0.0,
            obstacles: ObstacleSet::default(),
            chains: Vec::new(),
            chains_of: Vec::new(),
            chain_points: Vec::new(),
            lines: Vec::new(),
            proj_lines: Vec::new(),
            neighbors: Vec::new(),
            obstacle_neighbors: Vec::new(),
            look_ahead: 0.0,
            last_lines: 0,
            last_infeasible: false,
        }
    }

    /// Reads `neighbor_dist`, `max_neighbors`, `time_horizon`,
    /// `time_horizon_obst`, `pref_speed`, `perturb`, `seed` and
    /// `radius_margin` from a robot's params.
    pub fn from_params(params: &Params) -> Result<Self, ParamError> {
        let mut r = ParamReader::new("orca", params);
        let neighbor_dist = r.non_negative("neighbor_dist", 15.0)?;
        let max_neighbors = r.count("max_neighbors", 10, 0)?;
        let time_horizon = r.positive("time_horizon", 10.0)?;
        let time_horizon_obst = r.positive("time_horizon_obst", 10.0)?;
        let pref_speed = r.non_negative("pref_speed", 1.0)?;
        let perturb = r.non_negative("perturb", 0.0)?;
        let seed = r.count("seed", 0, 0)? as u64;
        let radius_margin = r.non_negative("radius_margin", 0.0)?;
        r.finish()?;
        Ok(Self {
            perturb,
            seed,
            radius_margin,
            ..Self::new(
                neighbor_dist,
                max_neighbors,
                time_horizon,
                time_horizon_obst,
                pref_speed,
            )
        })
    }

    /// The preferred velocity: towards the goal, at most `pref_speed` long.
    fn preferred_velocity(&self, obs: &Observation) -> Vec2 {
        let g = obs.goal - obs.me.position;
        let d = g.norm();
        let pref = if d > self.pref_speed {
            g * (self.pref_speed / d)
        } else {
            g
        };
        if self.perturb <= 0.0 {
            return pref;
        }
        let mut h = self.seed ^ (u64::from(obs.me.id) << 40) ^ obs.tick;
        let mut unit = || {
            // SplitMix64.
            h = h.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = h;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let angle = unit() * std::f64::consts::TAU;
        let length = unit() * self.perturb;
        pref + Vec2::new(angle.cos(), angle.sin()) * length
    }

    /// The indices of the `max_neighbors` nearest bodies within
    /// `neighbor_dist`, nearest first (ties by id), into `self.neighbors`.
    fn select_neighbors(&mut self, obs: &Observation) {
        let range_sq = self.neighbor_dist * self.neighbor_dist;
        self.neighbors.clear();
        self.neighbors.extend(
            obs.others
                .iter()
                .enumerate()
                .map(|(i, o)| ((o.position - obs.me.position).norm_squared(), i))
                .filter(|(d, _)| *d < range_sq),
        );
        nearest_first(&mut self.neighbors, self.max_neighbors, |k| {
            obs.others[k].id
        });
    }

    /// The obstacle edges that can matter within `time_horizon_obst`, seen
    /// from their outer (right) side, nearest first, into
    /// `self.obstacle_neighbors` (RVO2's `computeNeighbors` for obstacles).
    fn select_obstacle_neighbors(&mut self, position: Vec2, radius: f64, max_speed: f64) {
        self.obstacles.select_neighbors(
            position,
            radius,
            max_speed,
            self.time_horizon_obst,
            &mut self.obstacle_neighbors,
        );
    }

    /// Appends the half-planes of the static obstacles (RVO2's obstacle
    /// ORCA lines) to `self.lines`.
    fn push_obstacle_lines(&mut self, position: Vec2, velocity: Vec2, walls: WallRadius) {
        self.obstacles.push_lines(
            &self.obstacle_neighbors,
            self.time_horizon_obst,
            position,
            velocity,
            walls,
            &mut self.lines,
        );
    }
}

/// The share of its circumscribed radius by which a rectangle or polygon
/// keeps that disc off the walls. ORCA keeps a disc off a wall down to a
/// gap of zero, and the disc bounds the shape, but where the shape's
/// corner points at the wall (a door's jamb, turning through) the corner
/// is on the disc, and the world counts a gap within a millimetre a
/// contact: with no spare, AGVs turning through doors of the office map
/// grazed the jambs 0.6-1.0 mm off. 2 % (11 mm on a 0.9 x 0.6 m AGV)
/// keeps them off; discs are planned as before.
const SHAPE_WALL_SPARE: f64 = 0.005;

/// The half-planes that keep the real disc (radius `r`, centred at `c`)
/// of a unicycle driven through its look-ahead point off the walls along
/// its own motion.
///
/// The look-ahead point p moves at u = v h + l omega n, the centre only at
/// v h: a turn moves p without moving the centre. The walls' lines keep p
/// off them ([`WallRadius`]) while the turn is held; but a velocity that
/// backs the centre towards a wall (or drives it there) while the turn
/// swings p away from it satisfies them, and the centre's disc enters the
/// wall (a rectangle's corners, on that disc, graze it as they swing
/// round). So the centre's own approach to each wall within `reach` is
/// bounded as ORCA bounds the approach to an obstacle, the gap d - r closed
/// at most at (d - r) / `tau` (none once touching): v (h . n) >= -(d - r) /
/// tau, n the unit normal from the wall's nearest point to the centre and
/// v = u . h. Whatever the turn does to the heading, the centre's distance
/// to the wall then shrinks no faster than that. The bounds on v all
/// contain v = 0, so they never leave the walls' program infeasible on
/// their own.
fn centre_lines(walls: &[Segment], c: Vec2, h: Vec2, r: f64, reach: f64, tau: f64) -> [Line; 2] {
    let (mut v_lo, mut v_hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for w in walls {
        let off = c - w.closest_point(c);
        let d = off.norm();
        if d > r + reach || d <= f64::EPSILON {
            continue;
        }
        let k = h.dot(&(off / d));
        let room = (d - r).max(0.0) / tau;
        if k > 1e-9 {
            v_lo = v_lo.max(-room / k);
        } else if k < -1e-9 {
            v_hi = v_hi.min(room / -k);
        }
    }
    let big = 1e6;
    let at_least = |e: Vec2, x: f64| Line {
        point: e * x,
        direction: Vec2::new(e.y, -e.x),
    };
    [at_least(h, v_lo.max(-big)), at_least(-h, -v_hi.min(big))]
}

/// `share` of the avoidance taken by this robot; `radius` is its own
/// radius plus any padding of both discs.
fn body_line(
    position: Vec2,
    velocity: Vec2,
    radius: f64,
    other: &Sensed,
    inv_tau: f64,
    dt: f64,
    share: f64,
) -> Line {
    let rel_pos = other.position - position;
    let rel_vel = velocity - other.velocity;
    let dist_sq = rel_pos.norm_squared();
    let combined = radius + other.radius;
    let combined_sq = combined * combined;
    let (direction, u);
    if dist_sq > combined_sq {
        // No collision. w: from the cut-off centre to the relative velocity.
        let w = rel_vel - rel_pos * inv_tau;
        let w_len_sq = w.norm_squared();
        let dot1 = w.dot(&rel_pos);
        if dot1 < 0.0 && dot1 * dot1 > combined_sq * w_len_sq {
            // Project on cut-off circle.
            let w_len = w_len_sq.sqrt();
            let unit_w = w / w_len;
            direction = Vec2::new(unit_w.y, -unit_w.x);
            u = unit_w * (combined * inv_tau - w_len);
        } else {
            // Project on legs.
            let leg = (dist_sq - combined_sq).sqrt();
            direction = if det(rel_pos, w) > 0.0 {
                // Project on left leg.
                Vec2::new(
                    rel_pos.x * leg - rel_pos.y * combined,
                    rel_pos.x * combined + rel_pos.y * leg,
                ) / dist_sq
            } else {
                // Project on right leg.
                -Vec2::new(
                    rel_pos.x * leg + rel_pos.y * combined,
                    -rel_pos.x * combined + rel_pos.y * leg,
                ) / dist_sq
            };
            u = direction * rel_vel.dot(&direction) - rel_vel;
        }
    } else {
        // Collision: project on the cut-off circle of one control
        // period, so the overlap is resolved by the next tick.
        let inv_dt = 1.0 / dt;
        let w = rel_vel - rel_pos * inv_dt;
        let w_len = w.norm();
        // Degenerate w = 0: push straight apart; coincident centres:
        // any fixed direction (both robots then pick opposite ones
        // because their relative positions are opposite, or equal and
        // symmetric when exactly coincident).
        let unit_w = if w_len > f64::EPSILON {
            w / w_len
        } else {
            normalize_or(-rel_pos, Vec2::new(1.0, 0.0))
        };
        direction = Vec2::new(unit_w.y, -unit_w.x);
        u = unit_w * (combined * inv_dt - w_len);
    }
    Line {
        point: velocity + u * share,
        direction,
    }
}

/// Keeps the `max` nearest of `candidates` (squared distance, index),
/// ties broken by the body id `id` gives an index, nearest first: RVO2's
/// `computeNeighbors` over a list, for the planner and the people alike.
fn nearest_first(candidates: &mut Vec<(f64, usize)>, max: usize, id: impl Fn(usize) -> u32) {
    let by_distance =
        |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(id(a.1).cmp(&id(b.1)));
    if candidates.len() > max {
        if max == 0 {
            candidates.clear();
        } else {
            candidates.select_nth_unstable_by(max - 1, by_distance);
            candidates.truncate(max);
        }
    }
    candidates.sort_unstable_by(by_distance);
}

/// A body a [`Walker`] keeps clear of: a disc, its velocity, and the share
/// of the avoidance the walker takes (1/2 for one who avoids in turn, 1
/// for one who does not).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbor {
    /// The body's id (breaks ties between equally near bodies).
    pub id: u32,
    /// Centre.
    pub position: Vec2,
    /// Velocity.
    pub velocity: Vec2,
    /// Disc radius.
    pub radius: f64,
    /// The walker's share of the avoidance.
    pub share: f64,
    /// This body's time horizon, if not the walker's `time_horizon`.
    pub time_horizon: Option<f64>,
}

/// RVO2's parameters of one walker (`addAgent`'s): the neighbour search,
/// the two time horizons, the padding of the discs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkerParams {
    /// Largest centre distance at which another body is considered.
    pub neighbor_dist: f64,
    /// Most bodies considered, nearest first.
    pub max_neighbors: usize,
    /// Time horizon of the other bodies' velocity obstacles, s.
    pub time_horizon: f64,
    /// Time horizon of the walls' velocity obstacles, s.
    pub time_horizon_obst: f64,
    /// Padding added to the walker's disc and each neighbour's (walls:
    /// once).
    pub radius_margin: f64,
}

/// ORCA for a holonomic disc that no agent drives: RVO2's
/// `computeNewVelocity` (steps 1 to 3 of the module's documentation, the
/// unicycle's reach aside) for a body the world moves, a person. The
/// half-planes, the neighbour selection and the linear programs are the
/// planner's own functions; only the scratch space is the walker's.
#[derive(Debug, Clone, Default)]
pub struct Walker {
    obstacles: ObstacleSet,
    chains: Vec<WallChain>,
    chain_points: Vec<Vec2>,
    lines: Vec<Line>,
    proj_lines: Vec<Line>,
    obstacle_neighbors: Vec<(f64, usize)>,
    neighbors: Vec<(f64, usize)>,
}

impl Walker {
    /// A walker among `walls` (joined into chains once, as the planner
    /// joins them).
    pub fn new(walls: &[Segment]) -> Self {
        Self {
            chains: WallChain::join(walls),
            ..Self::default()
        }
    }

    /// The new velocity of the disc at `position` with `velocity`,
    /// `radius` and speed limit `max_speed`, preferring `pref`, among
    /// `candidates` (the bodies it may see; those beyond `neighbor_dist`
    /// are dropped, the `max_neighbors` nearest kept) and the walls, over
    /// a step of `dt` (RVO2's time step: the collision case's horizon).
    #[allow(clippy::too_many_arguments)]
    pub fn velocity(
        &mut self,
        position: Vec2,
        velocity: Vec2,
        radius: f64,
        max_speed: f64,
        pref: Vec2,
        candidates: &[Neighbor],
        params: &WalkerParams,
        dt: f64,
    ) -> Vec2 {
        self.lines.clear();
        // 1. Static obstacles, first: they stay hard in the 3-D program.
        let radius = radius + params.radius_margin;
        self.obstacles.clear();
        if !self.chains.is_empty() {
            self.obstacles
                .push_chains(&self.chains, position, &mut self.chain_points);
            self.obstacles.select_neighbors(
                position,
                radius,
                max_speed,
                params.time_horizon_obst,
                &mut self.obstacle_neighbors,
            );
            let walls = WallRadius {
                radius,
                behind: 0.0,
                heading: Vec2::new(1.0, 0.0),
            };
            self.obstacles.push_lines(
                &self.obstacle_neighbors,
                params.time_horizon_obst,
                position,
                velocity,
                walls,
                &mut self.lines,
            );
        }
        let num_obst_lines = self.lines.len();
        // 2. Other bodies, nearest first, each with its share.
        let range_sq = params.neighbor_dist * params.neighbor_dist;
        self.neighbors.clear();
        self.neighbors.extend(
            candidates
                .iter()
                .enumerate()
                .map(|(i, o)| ((o.position - position).norm_squared(), i))
                .filter(|(d, _)| *d < range_sq),
        );
        nearest_first(&mut self.neighbors, params.max_neighbors, |k| {
            candidates[k].id
        });
        let inv_tau = 1.0 / params.time_horizon;
        let dt = if dt > 0.0 { dt } else { 1.0 };
        for &(_, k) in &self.neighbors {
            let o = &candidates[k];
            let other = Sensed::disc(o.id, BodyKind::Person, o.position, o.velocity, o.radius);
            self.lines.push(body_line(
                position,
                velocity,
                radius + params.radius_margin,
                &other,
                o.time_horizon.map_or(inv_tau, |t| 1.0 / t),
                dt,
                o.share,
            ));
        }
        // 3. The velocity closest to the preferred one, else the one
        //    that least violates the body lines.
        let mut v = Vec2::zeros();
        let fail = linear_program2(&self.lines, max_speed, pref, false, &mut v);
        if fail < self.lines.len() {
            linear_program3(
                &self.lines,
                num_obst_lines,
                fail,
                max_speed,
                &mut v,
                &mut self.proj_lines,
            );
        }
        v
    }
}
