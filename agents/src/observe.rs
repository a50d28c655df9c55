//! From a snapshot to a planner's observation: the robot's own state, and
//! the other bodies it can sense (within `sensing_range`, measured surface
//! to surface, and within `field_of_view_deg` centred on its heading: the
//! direction of its velocity, or towards its goal while it stands still).
//!
//! Then, in this order, as a camera would give them (Zhu & Loh section 2):
//! the sensed positions get Gaussian noise of standard deviation
//! `position_noise` per axis (drawn from the robot's own stream of the
//! scenario's seed, so runs repeat), and with `velocity_source =
//! "differenced"` every sensed body's velocity and acceleration are
//! replaced by differences of its observed (noisy) positions, eqs 2.9-2.12
//! ([`VelocityEstimator`]). With `"truth"` the velocity is the snapshot's and
//! the acceleration zero.
//!
//! Each sensed body comes with its heading (the snapshot's) and its shape,
//! from the scenario by body id ([`shapes_of`]): a disc, a rectangle or a
//! convex polygon in its body frame; its `radius` is the disc around it
//! (a polygon's circumscribed radius), and the sensing range is measured to
//! that disc, so a polygon is sensed a little early rather than late.
//!
//! With a finite `sensing_range` the planner gets only the walls near it:
//! every chain of walls (segments joined end to end, such as a room's
//! outline or the arena) with a segment within the sensing range plus the
//! robot's radius of its centre, whole and in the run's order, so a
//! planner that joins walls into polygons (orca) sees the same polygons
//! ([`NearWalls`]). With an infinite range (the default) it gets them all.
//!
//! A unicycle robot's heading is its body's (the snapshot's `heading`), and
//! the observation says so ([`SelfState::heading`], `kinematics`). A robot
//! with a `sensor` gets a laser scan each tick ([`mrsim_lidar`]'s
//! [`Scanner::scan_robot`], the function the world's scan.csv calls too, so
//! the file repeats exactly what the planner saw): cast from its centre
//! along its heading (a holonomic robot's frame is the world's: heading 0)
//! against every other body of the snapshot (true positions and shapes at
//! their headings, whatever the sensing range) and every wall, with noise
//! from a stream per robot and tick.

use mrsim_lidar::{Scanner, Walls};
use mrsim_planners::estimate::VelocityEstimator;
use mrsim_planners::lidar::LaserScan;
use mrsim_planners::{
    BodyKind, DesignatedPath, Kinematics, Observation, Segment, SelfState, Sensed, Shape, Vec2,
};
use mrsim_proto::{BodyState, SnapshotHeader, body_kind};
use mrsim_scenario::rng::Rng;
use mrsim_scenario::{RobotSpec, Scenario, VelocitySource, WorldConfig};
use std::sync::Arc;

/// Turns snapshots into observations for one robot; keeps the buffers.
pub struct Observer {
    me: usize,
    dt: f64,
    others: Vec<Sensed>,
    /// Differenced velocities (eqs 2.9-2.12), if the robot asks for them.
    estimator: Option<VelocityEstimator>,
    /// Standard deviation of the position noise (0 = none).
    noise: f64,
    rng: Rng,
    seed: u64,
    /// The last scan, if the robot has a lidar.
    scan: LaserScan,
    /// The run's walls (fixed for the run).
    walls: Arc<[Segment]>,
    /// Every body's shape by id ([`shapes_of`]; empty: all discs).
    shapes: Arc<[Shape]>,
    /// The scanner among `walls`, built at the first scan.
    scanner: Option<Scanner>,
    /// The box of `walls` and, once the robot is out of reach of some
    /// wall, their index; built at the first observation with a finite
    /// sensing range.
    near_walls: Option<WallsBox>,
}

/// A run's walls as planners see them: its `[[wall]]`s (a map's traced
/// outlines among them) and the arena's four sides.
pub fn walls_of(
    walls: &[mrsim_scenario::WallSpec],
    arena: Option<mrsim_scenario::Arena>,
) -> Arc<[Segment]> {
    mrsim_scenario::walls_and_arena(walls, arena)
        .iter()
        .map(|w| Segment {
            a: Vec2::new(w[0][0], w[0][1]),
            b: Vec2::new(w[1][0], w[1][1]),
        })
        .collect()
}

/// Every body's shape by id (robots, then obstacles), shared by the
/// observers of a process; empty when every body is a disc, whose shape
/// is then the snapshot's radius.
pub fn shapes_of(scenario: &Scenario) -> Arc<[Shape]> {
    if scenario.has_shapes() {
        scenario.body_shapes().into()
    } else {
        Arc::new([])
    }
}

/// The box of a run's walls, and their [`NearWalls`] index once a robot
/// is out of reach of some wall (never with the default sensing range,
/// 1e9, so most runs build none).
struct WallsBox {
    lo: Vec2,
    hi: Vec2,
    index: Option<NearWalls>,
}

impl WallsBox {
    fn new(walls: &[Segment]) -> Self {
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        for p in walls.iter().flat_map(|w| [w.a, w.b]) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        Self {
            lo,
            hi,
            index: None,
        }
    }

    /// True if every wall is within `reach` of `p` (the box's farthest
    /// corner is).
    fn all_within(&self, p: Vec2, reach: f64) -> bool {
        let far = (p - self.lo).abs().sup(&(p - self.hi).abs());
        far.norm() <= reach
    }
}

/// The chains of a run's walls and a grid of their segments, built once,
/// to give a robot the chains within a distance of it each tick.
struct NearWalls {
    /// Chain of each segment.
    chain_of: Vec<u32>,
    /// Segments of each chain, ascending.
    chains: Vec<Vec<u32>>,
    /// A grid over the walls' box: cell `(i, j)` holds the segments whose
    /// box meets it, `cells[start[c]..start[c + 1]]`.
    lo: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    start: Vec<u32>,
    cells: Vec<u32>,
    /// The tick stamp of each chain taken (`stamp`: this query's).
    taken: Vec<u32>,
    stamp: u32,
    picked: Vec<u32>,
    out: Vec<Segment>,
}

impl NearWalls {
    /// Cells across the grid's longer side at most.
    const MAX_CELLS: f64 = 64.0;

    /// The index of `walls`, for queries of about `reach`.
    fn new(walls: &[Segment], reach: f64) -> Self {
        // Chains: segments sharing an end (bit for bit, as traced).
        let mut parent: Vec<u32> = (0..walls.len() as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                let up = parent[parent[i as usize] as usize];
                parent[i as usize] = up;
                i = up;
            }
            i
        }
        let mut ends: std::collections::HashMap<(u64, u64), u32> = Default::default();
        for (k, w) in walls.iter().enumerate() {
            for p in [w.a, w.b] {
                let other = *ends
                    .entry((p.x.to_bits(), p.y.to_bits()))
                    .or_insert(k as u32);
                let (a, b) = (root(&mut parent, other), root(&mut parent, k as u32));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let mut chain_id = vec![u32::MAX; walls.len()];
        let mut chains: Vec<Vec<u32>> = Vec::new();
        let mut chain_of = Vec::with_capacity(walls.len());
        for k in 0..walls.len() as u32 {
            let r = root(&mut parent, k) as usize;
            if chain_id[r] == u32::MAX {
                chain_id[r] = chains.len() as u32;
                chains.push(Vec::new());
            }
            chain_of.push(chain_id[r]);
            chains[chain_id[r] as usize].push(k);
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for w in walls {
            for p in [w.a, w.b] {
                lo = [lo[0].min(p.x), lo[1].min(p.y)];
                hi = [hi[0].max(p.x), hi[1].max(p.y)];
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        // No more cells across than about twice the root of the segments:
        // the grid's memory follows the walls (every robot out of reach of
        // some wall keeps an index: four arena sides must not cost each of
        // 100,000 robots a grid of 64 x 64 cells).
        let across = ((walls.len() as f64).sqrt().ceil() * 2.0).clamp(1.0, Self::MAX_CELLS);
        let cell = reach.max(extent / across).max(1e-9);
        let dims = [
            ((hi[0] - lo[0]) / cell) as usize + 1,
            ((hi[1] - lo[1]) / cell) as usize + 1,
        ];
        let at = |v: f64, k: usize| (((v - lo[k]) / cell).max(0.0) as usize).min(dims[k] - 1);
        let boxes: Vec<[usize; 4]> = walls
            .iter()
            .map(|w| {
                let (x0, x1) = (w.a.x.min(w.b.x), w.a.x.max(w.b.x));
                let (y0, y1) = (w.a.y.min(w.b.y), w.a.y.max(w.b.y));
                [at(x0, 0), at(x1, 0), at(y0, 1), at(y1, 1)]
            })
            .collect();
        let mut count = vec![0u32; dims[0] * dims[1] + 1];
        for b in &boxes {
            for j in b[2]..=b[3] {
                for i in b[0]..=b[1] {
                    count[j * dims[0] + i + 1] += 1;
                }
            }
        }
        for c in 1..count.len() {
            count[c] += count[c - 1];
        }
        let start = count.clone();
        let mut cells = vec![0u32; *count.last().unwrap_or(&0) as usize];
        for (k, b) in boxes.iter().enumerate() {
            for j in b[2]..=b[3] {
                for i in b[0]..=b[1] {
                    let c = j * dims[0] + i;
                    cells[count[c] as usize] = k as u32;
                    count[c] += 1;
                }
            }
        }
        Self {
            taken: vec![0; chains.len()],
            chain_of,
            chains,
            lo,
            cell,
            dims,
            start,
            cells,
            stamp: 0,
            picked: Vec::new(),
            out: Vec::new(),
        }
    }

    /// The chains of `walls` (the ones this index was built for) with a
    /// segment within `reach` of `p`; `None` if that is all of them.
    fn near(&mut self, walls: &[Segment], p: Vec2, reach: f64) -> Option<&[Segment]> {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.taken.fill(0);
            self.stamp = 1;
        }
        let mut chains = 0;
        // The cell of `v` along axis `k`, clamped to the grid: the cast
        // truncates, which is the floor for what is above the grid's
        // start, and what is below it (or NaN) is cell 0 (no call to the
        // C library's `floor`).
        let at = |v: f64, k: usize| {
            let c = (v - self.lo[k]) / self.cell;
            if c > 0.0 {
                c.min((self.dims[k] - 1) as f64) as usize
            } else {
                0
            }
        };
        let (i0, i1) = (at(p.x - reach, 0), at(p.x + reach, 0));
        let (j0, j1) = (at(p.y - reach, 1), at(p.y + reach, 1));
        for j in j0..=j1 {
            for i in i0..=i1 {
                let c = j * self.dims[0] + i;
                for &k in &self.cells[self.start[c] as usize..self.start[c + 1] as usize] {
                    let chain = self.chain_of[k as usize] as usize;
                    if self.taken[chain] != self.stamp
                        && (walls[k as usize].closest_point(p) - p).norm() <= reach
                    {
                        self.taken[chain] = self.stamp;
                        chains += 1;
                    }
                }
            }
        }
        if chains == self.chains.len() {
            return None;
        }
        self.picked.clear();
        for (c, segments) in self.chains.iter().enumerate() {
            if self.taken[c] == self.stamp {
                self.picked.extend_from_slice(segments);
            }
        }
        self.picked.sort_unstable();
        self.out.clear();
        self.out
            .extend(self.picked.iter().map(|&k| walls[k as usize]));
        Some(&self.out)
    }
}

/// What one robot's scan of a snapshot's bodies needs, the same for every
/// body: which bodies it senses ([`Scan::sense_all`]).
struct Scan<'s> {
    me: usize,
    /// Every body's shape by id (empty: all discs).
    shapes: &'s [Shape],
    position: Vec2,
    sensing_range: f64,
    radius: f64,
    /// The heading and the cosine of half the field of view, when it is
    /// narrower than a full turn.
    fov: Option<(Vec2, f64)>,
}

impl Scan<'_> {
    /// The reach of a body of radius zero, and the factor of a body's
    /// radius, for the squared-distance pre-test of [`Self::near_enough`]:
    /// `(range + radius + r) * (1 + 1e-9) + 1e-9` written as
    /// `base + r * scale`.
    fn reach_terms(&self) -> (f64, f64) {
        let scale = 1.0 + 1e-9;
        ((self.sensing_range + self.radius) * scale + 1e-9, scale)
    }

    /// False if `b` is clearly out of range (centre distance squared
    /// well beyond the range plus both radii), without a square root.
    /// Bodies near the limit, and any with a non-finite position, pass
    /// and go through the exact test of [`Self::accept`], so what is
    /// sensed does not depend on this test.
    #[inline(always)]
    #[expect(
        clippy::neg_cmp_op_on_partial_ord,
        reason = "a NaN distance must pass, to the exact test"
    )]
    fn near_enough(&self, b: &BodyState, (base, scale): (f64, f64)) -> bool {
        let (dx, dy) = (
            b.position[0] - self.position.x,
            b.position[1] - self.position.y,
        );
        let reach = base + b.radius * scale;
        !(dx * dx + dy * dy > reach * reach)
    }

    /// Appends `b` to `out` if it is not the robot itself and is within
    /// the sensing range, surface to surface, and the field of view.
    #[inline(always)]
    fn accept(&self, b: &BodyState, out: &mut Vec<Sensed>) {
        if b.id as usize == self.me {
            return;
        }
        let p = Vec2::new(b.position[0], b.position[1]);
        let d = p - self.position;
        let dist = d.norm();
        // Sensing range, surface to surface.
        if dist - b.radius - self.radius > self.sensing_range {
            return;
        }
        // Field of view around the heading (360 degrees sees all).
        if let Some((heading, cos_half)) = self.fov
            && dist > 1e-12
            && d.dot(&heading) / dist < cos_half
        {
            return;
        }
        out.push(Sensed {
            id: b.id,
            kind: match b.kind {
                body_kind::ROBOT => BodyKind::Robot,
                body_kind::PERSON => BodyKind::Person,
                _ => BodyKind::Obstacle,
            },
            position: p,
            velocity: Vec2::new(b.velocity[0], b.velocity[1]),
            acceleration: Vec2::zeros(),
            radius: b.radius,
            heading: b.heading,
            shape: match self.shapes.get(b.id as usize) {
                Some(s @ Shape::Polygon(_)) => *s,
                _ => Shape::disc(b.radius),
            },
        });
    }

    /// Appends to `out` every body of `bodies` (but the robot itself)
    /// within the sensing range, surface to surface, and the field of
    /// view, in the bodies' order.
    ///
    /// Most bodies are far: the pre-test runs over 64 bodies at a time
    /// without a branch, into a mask, and only the bodies it lets through
    /// are looked at again (in order) for the exact test.
    fn sense_all(&self, bodies: &[BodyState], out: &mut Vec<Sensed>) {
        let terms = self.reach_terms();
        for chunk in bodies.chunks(64) {
            let mut mask = 0u64;
            for (k, b) in chunk.iter().enumerate() {
                mask |= u64::from(self.near_enough(b, terms)) << k;
            }
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                self.accept(&chunk[k], out);
            }
        }
    }

    /// [`Self::sense_all`] over the bodies of `bodies` at the indices
    /// `near` (ascending), those out of the slice skipped.
    fn sense_among(&self, bodies: &[BodyState], near: &[u32], out: &mut Vec<Sensed>) {
        let terms = self.reach_terms();
        for b in near.iter().filter_map(|&k| bodies.get(k as usize)) {
            if self.near_enough(b, terms) {
                self.accept(b, out);
            }
        }
    }
}

impl Observer {
    /// An observer for robot `me` of `scenario`, among its walls and
    /// arena ([`walls_of`]).
    pub fn new(scenario: &Scenario, me: usize) -> Self {
        Self::for_robot(
            &scenario.world,
            scenario.robots.get(me),
            me,
            scenario.body_count(),
            walls_of(&scenario.walls, scenario.world.arena),
            shapes_of(scenario),
        )
    }

    /// An observer for robot `me` (its entry `spec`, if known) of a run
    /// with `world` and `bodies` bodies in each snapshot, among `walls`,
    /// the bodies' shapes `shapes` by id ([`shapes_of`]: a body beyond its
    /// end is the disc of its radius).
    pub fn for_robot(
        world: &WorldConfig,
        spec: Option<&RobotSpec>,
        me: usize,
        bodies: usize,
        walls: Arc<[Segment]>,
        shapes: Arc<[Shape]>,
    ) -> Self {
        Self {
            me,
            dt: world.dt,
            // Grown to what the robot senses, not sized for every body: a
            // run of n robots would hold n such buffers.
            others: Vec::with_capacity(bodies.min(16)),
            estimator: spec
                .is_some_and(|r| r.velocity_source == VelocitySource::Differenced)
                .then(VelocityEstimator::new),
            noise: spec.map_or(0.0, |r| r.position_noise),
            rng: Rng::stream(world.seed, "position-noise", me as u64),
            seed: world.seed,
            scan: LaserScan::default(),
            walls,
            shapes,
            scanner: None,
            near_walls: None,
        }
    }

    /// The run's walls, all of them (an observation holds those within
    /// the sensing range).
    pub fn walls(&self) -> &Arc<[Segment]> {
        &self.walls
    }

    /// The observation of this tick.
    pub fn observe<'a>(
        &'a mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        spec: &RobotSpec,
        path: Option<&'a DesignatedPath>,
    ) -> Observation<'a> {
        self.observe_among(header, bodies, None, spec, path)
    }

    /// [`Self::observe`], looking only at the bodies of indices `near`
    /// (ascending, so the sensed bodies come in the same order) when given:
    /// a caller that knows which bodies can be within range (a grid built
    /// once per snapshot for many robots) saves the scan of all of them.
    /// `near` must hold every body within the sensing range.
    pub fn observe_among<'a>(
        &'a mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
        spec: &RobotSpec,
        path: Option<&'a DesignatedPath>,
    ) -> Observation<'a> {
        let walls: &[Segment] = &self.walls;
        let s = &bodies[self.me];
        let position = Vec2::new(s.position[0], s.position[1]);
        let velocity = Vec2::new(s.velocity[0], s.velocity[1]);
        let goal = Vec2::new(spec.goal[0], spec.goal[1]);
        let heading = if spec.turns() {
            Vec2::new(s.heading.cos(), s.heading.sin())
        } else if velocity.norm() > 1e-9 {
            velocity.normalize()
        } else if (goal - position).norm() > 1e-12 {
            (goal - position).normalize()
        } else {
            Vec2::new(1.0, 0.0)
        };
        // The field of view's test, only when it is narrower than a full
        // turn (the cosine is not computed at all otherwise).
        let fov = (spec.field_of_view_deg < 360.0).then(|| {
            let half_fov = (spec.field_of_view_deg / 2.0).to_radians();
            (heading, half_fov.cos())
        });
        let scan = Scan {
            me: self.me,
            shapes: &self.shapes,
            position,
            sensing_range: spec.sensing_range,
            radius: spec.radius,
            fov,
        };
        self.others.clear();
        match near {
            None => scan.sense_all(bodies, &mut self.others),
            Some(near) => scan.sense_among(bodies, near, &mut self.others),
        }
        if self.noise > 0.0 {
            for o in &mut self.others {
                o.position.x += self.noise * self.rng.gaussian();
                o.position.y += self.noise * self.rng.gaussian();
            }
        }
        if let Some(e) = &mut self.estimator {
            e.apply(header.sim_time, &mut self.others);
        }
        let scanned = spec.sensor.is_some() && {
            let scanner = self
                .scanner
                .get_or_insert_with(|| Scanner::new(Walls::from_segments(walls)));
            scanner.scan_robot(
                &mut self.scan,
                self.seed,
                header.tick,
                self.me,
                spec,
                bodies,
                &self.shapes,
            )
        };
        let reach = spec.sensing_range + spec.radius;
        let near_walls = if reach.is_finite() && !walls.is_empty() {
            let b = self.near_walls.get_or_insert_with(|| WallsBox::new(walls));
            if b.all_within(position, reach) {
                walls
            } else {
                b.index
                    .get_or_insert_with(|| NearWalls::new(walls, reach))
                    .near(walls, position, reach)
                    .unwrap_or(walls)
            }
        } else {
            walls
        };
        Observation {
            tick: header.tick,
            time: header.sim_time,
            dt: self.dt,
            me: SelfState {
                id: self.me as u32,
                position,
                velocity,
                radius: spec.radius,
                // The shapes already read (a polygon checked once, not
                // every tick); all discs: the disc of its radius.
                shape: self
                    .shapes
                    .get(self.me)
                    .copied()
                    .unwrap_or(Shape::disc(spec.radius)),
                mass: spec.mass,
                damping: spec.damping,
                max_speed: spec.max_speed,
                max_accel: spec.max_accel,
                heading: s.heading,
                angular_velocity: s.angular_velocity,
                steering: s.steering,
                kinematics: kinematics_of(spec),
            },
            goal,
            goal_tolerance: spec.goal_tolerance,
            goal_hold_ticks: spec.goal_hold_ticks,
            others: &self.others,
            walls: near_walls,
            path,
            scan: scanned.then_some(&self.scan),
        }
    }
}

/// The planners' motion model of robot `spec`, its limits included.
pub fn kinematics_of(spec: &RobotSpec) -> Kinematics {
    match (spec.kinematics, spec.ackermann) {
        (mrsim_scenario::Kinematics::Unicycle, _) => Kinematics::Unicycle {
            max_angular_speed: spec.max_angular_speed,
            max_angular_accel: spec.max_angular_accel,
        },
        (mrsim_scenario::Kinematics::Ackermann, Some(a)) => Kinematics::Ackermann {
            wheelbase: a.wheelbase,
            max_steering: a.max_steering,
            max_steering_rate: a.max_steering_rate,
            max_reverse_speed: a.max_reverse_speed,
        },
        _ => Kinematics::Holonomic,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The square of side `s` at `(x, y)` (lower left), as four walls.
    fn square(x: f64, y: f64, s: f64) -> Vec<Segment> {
        let c = [(x, y), (x + s, y), (x + s, y + s), (x, y + s)];
        (0..4)
            .map(|k| Segment {
                a: Vec2::new(c[k].0, c[k].1),
                b: Vec2::new(c[(k + 1) % 4].0, c[(k + 1) % 4].1),
            })
            .collect()
    }

    #[test]
    fn a_robot_gets_the_whole_outlines_within_its_reach_and_no_others() {
        // Pillars at x = 0, 10, 20, ..., 90 and one long wall far below.
        let mut walls: Vec<Segment> = (0..10)
            .flat_map(|k| square(10.0 * k as f64, 0.0, 1.0))
            .collect();
        walls.push(Segment {
            a: Vec2::new(0.0, -50.0),
            b: Vec2::new(100.0, -50.0),
        });
        let mut near = NearWalls::new(&walls, 2.5);
        // From (12.5, 0.5): the pillar at 10 (its right side 1.5 away),
        // whole, all four sides; nothing else within 2.5.
        let got = near
            .near(&walls, Vec2::new(12.5, 0.5), 2.5)
            .expect("a few")
            .to_vec();
        assert_eq!(got, walls[4..8].to_vec());
        // Between two pillars: both, in the walls' order.
        let got = near
            .near(&walls, Vec2::new(25.5, 0.5), 5.0)
            .expect("a few")
            .to_vec();
        assert_eq!(got, walls[8..16].to_vec());
        // Far from everything: nothing.
        assert_eq!(near.near(&walls, Vec2::new(50.0, 30.0), 2.5), Some(&[][..]));
        // Within reach of all: `None`, the caller gives them all.
        assert_eq!(near.near(&walls, Vec2::new(50.0, 0.0), 500.0), None);
    }

    #[test]
    fn every_wall_within_reach_is_given_whatever_the_grid_cells() {
        // Pseudo-random separate segments: the index gives exactly those
        // within reach (each its own chain), in order.
        let mut x: u64 = 3;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 * 100.0
        };
        let walls: Vec<Segment> = (0..300)
            .map(|_| {
                let a = Vec2::new(next(), next());
                Segment {
                    a,
                    b: a + Vec2::new(next() / 10.0 - 5.0, next() / 10.0 - 5.0),
                }
            })
            .collect();
        let mut near = NearWalls::new(&walls, 4.0);
        for _ in 0..50 {
            let p = Vec2::new(next(), next());
            let want: Vec<Segment> = walls
                .iter()
                .filter(|w| (w.closest_point(p) - p).norm() <= 4.0)
                .copied()
                .collect();
            let got = near
                .near(&walls, p, 4.0)
                .map_or(walls.clone(), <[_]>::to_vec);
            assert_eq!(got, want, "from {p:?}");
        }
    }
}
