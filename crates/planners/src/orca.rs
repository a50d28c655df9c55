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
//!    share an endpoint ([`WallChain::join`]): a closed chain (a square drawn
//!    as four walls) is RVO2's polygon, counter-clockwise when the robot is
//!    outside it and clockwise (RVO2's "negative" obstacle, the boundary of
//!    an arena) when inside; an open chain p0..pk is the degenerate polygon
//!    p0..pk..p1, of which a lone segment is RVO2's two-vertex obstacle (two
//!    directed edges, both ends convex). Each directed edge is seen only
//!    from its right-hand side. The edges within `r + time_horizon_obst *
//!    v_max` of p, nearest first, each add one half-plane of admissible
//!    velocities: the velocity obstacle of the edge truncated at
//!    `time_horizon_obst`, with the full responsibility (obstacles do not
//!    move).
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
//!    non-reciprocating agents; RVO2 itself always uses 1/2).
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

use crate::{
    BodyKind, Command, Diagnostic, Observation, ParamError, ParamReader, Params, Planner, Segment,
    Sensed, Vec2,
};

/// RVO2's tolerance for parallel lines and covered obstacles.
const RVO_EPSILON: f64 = 1e-5;

/// 2-D cross product (RVO2's `det`).
fn det(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `v / |v|`, or `fallback` when `v` is (nearly) zero.
fn normalize_or(v: Vec2, fallback: Vec2) -> Vec2 {
    let n = v.norm();
    if n > f64::EPSILON { v / n } else { fallback }
}

/// Positive when `c` lies to the left of the directed line `a -> b`.
fn left_of(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    det(a - c, b - a)
}

/// A directed line; the admissible half-plane lies on its left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// A point on the line.
    pub point: Vec2,
    /// Unit direction; the admissible side is to its left.
    pub direction: Vec2,
}

impl Line {
    /// How far `v` lies on the forbidden (right) side; negative inside.
    fn violation(&self, v: Vec2) -> f64 {
        det(self.direction, self.point - v)
    }
}

/// One vertex of a static obstacle, RVO2-style: the edge from it to `next`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ObstacleVertex {
    point: Vec2,
    /// Unit direction of the edge to the next vertex.
    unit_dir: Vec2,
    convex: bool,
    next: usize,
    prev: usize,
}

/// Static obstacles as RVO2 stores them: closed chains of vertices.
#[derive(Debug, Clone, Default)]
pub struct ObstacleSet {
    vertices: Vec<ObstacleVertex>,
}

impl ObstacleSet {
    /// Forgets every obstacle.
    pub fn clear(&mut self) {
        self.vertices.clear();
    }

    /// Adds a polygon given counter-clockwise (the inside on the left of
    /// every edge), or a wall segment as two points. Fewer than two points,
    /// or a zero-length edge, adds nothing.
    pub fn push_polygon(&mut self, points: &[Vec2]) {
        let n = points.len();
        if n < 2 {
            return;
        }
        if (0..n).any(|i| (points[(i + 1) % n] - points[i]).norm() <= f64::EPSILON) {
            return;
        }
        let base = self.vertices.len();
        for i in 0..n {
            let prev = (i + n - 1) % n;
            let next = (i + 1) % n;
            let unit_dir = (points[next] - points[i]).normalize();
            // A segment's two ends are convex; a polygon vertex is convex
            // when the boundary turns left there.
            let convex = n == 2 || left_of(points[prev], points[i], points[next]) >= 0.0;
            self.vertices.push(ObstacleVertex {
                point: points[i],
                unit_dir,
                convex,
                next: base + next,
                prev: base + prev,
            });
        }
    }

    /// Adds wall chains as RVO2 obstacles seen from `position`: a closed
    /// chain is a polygon, counter-clockwise (an obstacle) when `position`
    /// is outside it and clockwise (RVO2's "negative" obstacle, a boundary)
    /// when inside; an open chain p0..pk is the degenerate polygon
    /// p0..pk..p1 that goes there and back, of which a lone segment is
    /// RVO2's two-vertex obstacle.
    pub fn push_chains(&mut self, chains: &[WallChain], position: Vec2) {
        let mut points = Vec::new();
        for c in chains {
            points.clear();
            points.extend_from_slice(&c.points);
            if c.closed {
                let ccw = signed_area(&points) > 0.0;
                if ccw == contains(&points, position) {
                    points.reverse();
                }
            } else if points.len() > 2 {
                let back: Vec<Vec2> = points[1..points.len() - 1].iter().rev().copied().collect();
                points.extend(back);
            }
            self.push_polygon(&points);
        }
    }

    /// Adds wall segments, joined into chains where they share endpoints
    /// (see [`WallChain::join`]), as seen from `position`.
    pub fn push_walls(&mut self, walls: &[Segment], position: Vec2) {
        self.push_chains(&WallChain::join(walls), position);
    }
}

/// Twice the signed area of a polygon (positive when counter-clockwise).
fn signed_area(points: &[Vec2]) -> f64 {
    let n = points.len();
    (0..n).map(|i| det(points[i], points[(i + 1) % n])).sum()
}

/// Is `p` inside the polygon (even-odd rule)?
fn contains(points: &[Vec2], p: Vec2) -> bool {
    let n = points.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// Wall segments joined end to end: the scenario's walls are segments, RVO2's
/// obstacles are polygons whose vertices know their neighbours (convexity,
/// the "foreign" legs along the next edge). Segments that share an endpoint
/// (within 1e-9 of the coordinates' scale) with exactly one other segment
/// are joined there; an endpoint shared by three or more ends a chain for
/// each of them.
#[derive(Debug, Clone, PartialEq)]
pub struct WallChain {
    /// The chain's points in order (a closed chain does not repeat its
    /// first point).
    pub points: Vec<Vec2>,
    /// Does the last point join the first?
    pub closed: bool,
}

impl WallChain {
    /// Joins `walls` into chains (zero-length segments are dropped).
    pub fn join(walls: &[Segment]) -> Vec<WallChain> {
        let segs: Vec<[Vec2; 2]> = walls
            .iter()
            .filter(|w| (w.b - w.a).norm() > f64::EPSILON)
            .map(|w| [w.a, w.b])
            .collect();
        let same = |p: Vec2, q: Vec2| (p - q).norm() <= 1e-9 * (1.0 + p.norm().max(q.norm()));
        // partner[2 s + e]: the only other segment end at end e of segment s.
        let ends = segs.len() * 2;
        let mut partner = vec![None; ends];
        for a in 0..ends {
            let pa = segs[a / 2][a % 2];
            let mut found = None;
            let mut count = 0;
            for b in 0..ends {
                if b != a && same(pa, segs[b / 2][b % 2]) {
                    count += 1;
                    found = Some(b);
                }
            }
            if count == 1 {
                partner[a] = found;
            }
        }
        let mut used = vec![false; segs.len()];
        let mut chains = Vec::new();
        for first in 0..segs.len() {
            if used[first] {
                continue;
            }
            // Walk backwards to the chain's start: `enter` is the end by
            // which the walk enters segment `s`.
            let (mut s, mut enter) = (first, 0);
            for _ in 0..segs.len() {
                match partner[2 * s + enter] {
                    Some(b) if b / 2 != first => (s, enter) = (b / 2, 1 - b % 2),
                    _ => break,
                }
            }
            let (start, mut points, mut closed) = (s, vec![segs[s][enter]], false);
            loop {
                used[s] = true;
                points.push(segs[s][1 - enter]);
                match partner[2 * s + 1 - enter] {
                    Some(b) if b / 2 == start => {
                        closed = true;
                        points.pop();
                        break;
                    }
                    Some(b) if !used[b / 2] => (s, enter) = (b / 2, b % 2),
                    _ => break,
                }
            }
            chains.push(WallChain { points, closed });
        }
        chains
    }
}

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
    lines: Vec<Line>,
    proj_lines: Vec<Line>,
    neighbors: Vec<(f64, usize)>,
    obstacle_neighbors: Vec<(f64, usize)>,
    last_lines: usize,
    last_infeasible: bool,
}

impl Default for Orca {
    fn default() -> Self {
        Self::new(15.0, 10, 10.0, 10.0, 1.0)
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
            lines: Vec::new(),
            proj_lines: Vec::new(),
            neighbors: Vec::new(),
            obstacle_neighbors: Vec::new(),
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
        let by_distance = |a: &(f64, usize), b: &(f64, usize)| {
            a.0.total_cmp(&b.0)
                .then(obs.others[a.1].id.cmp(&obs.others[b.1].id))
        };
        if self.neighbors.len() > self.max_neighbors {
            if self.max_neighbors == 0 {
                self.neighbors.clear();
            } else {
                self.neighbors
                    .select_nth_unstable_by(self.max_neighbors - 1, by_distance);
                self.neighbors.truncate(self.max_neighbors);
            }
        }
        self.neighbors.sort_unstable_by(by_distance);
    }

    /// The obstacle edges that can matter within `time_horizon_obst`, seen
    /// from their outer (right) side, nearest first, into
    /// `self.obstacle_neighbors` (RVO2's `computeNeighbors` for obstacles).
    fn select_obstacle_neighbors(&mut self, position: Vec2, radius: f64, max_speed: f64) {
        let range = self.time_horizon_obst * max_speed + radius;
        let range_sq = range * range;
        self.obstacle_neighbors.clear();
        for (i, o1) in self.obstacles.vertices.iter().enumerate() {
            let o2 = &self.obstacles.vertices[o1.next];
            // Only an edge the robot is on the right of (outside) can be seen.
            if left_of(o1.point, o2.point, position) >= 0.0 {
                continue;
            }
            let e = o2.point - o1.point;
            let s = ((position - o1.point).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            let dist_sq = (position - (o1.point + e * s)).norm_squared();
            if dist_sq < range_sq {
                self.obstacle_neighbors.push((dist_sq, i));
            }
        }
        self.obstacle_neighbors
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }

    /// Appends the half-planes of the static obstacles (RVO2's obstacle
    /// ORCA lines) to `self.lines`.
    fn push_obstacle_lines(&mut self, position: Vec2, velocity: Vec2, radius: f64) {
        let inv_tau = 1.0 / self.time_horizon_obst;
        let verts = &self.obstacles.vertices;
        for &(_, first) in &self.obstacle_neighbors {
            let mut i1 = first;
            let mut i2 = verts[i1].next;
            let rel1 = verts[i1].point - position;
            let rel2 = verts[i2].point - position;

            // Already covered: both ends' cut-off discs lie beyond a line
            // built for a nearer edge.
            let covered = self.lines.iter().any(|l| {
                det(rel1 * inv_tau - l.point, l.direction) - inv_tau * radius >= -RVO_EPSILON
                    && det(rel2 * inv_tau - l.point, l.direction) - inv_tau * radius >= -RVO_EPSILON
            });
            if covered {
                continue;
            }

            let dist_sq1 = rel1.norm_squared();
            let dist_sq2 = rel2.norm_squared();
            let radius_sq = radius * radius;
            let edge = verts[i2].point - verts[i1].point;
            let s = (-rel1).dot(&edge) / edge.norm_squared();
            let dist_sq_line = (-rel1 - edge * s).norm_squared();

            if s < 0.0 && dist_sq1 <= radius_sq {
                // Collision with left vertex (ignored if non-convex).
                if verts[i1].convex {
                    self.lines.push(Line {
                        point: Vec2::zeros(),
                        direction: normalize_or(Vec2::new(-rel1.y, rel1.x), -verts[i1].unit_dir),
                    });
                }
                continue;
            } else if s > 1.0 && dist_sq2 <= radius_sq {
                // Collision with right vertex (ignored if non-convex, or if
                // the next edge will take care of it).
                if verts[i2].convex && det(rel2, verts[i2].unit_dir) >= 0.0 {
                    self.lines.push(Line {
                        point: Vec2::zeros(),
                        direction: normalize_or(Vec2::new(-rel2.y, rel2.x), -verts[i1].unit_dir),
                    });
                }
                continue;
            } else if (0.0..=1.0).contains(&s) && dist_sq_line <= radius_sq {
                // Collision with obstacle segment (both ends included, as
                // in RVO2: a robot exactly abreast of the end, s = 1, is
                // still colliding with the segment).
                self.lines.push(Line {
                    point: Vec2::zeros(),
                    direction: -verts[i1].unit_dir,
                });
                continue;
            }

            // No collision: compute the legs. Seen obliquely, both legs may
            // come from one vertex; at a non-convex vertex the leg extends
            // the cut-off line.
            let left_tangent = |rel: Vec2, dist_sq: f64| {
                let leg = (dist_sq - radius_sq).max(0.0).sqrt();
                Vec2::new(rel.x * leg - rel.y * radius, rel.x * radius + rel.y * leg) / dist_sq
            };
            let right_tangent = |rel: Vec2, dist_sq: f64| {
                let leg = (dist_sq - radius_sq).max(0.0).sqrt();
                Vec2::new(rel.x * leg + rel.y * radius, -rel.x * radius + rel.y * leg) / dist_sq
            };
            let (mut left_leg, mut right_leg);
            if s < 0.0 && dist_sq_line <= radius_sq {
                // Obstacle viewed obliquely: the left vertex defines the
                // velocity obstacle.
                if !verts[i1].convex {
                    continue;
                }
                i2 = i1;
                left_leg = left_tangent(rel1, dist_sq1);
                right_leg = right_tangent(rel1, dist_sq1);
            } else if s > 1.0 && dist_sq_line <= radius_sq {
                // Obstacle viewed obliquely: the right vertex defines the
                // velocity obstacle.
                if !verts[i2].convex {
                    continue;
                }
                i1 = i2;
                left_leg = left_tangent(rel2, dist_sq2);
                right_leg = right_tangent(rel2, dist_sq2);
            } else {
                // Usual situation.
                left_leg = if verts[i1].convex {
                    left_tangent(rel1, dist_sq1)
                } else {
                    // Left vertex non-convex: the left leg extends the
                    // cut-off line.
                    -verts[i1].unit_dir
                };
                right_leg = if verts[i2].convex {
                    right_tangent(rel2, dist_sq2)
                } else {
                    // Right vertex non-convex: the right leg extends the
                    // cut-off line.
                    verts[i1].unit_dir
                };
            }

            // A leg at a convex vertex never points into the neighbouring
            // edge: take that edge's cut-off line instead ("foreign" leg; a
            // velocity projected on a foreign leg adds no constraint).
            let left_neighbor = verts[i1].prev;
            let mut left_foreign = false;
            let mut right_foreign = false;
            if verts[i1].convex && det(left_leg, -verts[left_neighbor].unit_dir) >= 0.0 {
                // Left leg points into obstacle.
                left_leg = -verts[left_neighbor].unit_dir;
                left_foreign = true;
            }
            if verts[i2].convex && det(right_leg, verts[i2].unit_dir) <= 0.0 {
                // Right leg points into obstacle.
                right_leg = verts[i2].unit_dir;
                right_foreign = true;
            }

            // Cut-off centres.
            let left_cutoff = (verts[i1].point - position) * inv_tau;
            let right_cutoff = (verts[i2].point - position) * inv_tau;
            let cutoff_vec = right_cutoff - left_cutoff;
            let single_vertex = i1 == i2;

            // Project the current velocity on the velocity obstacle: first,
            // is it projected on a cut-off circle?
            let t = if single_vertex {
                0.5
            } else {
                (velocity - left_cutoff).dot(&cutoff_vec) / cutoff_vec.norm_squared()
            };
            let t_left = (velocity - left_cutoff).dot(&left_leg);
            let t_right = (velocity - right_cutoff).dot(&right_leg);

            if (t < 0.0 && t_left < 0.0) || (single_vertex && t_left < 0.0 && t_right < 0.0) {
                // Project on left cut-off circle.
                let unit_w = normalize_or(
                    velocity - left_cutoff,
                    normalize_or(-left_cutoff, Vec2::x()),
                );
                self.lines.push(Line {
                    direction: Vec2::new(unit_w.y, -unit_w.x),
                    point: left_cutoff + unit_w * (radius * inv_tau),
                });
                continue;
            } else if t > 1.0 && t_right < 0.0 {
                // Project on right cut-off circle.
                let unit_w = normalize_or(
                    velocity - right_cutoff,
                    normalize_or(-right_cutoff, Vec2::x()),
                );
                self.lines.push(Line {
                    direction: Vec2::new(unit_w.y, -unit_w.x),
                    point: right_cutoff + unit_w * (radius * inv_tau),
                });
                continue;
            }

            // Project on the left leg, the right leg or the cut-off line,
            // whichever is closest to the velocity.
            let dist_sq_cutoff = if !(0.0..=1.0).contains(&t) || single_vertex {
                f64::INFINITY
            } else {
                (velocity - (left_cutoff + cutoff_vec * t)).norm_squared()
            };
            let dist_sq_left = if t_left < 0.0 {
                f64::INFINITY
            } else {
                (velocity - (left_cutoff + left_leg * t_left)).norm_squared()
            };
            let dist_sq_right = if t_right < 0.0 {
                f64::INFINITY
            } else {
                (velocity - (right_cutoff + right_leg * t_right)).norm_squared()
            };
            // The admissible side is left of the direction, so the line
            // sits `radius / tau` outward (to the right-hand normal's
            // opposite) of the obstacle's cut-off.
            let shifted = |cutoff: Vec2, direction: Vec2| Line {
                point: cutoff + Vec2::new(-direction.y, direction.x) * (radius * inv_tau),
                direction,
            };
            if dist_sq_cutoff <= dist_sq_left && dist_sq_cutoff <= dist_sq_right {
                // Project on cut-off line.
                self.lines.push(shifted(left_cutoff, -verts[i1].unit_dir));
            } else if dist_sq_left <= dist_sq_right {
                // Project on left leg.
                if !left_foreign {
                    self.lines.push(shifted(left_cutoff, left_leg));
                }
            } else {
                // Project on right leg.
                if !right_foreign {
                    self.lines.push(shifted(right_cutoff, -right_leg));
                }
            }
        }
    }

    /// The ORCA half-plane of another body (section 4 of the paper), with
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
}

/// Solves the 1-D program on line `line_no` under the earlier lines and the
/// speed disc of `radius` (RVO2's `linearProgram1`). `None` when the
/// constraints leave nothing of the line.
fn linear_program1(
    lines: &[Line],
    line_no: usize,
    radius: f64,
    opt: Vec2,
    direction_opt: bool,
) -> Option<Vec2> {
    let line = lines[line_no];
    let dot = line.point.dot(&line.direction);
    let discriminant = dot * dot + radius * radius - line.point.norm_squared();
    if discriminant < 0.0 {
        // Max speed circle fully invalidates line `line_no`.
        return None;
    }
    let sqrt_disc = discriminant.sqrt();
    let mut t_left = -dot - sqrt_disc;
    let mut t_right = -dot + sqrt_disc;
    for other in &lines[..line_no] {
        let denominator = det(line.direction, other.direction);
        let numerator = det(other.direction, line.point - other.point);
        if denominator.abs() <= RVO_EPSILON {
            // Lines `line_no` and `other` are (almost) parallel.
            if numerator < 0.0 {
                return None;
            }
            continue;
        }
        let t = numerator / denominator;
        if denominator >= 0.0 {
            // Line `other` bounds line `line_no` on the right.
            t_right = t_right.min(t);
        } else {
            // Line `other` bounds line `line_no` on the left.
            t_left = t_left.max(t);
        }
        if t_left > t_right {
            return None;
        }
    }
    let t = if direction_opt {
        // Optimise direction: take the extreme along `opt`.
        if opt.dot(&line.direction) > 0.0 {
            t_right
        } else {
            t_left
        }
    } else {
        // Optimise closest point.
        line.direction
            .dot(&(opt - line.point))
            .clamp(t_left, t_right)
    };
    Some(line.point + line.direction * t)
}

/// The point of the disc of `radius` left of every line that is closest to
/// `opt` (or furthest along the unit `opt` when `direction_opt`), added one
/// line at a time (RVO2's `linearProgram2`). Returns `lines.len()` on
/// success, else the index of the line that made it infeasible, `result`
/// being the optimum of the lines before it.
fn linear_program2(
    lines: &[Line],
    radius: f64,
    opt: Vec2,
    direction_opt: bool,
    result: &mut Vec2,
) -> usize {
    *result = if direction_opt {
        // Optimise direction (`opt` is a unit vector here).
        opt * radius
    } else if opt.norm_squared() > radius * radius {
        // Optimise closest point, outside the circle.
        opt.normalize() * radius
    } else {
        // Optimise closest point, inside the circle.
        opt
    };
    for i in 0..lines.len() {
        if lines[i].violation(*result) > 0.0 {
            // The result breaks constraint i: the new optimum is on line i.
            match linear_program1(lines, i, radius, opt, direction_opt) {
                Some(r) => *result = r,
                None => return i,
            }
        }
    }
    lines.len()
}

/// When the 2-D program is infeasible from line `begin_line` on: keeps the
/// first `num_obst_lines` (static obstacles) hard and minimises the largest
/// violation of the other lines, by a 2-D program in the space of the
/// bisectors for each line that is violated more than the current optimum
/// (RVO2's `linearProgram3`, the paper's 3-D program).
fn linear_program3(
    lines: &[Line],
    num_obst_lines: usize,
    begin_line: usize,
    radius: f64,
    result: &mut Vec2,
    proj_lines: &mut Vec<Line>,
) {
    let mut distance = 0.0;
    for i in begin_line..lines.len() {
        if lines[i].violation(*result) <= distance {
            continue;
        }
        // The result breaks line i by more than the current optimum.
        proj_lines.clear();
        proj_lines.extend_from_slice(&lines[..num_obst_lines]);
        for j in num_obst_lines..i {
            let determinant = det(lines[i].direction, lines[j].direction);
            let point = if determinant.abs() <= RVO_EPSILON {
                // Lines i and j are parallel.
                if lines[i].direction.dot(&lines[j].direction) > 0.0 {
                    // Same direction: j adds nothing.
                    continue;
                }
                // Opposite directions: the bisector is half way.
                (lines[i].point + lines[j].point) * 0.5
            } else {
                lines[i].point
                    + lines[i].direction
                        * (det(lines[j].direction, lines[i].point - lines[j].point) / determinant)
            };
            proj_lines.push(Line {
                point,
                direction: (lines[j].direction - lines[i].direction).normalize(),
            });
        }
        let previous = *result;
        let away = Vec2::new(-lines[i].direction.y, lines[i].direction.x);
        if linear_program2(proj_lines, radius, away, true, result) < proj_lines.len() {
            // In principle impossible (the result is feasible by
            // construction); only rounding gets here: keep the last result.
            *result = previous;
        }
        distance = lines[i].violation(*result);
    }
}

impl Planner for Orca {
    fn plan(&mut self, obs: &Observation) -> Command {
        let me = &obs.me;
        let pref = self.preferred_velocity(obs);
        self.lines.clear();

        // Static obstacles first (they stay hard in the 3-D program).
        if self.chains_of.as_slice() != obs.walls {
            self.chains_of = obs.walls.to_vec();
            self.chains = WallChain::join(obs.walls);
        }
        self.obstacles.clear();
        self.obstacles.push_chains(&self.chains, me.position);
        let radius = me.radius + self.radius_margin;
        self.select_obstacle_neighbors(me.position, radius, me.max_speed);
        self.push_obstacle_lines(me.position, me.velocity, radius);
        let num_obst_lines = self.lines.len();

        // Then the other bodies, nearest first.
        self.select_neighbors(obs);
        let inv_tau = 1.0 / self.time_horizon;
        let dt = if obs.dt > 0.0 { obs.dt } else { 1.0 };
        for &(_, k) in &self.neighbors {
            let other = &obs.others[k];
            let share = match other.kind {
                BodyKind::Robot => 0.5,
                BodyKind::Obstacle => 1.0,
            };
            self.lines.push(Self::body_line(
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

        let mut v = Vec2::zeros();
        let fail = linear_program2(&self.lines, me.max_speed, pref, false, &mut v);
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

    fn diagnostics(&self) -> Vec<Diagnostic> {
        vec![
            Diagnostic {
                name: "orca_lines".into(),
                value: self.last_lines as f64,
            },
            Diagnostic {
                name: "orca_infeasible".into(),
                value: if self.last_infeasible { 1.0 } else { 0.0 },
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::Sim;
    use crate::{ParamValue, SelfState};

    fn me(position: Vec2, velocity: Vec2, radius: f64) -> SelfState {
        SelfState {
            id: 0,
            position,
            velocity,
            radius,
            mass: 1.0,
            damping: 0.0,
            max_speed: 2.0,
            max_accel: 1e9,
        }
    }

    fn obs<'a>(
        me: SelfState,
        goal: Vec2,
        others: &'a [Sensed],
        walls: &'a [Segment],
    ) -> Observation<'a> {
        Observation {
            tick: 0,
            time: 0.0,
            dt: 0.25,
            me,
            goal,
            goal_tolerance: 0.1,
            goal_hold_ticks: 3,
            others,
            walls,
            path: None,
        }
    }

    fn body(id: u32, kind: BodyKind, position: Vec2, velocity: Vec2, radius: f64) -> Sensed {
        Sensed {
            id,
            kind,
            position,
            velocity,
            acceleration: Vec2::zeros(),
            radius,
        }
    }

    fn line(point: (f64, f64), direction: (f64, f64)) -> Line {
        Line {
            point: Vec2::new(point.0, point.1),
            direction: Vec2::new(direction.0, direction.1).normalize(),
        }
    }

    /// Closest centre distance over [0, horizon] of two bodies whose
    /// relative position is `rel_pos` and relative velocity `rel_vel`.
    fn closest_approach(rel_pos: Vec2, rel_vel: Vec2, horizon: f64) -> f64 {
        let t = if rel_vel.norm_squared() > 0.0 {
            (rel_pos.dot(&rel_vel) / rel_vel.norm_squared()).clamp(0.0, horizon)
        } else {
            0.0
        };
        (rel_pos - rel_vel * t).norm()
    }

    #[test]
    fn linear_program_finds_the_closest_admissible_point_when_feasible() {
        // y >= 1 and x >= 1, speed disc of radius 2, optimum at the origin.
        let lines = [line((0.0, 1.0), (1.0, 0.0)), line((1.0, 0.0), (0.0, -1.0))];
        let mut v = Vec2::zeros();
        let n = linear_program2(&lines, 2.0, Vec2::zeros(), false, &mut v);
        assert_eq!(n, lines.len());
        assert!((v - Vec2::new(1.0, 1.0)).norm() < 1e-12, "{v:?}");
        // An optimum already admissible is kept as it is.
        let n = linear_program2(&lines, 2.0, Vec2::new(1.2, 1.5), false, &mut v);
        assert_eq!(n, lines.len());
        assert!((v - Vec2::new(1.2, 1.5)).norm() < 1e-12, "{v:?}");
    }

    #[test]
    fn infeasible_program_minimises_the_largest_violation() {
        // y >= 1 and y <= -1 cannot both hold: the 2-D program fails at the
        // second line, and the 3-D program settles on y = 0, one unit from
        // each.
        let lines = [line((0.0, 1.0), (1.0, 0.0)), line((0.0, -1.0), (-1.0, 0.0))];
        let mut v = Vec2::zeros();
        let fail = linear_program2(&lines, 2.0, Vec2::new(0.5, 0.0), false, &mut v);
        assert_eq!(fail, 1);
        let mut scratch = Vec::new();
        linear_program3(&lines, 0, fail, 2.0, &mut v, &mut scratch);
        assert!(v.y.abs() < 1e-12, "{v:?}");
        assert!(v.norm() <= 2.0 + 1e-12);
        assert!((lines[0].violation(v) - 1.0).abs() < 1e-12);
        assert!((lines[1].violation(v) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn constraint_beyond_the_speed_disc_gives_the_nearest_fast_velocity() {
        // y >= 3 with |v| <= 2: max speed circle fully invalidates the line.
        let lines = [line((0.0, 3.0), (1.0, 0.0))];
        let mut v = Vec2::zeros();
        let fail = linear_program2(&lines, 2.0, Vec2::new(1.0, 0.0), false, &mut v);
        assert_eq!(fail, 0);
        linear_program3(&lines, 0, fail, 2.0, &mut v, &mut Vec::new());
        assert!((v - Vec2::new(0.0, 2.0)).norm() < 1e-12, "{v:?}");
    }

    #[test]
    fn infeasible_program_keeps_obstacle_lines_hard() {
        // Obstacle line x >= 1 first, then the contradictory body lines.
        let lines = [
            line((1.0, 0.0), (0.0, -1.0)),
            line((0.0, 1.0), (1.0, 0.0)),
            line((0.0, -1.0), (-1.0, 0.0)),
        ];
        let mut v = Vec2::zeros();
        let fail = linear_program2(&lines, 2.0, Vec2::zeros(), false, &mut v);
        assert_eq!(fail, 2);
        linear_program3(&lines, 1, fail, 2.0, &mut v, &mut Vec::new());
        assert!(v.x >= 1.0 - 1e-12, "{v:?}");
        assert!(v.y.abs() < 1e-12, "{v:?}");
    }

    fn head_on(kind_of_b: BodyKind) -> (Vec2, Vec2, Vec2, Vec2) {
        let (pa, va) = (Vec2::new(-5.0, 0.0), Vec2::new(1.0, 0.0));
        let (pb, vb) = (Vec2::new(5.0, 0.0), Vec2::new(-1.0, 0.0));
        let mut orca = Orca::default();
        let b_seen_by_a = [body(1, kind_of_b, pb, vb, 1.0)];
        let a_seen_by_b = [body(0, BodyKind::Robot, pa, va, 1.0)];
        // Goals far ahead: the preferred velocity is the current one.
        let new_a = orca
            .plan(&obs(
                me(pa, va, 1.0),
                Vec2::new(100.0, 0.0),
                &b_seen_by_a,
                &[],
            ))
            .vector();
        let mut me_b = me(pb, vb, 1.0);
        me_b.id = 1;
        let new_b = orca
            .plan(&obs(me_b, Vec2::new(-100.0, 0.0), &a_seen_by_b, &[]))
            .vector();
        (va, new_a, vb, new_b)
    }

    #[test]
    fn two_robots_head_on_each_take_half_of_the_avoidance() {
        let (va, new_a, vb, new_b) = head_on(BodyKind::Robot);
        let (da, db) = (new_a - va, new_b - vb);
        assert!(da.norm() > 1e-3, "A must swerve: {da:?}");
        assert!(
            (da + db).norm() < 1e-12,
            "equal and opposite: {da:?} {db:?}"
        );
        // Each swerves to its own right: A (moving +x) to -y, B to +y.
        assert!(da.y < 0.0 && db.y > 0.0);
        // Together the two halves put the relative velocity exactly on the
        // boundary of the truncated velocity obstacle: the discs graze
        // (combined radius 2) within the time horizon.
        let rel_pos = Vec2::new(10.0, 0.0);
        let closest = closest_approach(rel_pos, new_a - new_b, 10.0);
        assert!((closest - 2.0).abs() < 1e-9, "closest approach {closest}");
    }

    #[test]
    fn a_scripted_obstacle_gets_no_share_of_the_avoidance() {
        let (va, robot_a, _, _) = head_on(BodyKind::Robot);
        let (_, obstacle_a, vb, _) = head_on(BodyKind::Obstacle);
        let (half, full) = (robot_a - va, obstacle_a - va);
        assert!((full - half * 2.0).norm() < 1e-12, "{half:?} {full:?}");
        // Alone, A's new velocity clears the obstacle's constant motion.
        let closest = closest_approach(Vec2::new(10.0, 0.0), obstacle_a - vb, 10.0);
        assert!((closest - 2.0).abs() < 1e-9, "closest approach {closest}");
    }

    #[test]
    fn overlapping_robots_separate_within_one_control_period() {
        // Centres 1.5 apart, combined radius 2, both still: the collision
        // case asks for a relative velocity that opens the gap in one dt.
        let mut orca = Orca::default();
        let other = [body(
            1,
            BodyKind::Robot,
            Vec2::new(1.5, 0.0),
            Vec2::zeros(),
            1.0,
        )];
        let v = orca
            .plan(&obs(
                me(Vec2::zeros(), Vec2::zeros(), 1.0),
                Vec2::zeros(),
                &other,
                &[],
            ))
            .vector();
        // Half of the 0.5 overlap in 0.25 s: 1 unit/s away from the other.
        assert!((v - Vec2::new(-1.0, 0.0)).norm() < 1e-12, "{v:?}");
    }

    #[test]
    fn robot_facing_a_wall_may_only_reach_it_after_the_obstacle_horizon() {
        // Wall x = 3, robot of radius 0.5 at the origin, goal behind the
        // wall: "Project on cut-off line" allows at most (3 - 0.5) / 10
        // towards the wall, and nothing along it is preferred.
        let walls = [Segment {
            a: Vec2::new(3.0, -5.0),
            b: Vec2::new(3.0, 5.0),
        }];
        let mut orca = Orca::default();
        let v = orca
            .plan(&obs(
                me(Vec2::zeros(), Vec2::zeros(), 0.5),
                Vec2::new(10.0, 0.0),
                &[],
                &walls,
            ))
            .vector();
        assert!((v - Vec2::new(0.25, 0.0)).norm() < 1e-12, "{v:?}");
        // Drawn the other way round, the wall is the same obstacle.
        let flipped = [Segment {
            a: walls[0].b,
            b: walls[0].a,
        }];
        let w = orca
            .plan(&obs(
                me(Vec2::zeros(), Vec2::zeros(), 0.5),
                Vec2::new(10.0, 0.0),
                &[],
                &flipped,
            ))
            .vector();
        assert!((v - w).norm() < 1e-12, "{v:?} {w:?}");
    }

    /// Runs one ORCA robot of radius 0.5 from `start` to `goal` past
    /// `walls`; returns the smallest gap to a wall, the tick it came within
    /// 0.1 of the goal, and where it ended.
    fn past_walls(
        walls: &[Segment],
        start: Vec2,
        goal: Vec2,
        ticks: u64,
    ) -> (f64, Option<u64>, Vec2) {
        let mut sim = Sim::new(0.25, 1);
        sim.walls.extend_from_slice(walls);
        sim.add_robot(
            Box::new(Orca::default()),
            start,
            goal,
            0.5,
            1.0,
            0.0,
            2.0,
            1e9,
        );
        let mut min_gap = f64::INFINITY;
        for tick in 1..=ticks {
            sim.step();
            let p = sim.robots[0].state.position;
            for w in walls {
                min_gap = min_gap.min((p - w.closest_point(p)).norm() - 0.5);
            }
            if (p - goal).norm() < 0.1 {
                return (min_gap, Some(tick), p);
            }
        }
        (min_gap, None, sim.robots[0].state.position)
    }

    #[test]
    fn robot_slides_along_a_wall_and_round_its_end_without_touching_it() {
        let wall = Segment {
            a: Vec2::new(5.0, -1.0),
            b: Vec2::new(5.0, 3.0),
        };
        let (min_gap, reached, end) = past_walls(&[wall], Vec2::zeros(), Vec2::new(10.0, 6.0), 400);
        assert!(min_gap >= -TOUCH, "touched the wall: gap {min_gap}");
        assert!(reached.is_some(), "stuck at {end:?}");
    }

    #[test]
    fn robot_heading_square_into_a_wall_stops_short_of_it() {
        // ORCA is local: with the goal straight behind the wall nothing
        // pushes the robot sideways, and it creeps towards the wall without
        // reaching it (RVO2 pairs ORCA with a roadmap for this).
        let wall = Segment {
            a: Vec2::new(5.0, -1.0),
            b: Vec2::new(5.0, 3.0),
        };
        let (min_gap, reached, end) = past_walls(&[wall], Vec2::zeros(), Vec2::new(10.0, 0.0), 400);
        assert!(reached.is_none());
        assert!(min_gap >= -TOUCH, "touched the wall: gap {min_gap}");
        assert!(end.y.abs() < 1e-9 && end.x > 4.0, "{end:?}");
    }

    fn seg(a: (f64, f64), b: (f64, f64)) -> Segment {
        Segment {
            a: Vec2::new(a.0, a.1),
            b: Vec2::new(b.0, b.1),
        }
    }

    /// The obstacle lines a robot at `p` with velocity `v` gets from `set`.
    fn obstacle_lines(set: ObstacleSet, p: Vec2, v: Vec2) -> Vec<Line> {
        let mut orca = Orca {
            time_horizon_obst: 5.0,
            ..Orca::default()
        };
        orca.obstacles = set;
        orca.select_obstacle_neighbors(p, 2.0, 2.0);
        orca.push_obstacle_lines(p, v, 2.0);
        orca.lines
    }

    #[test]
    fn a_robot_touching_a_wall_exactly_abreast_of_its_end_gets_the_segment_collision_line() {
        // Wall from (0, 0) to (10, 0), seen from below; a robot of radius 2
        // at (10, -1) projects exactly onto the wall's end (s = 1) and
        // overlaps the wall. RVO2 takes 0 <= s <= 1 as "collision with
        // obstacle segment": the line through the origin along the wall
        // reversed, leaving only velocities away from the wall.
        let mut set = ObstacleSet::default();
        set.push_walls(&[seg((0.0, 0.0), (10.0, 0.0))], Vec2::new(10.0, -1.0));
        let lines = obstacle_lines(set, Vec2::new(10.0, -1.0), Vec2::zeros());
        let expected = Line {
            point: Vec2::zeros(),
            direction: Vec2::new(-1.0, 0.0),
        };
        assert_eq!(lines.first(), Some(&expected), "{lines:?}");
    }

    #[test]
    fn a_square_drawn_as_four_walls_in_any_order_is_rvo2s_polygon() {
        // RVO2's Blocks obstacle 2, counter-clockwise, and the same square as
        // four walls, shuffled and some reversed.
        let polygon =
            [(10.0, 40.0), (10.0, 10.0), (40.0, 10.0), (40.0, 40.0)].map(|(x, y)| Vec2::new(x, y));
        let walls = [
            seg((40.0, 10.0), (40.0, 40.0)),
            seg((10.0, 10.0), (10.0, 40.0)),
            seg((40.0, 40.0), (10.0, 40.0)),
            seg((40.0, 10.0), (10.0, 10.0)),
        ];
        let chains = WallChain::join(&walls);
        assert_eq!(chains.len(), 1);
        assert!(chains[0].closed && chains[0].points.len() == 4);
        let mut lone_segments_differ = 0;
        // Robots all round the square, near and far, heading at it, past
        // its corners and along its sides.
        for k in 0..48 {
            for dist in [19.0, 21.5, 24.0, 30.0] {
                for turn in 0..8 {
                    // Off the diagonals: no two edges at exactly one distance.
                    let a = (k as f64 + 0.3) * std::f64::consts::TAU / 48.0;
                    let p = Vec2::new(25.0, 25.0) + Vec2::new(a.cos(), a.sin()) * dist;
                    if (p.x - 25.0).abs() < 17.0 && (p.y - 25.0).abs() < 17.0 {
                        continue;
                    }
                    let b = turn as f64 * std::f64::consts::TAU / 8.0;
                    let v = Vec2::new(b.cos(), b.sin()) * 1.8;
                    let mut rvo2 = ObstacleSet::default();
                    rvo2.push_polygon(&polygon);
                    let mut ours = ObstacleSet::default();
                    ours.push_walls(&walls, p);
                    let (want, got) = (obstacle_lines(rvo2, p, v), obstacle_lines(ours, p, v));
                    // The same lines; edges at equal distances may come in
                    // another order (RVO2 orders such ties by its k-d tree).
                    assert_eq!(want.len(), got.len(), "at {p:?}");
                    for w in &want {
                        assert!(
                            got.iter().any(|g| (w.point - g.point).norm() < 1e-12
                                && (w.direction - g.direction).norm() < 1e-12),
                            "at {p:?} with {v:?}: {w:?} missing from {got:?}"
                        );
                    }
                    // Four unrelated segments are not the same obstacle.
                    let mut lone = ObstacleSet::default();
                    for w in &walls {
                        lone.push_polygon(&[w.a, w.b]);
                    }
                    lone_segments_differ += usize::from(obstacle_lines(lone, p, v) != want);
                }
            }
        }
        assert!(lone_segments_differ > 0);
    }

    #[test]
    fn an_arena_is_a_boundary_from_inside_and_open_chains_go_there_and_back() {
        let arena = [
            seg((0.0, 0.0), (10.0, 0.0)),
            seg((10.0, 0.0), (10.0, 10.0)),
            seg((10.0, 10.0), (0.0, 10.0)),
            seg((0.0, 10.0), (0.0, 0.0)),
        ];
        let mut inside = ObstacleSet::default();
        inside.push_walls(&arena, Vec2::new(5.0, 5.0));
        // Clockwise seen from inside: every edge has the robot on its right.
        for v in &inside.vertices {
            let next = inside.vertices[v.next].point;
            assert!(left_of(v.point, next, Vec2::new(5.0, 5.0)) < 0.0);
            assert!(!v.convex, "an arena's corners are concave from inside");
        }
        // An L of two walls: p0, p1, p2, then back through p1.
        let l = [seg((0.0, 0.0), (5.0, 0.0)), seg((5.0, 5.0), (5.0, 0.0))];
        let chains = WallChain::join(&l);
        assert_eq!(chains.len(), 1);
        assert!(!chains[0].closed);
        let mut set = ObstacleSet::default();
        set.push_chains(&chains, Vec2::new(-3.0, 2.0));
        let pts: Vec<Vec2> = set.vertices.iter().map(|v| v.point).collect();
        assert_eq!(pts.len(), 4);
        assert_eq!(pts[1], Vec2::new(5.0, 0.0));
        assert_eq!(pts[3], Vec2::new(5.0, 0.0));
        // The corner is convex on one pass and concave on the other.
        assert_ne!(set.vertices[1].convex, set.vertices[3].convex);
        // A T junction ends the chains there.
        let t = [
            seg((0.0, 0.0), (2.0, 0.0)),
            seg((2.0, 0.0), (4.0, 0.0)),
            seg((2.0, 0.0), (2.0, 2.0)),
        ];
        assert_eq!(WallChain::join(&t).len(), 3);
    }

    #[test]
    fn robot_inside_an_arena_stays_inside_and_rounds_an_l_shaped_wall() {
        let walls = [
            seg((-10.0, -10.0), (10.0, -10.0)),
            seg((10.0, -10.0), (10.0, 10.0)),
            seg((10.0, 10.0), (-10.0, 10.0)),
            seg((-10.0, 10.0), (-10.0, -10.0)),
            seg((0.0, -1.0), (0.0, 3.0)),
            seg((3.0, 3.0), (0.0, 3.0)),
        ];
        let goal = Vec2::new(7.0, 6.0);
        let (min_gap, reached, end) = past_walls(&walls, Vec2::new(-7.0, -6.0), goal, 400);
        assert!(min_gap >= -TOUCH, "touched a wall: gap {min_gap}");
        assert!(reached.is_some(), "stuck at {end:?}");
    }

    #[test]
    fn perturbation_is_bounded_seeded_and_off_by_default() {
        let o = obs(
            me(Vec2::zeros(), Vec2::zeros(), 0.5),
            Vec2::new(10.0, 0.0),
            &[],
            &[],
        );
        let plain = Orca::default().plan(&o).vector();
        assert_eq!(plain, Vec2::new(1.0, 0.0));
        let perturbed = |seed| {
            let mut p = Orca {
                perturb: 1e-4,
                seed,
                ..Orca::default()
            };
            p.plan(&o).vector()
        };
        let (a, b, c) = (perturbed(1), perturbed(1), perturbed(2));
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!((a - plain).norm() < 1e-4 && a != plain);
    }

    #[test]
    fn only_the_nearest_max_neighbors_within_neighbor_dist_are_avoided() {
        // Three bodies close by but out of the way, one far ahead in the
        // way (inside neighbor_dist), one beyond neighbor_dist.
        let others = [
            body(1, BodyKind::Robot, Vec2::new(0.0, 4.0), Vec2::zeros(), 0.5),
            body(2, BodyKind::Robot, Vec2::new(0.0, -4.0), Vec2::zeros(), 0.5),
            body(3, BodyKind::Robot, Vec2::new(-4.0, 0.0), Vec2::zeros(), 0.5),
            body(
                4,
                BodyKind::Obstacle,
                Vec2::new(8.0, 0.0),
                Vec2::zeros(),
                0.5,
            ),
            body(
                5,
                BodyKind::Obstacle,
                Vec2::new(20.0, 0.0),
                Vec2::zeros(),
                0.5,
            ),
        ];
        let start = me(Vec2::zeros(), Vec2::new(1.0, 0.0), 0.5);
        let goal = Vec2::new(100.0, 0.0);
        let mut three = Orca {
            max_neighbors: 3,
            ..Orca::default()
        };
        let v = three.plan(&obs(start, goal, &others, &[])).vector();
        assert_eq!(three.diagnostics()[0].value, 3.0);
        assert!((v - Vec2::new(1.0, 0.0)).norm() < 1e-12, "{v:?}");
        // With room for four, the body ahead is seen and avoided; the one
        // beyond neighbor_dist never is.
        let mut four = Orca {
            max_neighbors: 4,
            ..Orca::default()
        };
        let v = four.plan(&obs(start, goal, &others, &[])).vector();
        assert_eq!(four.diagnostics()[0].value, 4.0);
        assert!(v.y.abs() > 1e-3, "{v:?}");
        let mut all = Orca::default();
        all.plan(&obs(start, goal, &others, &[]));
        assert_eq!(all.diagnostics()[0].value, 4.0);
    }

    #[test]
    fn parameters_use_rvo2_names_and_refuse_others() {
        let mut p = Params::new();
        p.insert("time_horizon".into(), ParamValue::Number(5.0));
        p.insert("max_neighbors".into(), ParamValue::Number(4.0));
        let o = Orca::from_params(&p).unwrap();
        assert_eq!((o.time_horizon, o.max_neighbors), (5.0, 4));
        assert_eq!(o.neighbor_dist, 15.0);
        p.insert("tau".into(), ParamValue::Number(5.0));
        assert!(Orca::from_params(&p).is_err());
    }

    /// RVO2's Circle example with `n` agents on a circle of `radius`, each
    /// start moved by up to `jitter` in x and y (a fixed-seed generator:
    /// real robots are never placed with perfect symmetry).
    fn circle(n: usize, radius: f64, jitter: f64, max_neighbors: usize) -> (Sim, Vec<Vec2>) {
        let mut state: u64 = 12345;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut sim = Sim::new(0.25, 1);
        let mut goals = Vec::new();
        for i in 0..n {
            let a = i as f64 * std::f64::consts::TAU / n as f64;
            let on_circle = Vec2::new(a.cos(), a.sin()) * radius;
            goals.push(-on_circle);
            let start = on_circle + Vec2::new(uniform(), uniform()) * jitter;
            let planner = Orca {
                max_neighbors,
                ..Orca::default()
            };
            sim.add_robot(
                Box::new(planner),
                start,
                -on_circle,
                1.5,
                1.0,
                0.0,
                2.0,
                1e12,
            );
        }
        (sim, goals)
    }

    fn gap(sim: &Sim, i: usize, j: usize) -> f64 {
        let (a, b) = (&sim.robots[i].state, &sim.robots[j].state);
        (a.position - b.position).norm() - a.radius - b.radius
    }

    fn all_reached(sim: &Sim, goals: &[Vec2]) -> bool {
        // RVO2's `reachedGoal`: every agent within its radius of its goal.
        sim.robots
            .iter()
            .zip(goals)
            .all(|(r, g)| (r.state.position - g).norm() <= r.state.radius)
    }

    fn infeasible(sim: &Sim, i: usize) -> bool {
        sim.robots[i].planner.diagnostics()[1].value != 0.0
    }

    /// Contact within rounding counts as touching, not overlapping.
    const TOUCH: f64 = 1e-9;

    #[test]
    fn sixteen_robots_on_a_circle_reach_their_antipodes_overlapping_only_after_infeasible_steps() {
        // RVO2's Circle spacing (250 on radius 200) for 16 agents, every
        // agent seeing all the others so that every pair is reciprocal.
        let n = 16;
        let (mut sim, goals) = circle(n, 200.0 * n as f64 / 250.0, 0.1, n - 1);
        let pairs: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .collect();
        let mut overlapping = vec![false; pairs.len()];
        let mut reached = None;
        let mut infeasible_steps = 0;
        for tick in 1..=2000 {
            sim.step();
            infeasible_steps += (0..n).filter(|&i| infeasible(&sim, i)).count();
            for (k, &(i, j)) in pairs.iter().enumerate() {
                let now = gap(&sim, i, j) < -TOUCH;
                // The paper's guarantee: when both robots' programs were
                // feasible, each kept its half of the pair's constraint and
                // the pair cannot come into overlap during the step.
                if now && !overlapping[k] {
                    assert!(
                        infeasible(&sim, i) || infeasible(&sim, j),
                        "robots {i} and {j} overlap at tick {tick} after feasible programs"
                    );
                }
                overlapping[k] = now;
            }
            if all_reached(&sim, &goals) {
                reached = Some(tick);
                break;
            }
        }
        assert!(reached.is_some(), "not all reached their goals");
        // The crowd in the middle is dense enough to make programs
        // infeasible (RVO2 shows the same); the check above is not vacuous.
        assert!(infeasible_steps > 0);
    }

    #[test]
    fn perfectly_symmetric_circle_jams_as_rvo2_does() {
        // With exact symmetry every robot's constraints are mirror images,
        // the optimum stays on its radius and the crowd stops in a ring of
        // touching discs. RVO2 (compiled from snape/RVO2, 16 agents on
        // radius 12.8) jams the same way; only rounding or noise breaks it.
        let n = 16;
        let (mut sim, goals) = circle(n, 200.0 * n as f64 / 250.0, 0.0, 10);
        let mut min_gap = f64::INFINITY;
        for _ in 0..600 {
            sim.step();
            for i in 0..n {
                for j in i + 1..n {
                    min_gap = min_gap.min(gap(&sim, i, j));
                }
            }
        }
        assert!(!all_reached(&sim, &goals));
        assert!(min_gap >= -TOUCH, "overlap {min_gap}");
        assert!(sim.robots.iter().all(|r| r.state.velocity.norm() < 1e-3));
    }

    /// RVO2's Blocks obstacle 4 (the lower-left square), as four walls.
    fn blocks_square_4() -> Vec<Segment> {
        let corners = [
            (-10.0, -40.0),
            (-10.0, -10.0),
            (-40.0, -10.0),
            (-40.0, -40.0),
        ];
        (0..4)
            .map(|k| seg(corners[k], corners[(k + 1) % 4]))
            .collect()
    }

    /// ORCA with RVO2's Blocks parameters and perturbation, `seed` drawn.
    fn blocks_orca(seed: u64) -> Orca {
        Orca {
            perturb: 1e-4,
            seed,
            ..Orca::new(15.0, 10, 5.0, 5.0, 1.0)
        }
    }

    #[test]
    fn three_robots_wedged_under_a_square_with_crossing_goals_stay_jammed_as_in_rvo2() {
        // Blocks' perturbation seed 7 ends with this jam under square 4
        // (BENCHMARKS.md, "Blocks"): two robots touching the bottom wall
        // head on, one wanting to pass right (goal up-right), one left
        // (goal up-left), and a third wedged below them between both,
        // wanting up-left. Each preferred velocity lies in the cone of its
        // constraints' normals (wall, and the touching neighbours' ORCA
        // lines through the current velocity), so the programs stay
        // feasible and the closest admissible velocity is (nearly) zero;
        // RVO2 fed the same three discs (f32 and f64) is still jammed
        // after 20,000 steps. ORCA is local: nothing makes one of them back
        // off.
        let mut sim = Sim::new(0.25, 1);
        sim.walls = blocks_square_4();
        let h = (4.01f64 * 4.01 - 2.005 * 2.005).sqrt();
        let robots = [
            (Vec2::new(-26.51, -42.001), Vec2::new(75.0, 75.0)),
            (Vec2::new(-22.5, -42.001), Vec2::new(-75.0, 75.0)),
            (Vec2::new(-24.505, -42.001 - h), Vec2::new(-75.0, 75.0)),
        ];
        for (start, goal) in robots {
            sim.add_robot(
                Box::new(blocks_orca(7)),
                start,
                goal,
                2.0,
                1.0,
                0.0,
                2.0,
                1e12,
            );
        }
        // 500 s, in which a free robot would cover its 130-160 to the goal
        // three times over at its preferred speed of 1.
        for _ in 0..2000 {
            sim.step();
            for i in 0..3 {
                assert!(!infeasible(&sim, i), "robot {i}: infeasible program");
            }
        }
        for (i, (start, goal)) in robots.iter().enumerate() {
            let p = sim.robots[i].state.position;
            assert!((p - start).norm() < 1.0, "robot {i} got loose: {p:?}");
            assert!((p - goal).norm() > 100.0);
            assert!(sim.robots[i].state.velocity.norm() < 0.01);
        }
        for i in 0..3 {
            for j in i + 1..3 {
                assert!(gap(&sim, i, j) >= -TOUCH, "{i} and {j} overlap");
            }
        }
    }

    /// RVO2's Blocks example (examples/Blocks.cc: 100 agents, four squares,
    /// its parameters and preferred-velocity perturbation) for the
    /// perturbation seeds in `BLOCKS_SEEDS` (default 1..=10); prints each
    /// makespan in steps, as BENCHMARKS.md compares with RVO2's (run with
    /// `BLOCKS_SEEDS=1-10 cargo test --release -p mrsim-planners rvo2_blocks -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn rvo2_blocks_reports_its_makespan_for_each_perturbation_seed() {
        let (first, last) = std::env::var("BLOCKS_SEEDS")
            .ok()
            .and_then(|s| {
                let (a, b) = s.split_once('-').unwrap_or((&s, &s));
                Some((a.trim().parse::<u64>().ok()?, b.trim().parse::<u64>().ok()?))
            })
            .unwrap_or((1, 10));
        let polygons = [
            [(-10.0, 40.0), (-40.0, 40.0), (-40.0, 10.0), (-10.0, 10.0)],
            [(10.0, 40.0), (10.0, 10.0), (40.0, 10.0), (40.0, 40.0)],
            [(10.0, -40.0), (40.0, -40.0), (40.0, -10.0), (10.0, -10.0)],
            [
                (-10.0, -40.0),
                (-10.0, -10.0),
                (-40.0, -10.0),
                (-40.0, -40.0),
            ],
        ];
        for seed in first..=last {
            let mut sim = Sim::new(0.25, 1);
            for p in polygons {
                sim.walls.extend((0..4).map(|k| seg(p[k], p[(k + 1) % 4])));
            }
            let mut goals = Vec::new();
            // Blocks.cc's order: per grid cell, one agent of each group.
            for i in 0..5 {
                for j in 0..5 {
                    let (x, y) = (55.0 + 10.0 * i as f64, 55.0 + 10.0 * j as f64);
                    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                        let goal = Vec2::new(-75.0 * sx, -75.0 * sy);
                        goals.push(goal);
                        let start = Vec2::new(x * sx, y * sy);
                        let orca = Box::new(blocks_orca(seed));
                        sim.add_robot(orca, start, goal, 2.0, 1.0, 0.0, 2.0, 1e12);
                    }
                }
            }
            // Blocks.cc's reachedGoal: every agent within 20 of its goal.
            let done = |sim: &Sim| {
                sim.robots
                    .iter()
                    .zip(&goals)
                    .all(|(r, g)| (r.state.position - g).norm_squared() <= 400.0)
            };
            let (mut min_gap, mut steps) = (f64::INFINITY, 0);
            while steps < 20_000 && !done(&sim) {
                sim.step();
                steps += 1;
                for i in 0..sim.robots.len() {
                    for j in i + 1..sim.robots.len() {
                        min_gap = min_gap.min(gap(&sim, i, j));
                    }
                }
            }
            let out: Vec<String> = sim
                .robots
                .iter()
                .zip(&goals)
                .enumerate()
                .filter(|(_, (r, g))| (r.state.position - *g).norm_squared() > 400.0)
                .map(|(i, (r, _))| {
                    let p = r.state.position;
                    format!("a{i} at ({:.2}, {:.2})", p.x, p.y)
                })
                .collect();
            println!(
                "blocks seed {seed}: {} steps, min gap {min_gap:.4}{}",
                if out.is_empty() {
                    steps.to_string()
                } else {
                    format!("> {steps}")
                },
                if out.is_empty() {
                    String::new()
                } else {
                    format!(", not in: {}", out.join(", "))
                }
            );
        }
    }

    /// RVO2's Circle example at full size, with its exact symmetric start;
    /// prints the makespan to compare with RVO2's (run with
    /// `cargo test --release -p mrsim-planners rvo2_circle -- --ignored --nocapture`).
    #[test]
    #[ignore]
    fn rvo2_circle_of_250_reaches_goals_and_reports_its_makespan() {
        let n = 250;
        let (mut sim, goals) = circle(n, 200.0, 0.0, 10);
        let mut min_gap = f64::INFINITY;
        let mut reached = None;
        let mut planning = std::time::Duration::ZERO;
        for tick in 1..=20_000u64 {
            let start = std::time::Instant::now();
            sim.step();
            planning += start.elapsed();
            for i in 0..n {
                for j in i + 1..n {
                    min_gap = min_gap.min(gap(&sim, i, j));
                }
            }
            if all_reached(&sim, &goals) {
                reached = Some(tick);
                break;
            }
        }
        let steps = reached.unwrap_or(20_000);
        println!(
            "circle-250: makespan {reached:?} ticks = {:?} s, min gap {min_gap:.4}, \
             {:.2} us per agent per step (testkit step: snapshot copy + plan + integrate)",
            reached.map(|t| t as f64 * 0.25),
            planning.as_secs_f64() * 1e6 / (steps as f64 * n as f64)
        );
        assert!(reached.is_some(), "not all reached their goals");
    }
}
