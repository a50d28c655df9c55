//! The laser scanner: what a planner gets in
//! [`mrsim_planners::Observation::scan`] and what the world writes to
//! scan.csv, both from one function ([`Scanner::scan_robot`]) so they agree
//! to the bit.
//!
//! The ranges come from rapier's geometry (its re-exported parry2d): the
//! static walls (the arena, `[[wall]]` segments, a map's traced outlines)
//! are one [`Polyline`] whose bounding-volume hierarchy is built once per
//! scanner ([`Walls::new`]); the other bodies of each scan (robots,
//! obstacles: [`Body`]) are cast as they are: a disc as a ball
//! ([`ray_toi_with_ball`]), a rectangle or convex polygon as parry's
//! [`ConvexPolygon`] of its corners at the body's heading (GJK's ray cast),
//! through a [`Bvh`] of their boxes when there are many. Each beam is one
//! ray cast against the walls, then against the bodies nearer than the
//! wall it hit. parry works in f32 here (rapier2d's `Real`): the bodies are
//! cast in coordinates relative to the scanner's origin, so a range is
//! exact to f32 rounding of the shapes near the robot; the walls in world
//! coordinates (an error of about 1e-7 of the map's coordinates).
//!
//! The scan keeps ROS `sensor_msgs/LaserScan`'s meanings (see
//! [`mrsim_planners::lidar`]): `ranges[k]` is the distance from the robot's
//! centre along beam `k` to the first surface, `+inf` when nothing lies
//! within `range_max`; a ray starting inside a body reads 0. Noise, when
//! asked for, is added to each hit's range (Gaussian, standard deviation
//! `noise`, drawn from [`Rng::lidar`], a stream per robot and tick, once
//! per hit beam in beam order) and clamped to [0, range_max]; misses stay
//! `+inf`.
//!
//! ARCHITECTURE.md ("Lidar") says why the agents compute the scans and not
//! the world, and BENCHMARKS.md what they cost.

#![warn(missing_docs)]

use mrsim_planners::lidar::{LaserScan, LidarConfig};
use mrsim_planners::{Pose, Segment, Shape, Vec2};
use mrsim_proto::BodyState;
use mrsim_scenario::rng::Rng;
use mrsim_scenario::{Lidar, RobotSpec};
use rapier2d::parry::bounding_volume::Aabb;
use rapier2d::parry::math::{Real, Vector};
use rapier2d::parry::partitioning::{Bvh, BvhBuildStrategy, TraversalAction};
use rapier2d::parry::query::details::ray_toi_with_ball;
use rapier2d::parry::query::{Ray, RayCast};
use rapier2d::parry::shape::{ConvexPolygon, Polyline};

/// Above this many bodies within range, a scan casts its rays through a
/// [`Bvh`] of the bodies' boxes instead of against each body.
const BODIES_BRUTE_FORCE: usize = 24;

/// A body a scan casts its rays against: where it is, its heading and its
/// shape (body frame, x along the heading).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Position, scenario units.
    pub position: Vec2,
    /// Heading, rad counter-clockwise from +x (a disc's does not matter).
    pub heading: f64,
    /// Disc, rectangle or convex polygon.
    pub shape: Shape,
}

impl Body {
    /// The disc of `radius` at `position`.
    pub fn disc(position: Vec2, radius: f64) -> Self {
        Self {
            position,
            heading: 0.0,
            shape: Shape::disc(radius),
        }
    }
}

impl From<(Vec2, f64)> for Body {
    /// A disc: (centre, radius).
    fn from((position, radius): (Vec2, f64)) -> Self {
        Self::disc(position, radius)
    }
}

/// A body of one scan, relative to the scanner's origin.
#[derive(Debug, Clone)]
enum Target {
    /// Centre and radius.
    Disc(Vector, Real),
    /// The corners at the body's pose.
    Polygon(ConvexPolygon),
}

impl Target {
    /// The body `b`, seen from `origin`, if some of it may lie within
    /// `range` of it (by the disc around it).
    fn of(b: &Body, origin: Vec2, range: f64) -> Option<Self> {
        let d = b.position - origin;
        let r = b.shape.circumradius();
        if d.norm() - r > range {
            return None;
        }
        let disc = Target::Disc(Vector::new(d.x as Real, d.y as Real), r as Real);
        let Some(placed) = b.shape.placed(Pose::new([d.x, d.y], b.heading)) else {
            return Some(disc);
        };
        let points = placed
            .points()
            .iter()
            .map(|p| Vector::new(p[0] as Real, p[1] as Real))
            .collect();
        // The corners as given (a validated convex polygon, kept whole: the
        // simplifying constructor would drop corners turning by less than
        // about a degree); corners that f32 makes one (a body far smaller
        // than its distance) leave the disc around it.
        Some(ConvexPolygon::from_convex_polyline_unmodified(points).map_or(disc, Target::Polygon))
    }

    fn aabb(&self) -> Aabb {
        match self {
            Target::Disc(c, r) => Aabb::new(*c - Vector::splat(*r), *c + Vector::splat(*r)),
            Target::Polygon(p) => p.local_aabb(),
        }
    }

    /// The distance along `ray` (from the scanner's origin) to the body,
    /// if it is met within `max` (0 from inside).
    fn cast(&self, ray: &Ray, max: Real) -> Option<Real> {
        match self {
            Target::Disc(c, r) => ray_toi_with_ball(*c, *r, ray, true).1,
            Target::Polygon(p) => p.cast_local_ray(ray, max, true),
        }
        .filter(|t| *t <= max)
    }
}

/// The static walls of a run, as one ray-castable shape built once.
#[derive(Clone)]
pub struct Walls {
    /// `None` when there are no walls.
    shape: Option<Polyline>,
    count: usize,
}

impl std::fmt::Debug for Walls {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walls").field("count", &self.count).finish()
    }
}

impl Walls {
    /// The walls `segments` (ends in scenario units), their hierarchy built.
    pub fn new(segments: impl IntoIterator<Item = [[f64; 2]; 2]>) -> Self {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for [a, b] in segments {
            let i = vertices.len() as u32;
            vertices.push(Vector::new(a[0] as Real, a[1] as Real));
            vertices.push(Vector::new(b[0] as Real, b[1] as Real));
            indices.push([i, i + 1]);
        }
        let count = indices.len();
        Self {
            shape: (count > 0).then(|| Polyline::new(vertices, Some(indices))),
            count,
        }
    }

    /// [`Walls::new`] from the planners' segments.
    pub fn from_segments(segments: &[Segment]) -> Self {
        Self::new(segments.iter().map(|s| [[s.a.x, s.a.y], [s.b.x, s.b.y]]))
    }

    /// Number of wall segments.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True if there are no walls.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// The planners' scanner configuration of a robot's `sensor`.
pub fn config_of(l: &Lidar) -> LidarConfig {
    LidarConfig {
        beams: l.beams,
        fov: l.fov_deg.to_radians(),
        range: l.range,
        noise: l.noise,
    }
}

/// A scanner among fixed walls; keeps the per-scan buffers.
#[derive(Debug, Clone)]
pub struct Scanner {
    walls: Walls,
    /// The bodies within range of this scan, relative to the scanner's
    /// origin.
    targets: Vec<Target>,
}

impl Scanner {
    /// A scanner among `walls`.
    pub fn new(walls: Walls) -> Self {
        Self {
            walls,
            targets: Vec::new(),
        }
    }

    /// The walls this scanner casts against.
    pub fn walls(&self) -> &Walls {
        &self.walls
    }

    /// The scan of robot `me` (entry `spec`) among `bodies` (every body of
    /// the snapshot, the robot itself skipped, each at its heading) and the
    /// walls, into `out`, with the noise of robot `me` at `tick` under
    /// `seed`; `false` (and `out` untouched) if the robot has no sensor or
    /// is not in `bodies`. Body `k`'s shape is `shapes[k]`
    /// ([`mrsim_scenario::Scenario::body_shapes`]); a body past the end of
    /// `shapes` (every body, when it is empty) is the disc of its radius.
    /// The agent's observation and the world's scan.csv both call this.
    #[allow(clippy::too_many_arguments)]
    pub fn scan_robot(
        &mut self,
        out: &mut LaserScan,
        seed: u64,
        tick: u64,
        me: usize,
        spec: &RobotSpec,
        bodies: &[BodyState],
        shapes: &[Shape],
    ) -> bool {
        let (Some(sensor), Some(s)) = (&spec.sensor, bodies.get(me)) else {
            return false;
        };
        let mut rng = Rng::lidar(seed, me as u64, tick);
        self.scan(
            out,
            &config_of(sensor),
            Vec2::new(s.position[0], s.position[1]),
            s.heading,
            bodies
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != me)
                .map(|(k, b)| Body {
                    position: Vec2::new(b.position[0], b.position[1]),
                    heading: b.heading,
                    shape: match shapes.get(k) {
                        Some(s @ Shape::Polygon(_)) => *s,
                        _ => Shape::disc(b.radius),
                    },
                }),
            &mut || rng.gaussian(),
        );
        true
    }

    /// Fills `out` with the scan from `origin` heading `heading` (rad)
    /// among `bodies` ([`Body`], or (centre, radius) for discs) and the
    /// walls. `gaussian` draws the noise (once per hit beam, in beam order,
    /// only when `config.noise > 0`).
    pub fn scan<B: Into<Body>>(
        &mut self,
        out: &mut LaserScan,
        config: &LidarConfig,
        origin: Vec2,
        heading: f64,
        bodies: impl IntoIterator<Item = B>,
        gaussian: &mut dyn FnMut() -> f64,
    ) {
        let (angle_min, inc) = config.angles();
        let range = config.range;
        out.angle_min = angle_min;
        out.angle_increment = inc;
        out.range_max = range;
        out.ranges.clear();
        let beams = config.beams.max(1) as usize;
        let max_toi = range as Real;
        self.targets.clear();
        self.targets.extend(
            bodies
                .into_iter()
                .filter_map(|b| Target::of(&b.into(), origin, range)),
        );
        let bvh = (self.targets.len() > BODIES_BRUTE_FORCE).then(|| {
            Bvh::from_iter(
                BvhBuildStrategy::Binned,
                self.targets.iter().enumerate().map(|(i, t)| (i, t.aabb())),
            )
        });
        let world_origin = Vector::new(origin.x as Real, origin.y as Real);
        for k in 0..beams {
            let a = heading + angle_min + inc * k as f64;
            let dir = Vector::new(a.cos() as Real, a.sin() as Real);
            let mut best = self.walls.shape.as_ref().map_or(Real::MAX, |w| {
                let ray = Ray::new(world_origin, dir);
                cast(w.bvh(), &ray, max_toi, |i, so_far| {
                    w.segment(i).cast_local_ray(&ray, so_far, true)
                })
                .unwrap_or(Real::MAX)
            });
            let local = Ray::new(Vector::ZERO, dir);
            let limit = best.min(max_toi);
            let body = |i: u32, so_far: Real| self.targets[i as usize].cast(&local, so_far);
            let hit = match &bvh {
                Some(bvh) => cast(bvh, &local, limit, body),
                None => (0..self.targets.len() as u32)
                    .filter_map(|i| body(i, limit))
                    .reduce(Real::min),
            };
            if let Some(t) = hit {
                best = best.min(t);
            }
            // A hit within the f32 range is within `range` (up to its
            // rounding, which the clamp takes back).
            let t = f64::from(best).min(range);
            out.ranges.push(if best > max_toi {
                f64::INFINITY
            } else if config.noise > 0.0 {
                (t + config.noise * gaussian()).clamp(0.0, range)
            } else {
                t
            });
        }
    }
}

/// The nearest hit, within `max`, of `ray` on the leaves of `bvh`, each
/// cast by `leaf` (its index, the nearest hit so far). A depth-first walk
/// that skips every box the ray misses or meets beyond the nearest hit so
/// far (slab test with the inverse direction computed once; along an axis
/// the ray does not move on, the box is met if the origin lies within its
/// extent, faces included).
fn cast(bvh: &Bvh, ray: &Ray, max: Real, leaf: impl Fn(u32, Real) -> Option<Real>) -> Option<Real> {
    let (o, d) = (ray.origin, ray.dir);
    let inv = Vector::new(1.0 / d.x, 1.0 / d.y);
    let axis_aligned = d.x == 0.0 || d.y == 0.0;
    // The entry and exit distances of the box `lo`..`hi` along one axis.
    let slab = |o: Real, d: Real, inv: Real, lo: Real, hi: Real| {
        if d == 0.0 {
            if (lo..=hi).contains(&o) {
                (Real::MIN, Real::MAX)
            } else {
                (Real::MAX, Real::MIN)
            }
        } else {
            let (a, b) = ((lo - o) * inv, (hi - o) * inv);
            (a.min(b), a.max(b))
        }
    };
    let mut best = max;
    let mut found = false;
    bvh.traverse(|node| {
        let (lo, hi) = (node.mins(), node.maxs());
        let (near, far) = if axis_aligned {
            let (nx, fx) = slab(o.x, d.x, inv.x, lo.x, hi.x);
            let (ny, fy) = slab(o.y, d.y, inv.y, lo.y, hi.y);
            (nx.max(ny), fx.min(fy))
        } else {
            let (t1, t2) = ((lo - o) * inv, (hi - o) * inv);
            (t1.min(t2).max_element(), t1.max(t2).min_element())
        };
        if far < near.max(0.0) || near > best {
            return TraversalAction::Prune;
        }
        if let Some(i) = node.leaf_data()
            && let Some(t) = leaf(i, best)
            && t <= best
        {
            best = t;
            found = true;
        }
        TraversalAction::Continue
    });
    found.then_some(best)
}
