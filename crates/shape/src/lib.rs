//! Body shapes of mrsim and the true surface gap between them.
//!
//! A body is a disc (the default, every body before shapes existed) or a
//! convex polygon given in its body frame, counter-clockwise, with at most
//! [`MAX_VERTICES`] vertices (Box2D's `b2_maxPolygonVertices`, Flatland's
//! footprints); a rectangle is the polygon of its four corners, its length
//! along the heading. A body's pose is its position and heading: the body
//! frame's origin and its x axis.
//!
//! Why the crate is shaped as it is:
//!
//! - **No physics engine.** The scenario refuses starts whose true shapes
//!   overlap, the planners see other bodies' shapes, and the world measures
//!   clearances, contacts and times to collision; the scenario and the
//!   planners may not depend on rapier, so the geometry they share lives
//!   here, a leaf. The world gives rapier the same shapes (cuboids and
//!   convex polygons), and its tests check [`gap`] against parry's distance
//!   and contact queries.
//! - **f64 and exact for discs.** Two discs' gap is the distance between
//!   their centres less both radii, computed exactly as mrsim always has, so
//!   runs of discs keep every recorded number.
//! - **[`Shape`] is `Copy`.** A polygon is a fixed array, so an observation
//!   of other bodies stays a slice of plain values, as it was for discs.
#![warn(missing_docs)]

/// The most vertices a polygon may have.
pub const MAX_VERTICES: usize = 8;

/// A point or vector of the plane.
pub type P2 = [f64; 2];

/// A body's shape in its body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A disc centred on the body's position (radius 0: a point).
    Disc {
        /// Radius, >= 0.
        radius: f64,
    },
    /// A convex polygon: a rectangle or any other.
    Polygon(Polygon),
}

/// A convex polygon in the body frame: 3 to [`MAX_VERTICES`] vertices,
/// counter-clockwise, no three in a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polygon {
    len: u8,
    points: [P2; MAX_VERTICES],
}

/// Why points do not make a [`Polygon`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonError {
    /// Fewer than three points, or more than [`MAX_VERTICES`].
    #[error("a polygon has 3 to {MAX_VERTICES} points, not {0}")]
    Count(usize),
    /// A coordinate is NaN or infinite.
    #[error("point {0} is not finite")]
    NotFinite(usize),
    /// The points go round clockwise.
    #[error("the points go round clockwise; give them counter-clockwise")]
    Clockwise,
    /// The polygon is not convex at a point (or has three in a line).
    #[error(
        "the polygon is not convex at point {0} (or three points are in a line); \
         a non-convex body is refused: give its convex hull or split it into bodies"
    )]
    NotConvex(usize),
}

/// Why a rectangle's sides cannot make one.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("a rectangle's length and width must be finite and > 0 (got {length} x {width})")]
pub struct RectangleError {
    /// The length given.
    pub length: f64,
    /// The width given.
    pub width: f64,
}

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn norm(a: P2) -> f64 {
    dot(a, a).sqrt()
}

impl Polygon {
    /// The polygon of `points` (body frame, counter-clockwise, convex).
    ///
    /// ```
    /// use mrsim_shape::{Polygon, PolygonError};
    /// let tri = Polygon::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    /// assert_eq!(tri.points().len(), 3);
    /// let cw = Polygon::new(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]);
    /// assert_eq!(cw, Err(PolygonError::Clockwise));
    /// ```
    pub fn new(points: &[P2]) -> Result<Self, PolygonError> {
        let n = points.len();
        if !(3..=MAX_VERTICES).contains(&n) {
            return Err(PolygonError::Count(n));
        }
        if let Some(i) = points
            .iter()
            .position(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            return Err(PolygonError::NotFinite(i));
        }
        let area2: f64 = (0..n).map(|i| cross(points[i], points[(i + 1) % n])).sum();
        if area2 < 0.0 {
            return Err(PolygonError::Clockwise);
        }
        // Convex, counter-clockwise: every turn is to the left, and the
        // edges go round once (their turns add up to one revolution).
        let mut turned = 0.0;
        for i in 0..n {
            let a = points[(i + n - 1) % n];
            let b = points[i];
            let c = points[(i + 1) % n];
            let (e0, e1) = (sub(b, a), sub(c, b));
            if cross(e0, e1) <= 0.0 {
                return Err(PolygonError::NotConvex(i));
            }
            turned += cross(e0, e1).atan2(dot(e0, e1));
        }
        if turned > 1.5 * std::f64::consts::TAU {
            return Err(PolygonError::NotConvex(0));
        }
        let mut out = [[0.0; 2]; MAX_VERTICES];
        out[..n].copy_from_slice(points);
        Ok(Self {
            len: n as u8,
            points: out,
        })
    }

    /// The rectangle `length` along the body's x axis by `width`, centred
    /// on its origin.
    pub fn rectangle(length: f64, width: f64) -> Result<Self, RectangleError> {
        if !(length.is_finite() && width.is_finite() && length > 0.0 && width > 0.0) {
            return Err(RectangleError { length, width });
        }
        let (x, y) = (length / 2.0, width / 2.0);
        Self::new(&[[-x, -y], [x, -y], [x, y], [-x, y]])
            .map_err(|_| RectangleError { length, width })
    }

    /// The vertices, body frame, counter-clockwise.
    pub fn points(&self) -> &[P2] {
        &self.points[..self.len as usize]
    }
}

/// Where a body is: its position and heading (rad, counter-clockwise
/// from +x).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// Position of the body frame's origin.
    pub position: P2,
    /// Heading: the body frame's x axis, rad.
    pub heading: f64,
}

impl Pose {
    /// A pose.
    pub fn new(position: P2, heading: f64) -> Self {
        Self { position, heading }
    }

    /// A body-frame point in the world.
    pub fn apply(&self, p: P2) -> P2 {
        let (s, c) = self.heading.sin_cos();
        [
            self.position[0] + c * p[0] - s * p[1],
            self.position[1] + s * p[0] + c * p[1],
        ]
    }
}

/// Up to [`MAX_VERTICES`] points in the world.
#[derive(Debug, Clone, Copy)]
pub struct Placed {
    len: usize,
    points: [P2; MAX_VERTICES],
}

impl Placed {
    /// The points, counter-clockwise.
    pub fn points(&self) -> &[P2] {
        &self.points[..self.len]
    }
}

impl Shape {
    /// A disc.
    pub fn disc(radius: f64) -> Self {
        Shape::Disc { radius }
    }

    /// Is it a disc?
    pub fn is_disc(&self) -> bool {
        matches!(self, Shape::Disc { .. })
    }

    /// The radius of the smallest disc about the body's origin that holds
    /// the shape (a disc's own radius): what a planner that sees discs
    /// takes the body for.
    ///
    /// ```
    /// use mrsim_shape::{Polygon, Shape};
    /// let car = Shape::Polygon(Polygon::rectangle(4.0, 3.0).unwrap());
    /// assert_eq!(car.circumradius(), 2.5);
    /// ```
    pub fn circumradius(&self) -> f64 {
        match self {
            Shape::Disc { radius } => *radius,
            Shape::Polygon(p) => p.points().iter().map(|&q| norm(q)).fold(0.0, f64::max),
        }
    }

    /// The radius of the largest disc about the body's origin inside the
    /// shape (a disc's own radius; a rectangle's half width): the least
    /// distance from the origin to an edge's line, 0 if the origin is not
    /// inside.
    ///
    /// ```
    /// use mrsim_shape::{Polygon, Shape};
    /// let agv = Shape::Polygon(Polygon::rectangle(0.9, 0.6).unwrap());
    /// assert!((agv.inradius() - 0.3).abs() < 1e-12);
    /// ```
    pub fn inradius(&self) -> f64 {
        match self {
            Shape::Disc { radius } => *radius,
            Shape::Polygon(p) => {
                let pts = p.points();
                let n = pts.len();
                (0..n)
                    .map(|i| {
                        let (a, b) = (pts[i], pts[(i + 1) % n]);
                        let e = sub(b, a);
                        cross(e, sub([0.0, 0.0], a)) / norm(e)
                    })
                    .fold(f64::INFINITY, f64::min)
                    .max(0.0)
            }
        }
    }

    /// The polygon's vertices in the world at `pose` (`None` for a disc).
    pub fn placed(&self, pose: Pose) -> Option<Placed> {
        match self {
            Shape::Disc { .. } => None,
            Shape::Polygon(p) => {
                let mut points = [[0.0; 2]; MAX_VERTICES];
                for (o, q) in points.iter_mut().zip(p.points()) {
                    *o = pose.apply(*q);
                }
                Some(Placed {
                    len: p.points().len(),
                    points,
                })
            }
        }
    }
}

/// The signed surface gap between two posed shapes: the distance between
/// their surfaces when apart, 0 touching, and minus the depth by which
/// they overlap (the least translation that separates them) when they do.
///
/// Two discs: the distance between centres less both radii, as mrsim has
/// always measured it. A disc and a polygon: the centre's signed distance
/// to the polygon less the radius. Two polygons: the least distance from a
/// vertex of one to an edge of the other when apart, and the least overlap
/// of their projections on an edge normal (the separating-axis theorem)
/// when they overlap.
///
/// ```
/// use mrsim_shape::{gap, Polygon, Pose, Shape};
/// // Two 0.9 x 0.6 rectangles side by side, 0.1 apart: their circumscribed
/// // discs (radius 0.54) overlap, the rectangles do not.
/// let agv = Shape::Polygon(Polygon::rectangle(0.9, 0.6).unwrap());
/// let g = gap(&agv, Pose::new([0.0, 0.0], 0.0), &agv, Pose::new([0.0, 0.7], 0.0));
/// assert!((g - 0.1).abs() < 1e-12);
/// ```
pub fn gap(a: &Shape, pa: Pose, b: &Shape, pb: Pose) -> f64 {
    match (a, b) {
        (Shape::Disc { radius: ra }, Shape::Disc { radius: rb }) => {
            let dx = pa.position[0] - pb.position[0];
            let dy = pa.position[1] - pb.position[1];
            (dx * dx + dy * dy).sqrt() - ra - rb
        }
        (Shape::Disc { radius }, Shape::Polygon(_)) => signed_distance(b, pb, pa.position) - radius,
        (Shape::Polygon(_), Shape::Disc { radius }) => signed_distance(a, pa, pb.position) - radius,
        (Shape::Polygon(_), Shape::Polygon(_)) => match (a.placed(pa), b.placed(pb)) {
            (Some(x), Some(y)) => convex_gap(x.points(), y.points()),
            _ => f64::INFINITY,
        },
    }
}

/// A shape placed at its pose once, for many gaps at one instant (a
/// polygon's vertices turned into the world once, not once per pair).
#[derive(Debug, Clone, Copy)]
pub enum Placement {
    /// A disc: centre and radius.
    Disc {
        /// Centre.
        centre: P2,
        /// Radius.
        radius: f64,
    },
    /// A polygon's vertices in the world.
    Polygon(Placed),
}

impl Placement {
    /// `shape` at `pose`.
    pub fn of(shape: &Shape, pose: Pose) -> Self {
        match shape.placed(pose) {
            Some(p) => Placement::Polygon(p),
            None => Placement::Disc {
                centre: pose.position,
                radius: shape.circumradius(),
            },
        }
    }
}

/// [`gap`] of two placed shapes: the same number.
pub fn placed_gap(a: &Placement, b: &Placement) -> f64 {
    match (a, b) {
        (
            Placement::Disc {
                centre: ca,
                radius: ra,
            },
            Placement::Disc {
                centre: cb,
                radius: rb,
            },
        ) => {
            let dx = ca[0] - cb[0];
            let dy = ca[1] - cb[1];
            (dx * dx + dy * dy).sqrt() - ra - rb
        }
        (Placement::Disc { centre, radius }, Placement::Polygon(p))
        | (Placement::Polygon(p), Placement::Disc { centre, radius }) => {
            polygon_signed_distance(p.points(), *centre) - radius
        }
        (Placement::Polygon(x), Placement::Polygon(y)) => convex_gap(x.points(), y.points()),
    }
}

/// The time until two posed shapes touch, `b` moving at `v` relative to
/// `a` and neither turning: 0 if they overlap, infinity if they never
/// touch. `from` is a time known to come before contact (0, or the
/// circumscribed discs' time to collision, which never comes later).
///
/// [`placed_time_to_contact`] of the shapes placed at their poses.
pub fn time_to_contact(a: &Shape, pa: Pose, b: &Shape, pb: Pose, v: P2, from: f64) -> f64 {
    placed_time_to_contact(&Placement::of(a, pa), &Placement::of(b, pb), v, from)
}

/// [`time_to_contact`] of two placed shapes, `b` moving at `v` relative
/// to `a`.
///
/// - **Two polygons: exact.** `b` moved by `v t` meets `a` when `v t` lies
///   in the Minkowski difference `a - b`, a convex polygon whose edges'
///   normals are those of `a` and those of `b` turned round (van den
///   Bergen, "Collision Detection in Interactive 3D Environments", 2004,
///   ch. 2.7: a translational ray cast is a ray against the configuration
///   space obstacle). The ray `v t` from the origin is clipped to each of
///   those half-planes in turn (Cyrus and Beck, 1978); where it enters the
///   polygon, the shapes touch.
/// - **A disc and a polygon: conservative advancement** (Mirtich 1996):
///   the gap closes at most at the relative speed, so stepping by gap /
///   speed never passes the contact; the gap of two translating convex
///   bodies is convex in time, so once it grows they never touch. Stops
///   within 1e-9 of contact or after 64 steps, a time at or before the
///   contact.
/// - **Two discs:** when their centres come within the sum of the radii.
pub fn placed_time_to_contact(a: &Placement, b: &Placement, v: P2, from: f64) -> f64 {
    let g0 = placed_gap(a, b);
    if g0 <= 0.0 {
        return 0.0;
    }
    let speed = norm(v);
    if speed.is_nan() || speed <= 0.0 || !from.is_finite() {
        return f64::INFINITY;
    }
    match (a, b) {
        (Placement::Polygon(x), Placement::Polygon(y)) => {
            polygons_time_to_contact(x.points(), y.points(), v)
        }
        (
            Placement::Disc {
                centre: ca,
                radius: ra,
            },
            Placement::Disc {
                centre: cb,
                radius: rb,
            },
        ) => {
            // |d + v t| = ra + rb, the smaller root, closing.
            let d = sub(*cb, *ca);
            let r = ra + rb;
            let (vv, dv) = (dot(v, v), dot(d, v));
            let disc = dv * dv - vv * (dot(d, d) - r * r);
            if dv >= 0.0 || disc < 0.0 {
                f64::INFINITY
            } else {
                (-dv - disc.sqrt()) / vv
            }
        }
        (Placement::Disc { centre, radius }, Placement::Polygon(p)) => {
            // The polygon moving at v is the disc moving at -v.
            let c = *centre;
            advance(
                |t| {
                    polygon_signed_distance(p.points(), [c[0] - v[0] * t, c[1] - v[1] * t]) - radius
                },
                speed,
                from,
            )
        }
        (Placement::Polygon(p), Placement::Disc { centre, radius }) => {
            let c = *centre;
            advance(
                |t| {
                    polygon_signed_distance(p.points(), [c[0] + v[0] * t, c[1] + v[1] * t]) - radius
                },
                speed,
                from,
            )
        }
    }
}

/// Conservative advancement of a gap `at(t)` closing at most at `speed`,
/// from a time `from` at or before contact.
fn advance(at: impl Fn(f64) -> f64, speed: f64, from: f64) -> f64 {
    let mut t = from.max(0.0);
    let mut g = at(t);
    for _ in 0..64 {
        if g <= 1e-9 {
            return t;
        }
        let next = t + g / speed;
        let gn = at(next);
        if gn >= g {
            return f64::INFINITY;
        }
        (t, g) = (next, gn);
    }
    t
}

/// The first time `t` >= 0 at which convex polygon `b` (world points,
/// counter-clockwise) moved by `v t` touches convex polygon `a`, or
/// infinity: the ray `v t` against the Minkowski difference `a - b`.
fn polygons_time_to_contact(a: &[P2], b: &[P2], v: P2) -> f64 {
    let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
    // Each edge normal n of either polygon bounds a - b by n . x <= c,
    // c = max over a of n . p - min over b of n . q (the support of a - b).
    let normals = edge_normals(a).chain(edge_normals(b).map(|n| [-n[0], -n[1]]));
    for n in normals {
        let c = a
            .iter()
            .map(|&p| dot(n, p))
            .fold(f64::NEG_INFINITY, f64::max)
            - b.iter().map(|&q| dot(n, q)).fold(f64::INFINITY, f64::min);
        let along = dot(n, v);
        if along == 0.0 {
            // Parallel to this side: inside it for good, or never.
            if c < 0.0 {
                return f64::INFINITY;
            }
        } else if along > 0.0 {
            exit = exit.min(c / along);
        } else {
            enter = enter.max(c / along);
        }
        if enter > exit {
            return f64::INFINITY;
        }
    }
    enter
}

/// The outward normals (not unit) of a counter-clockwise polygon's edges.
fn edge_normals(pts: &[P2]) -> impl Iterator<Item = P2> + '_ {
    let n = pts.len();
    (0..n).map(move |i| {
        let e = sub(pts[(i + 1) % n], pts[i]);
        [e[1], -e[0]]
    })
}

/// The signed gap between a posed shape and a wall segment `s`: the
/// distance from the segment to the shape's surface, negative by the depth
/// the segment reaches into it.
pub fn gap_to_segment(shape: &Shape, pose: Pose, s: [P2; 2]) -> f64 {
    match shape.placed(pose) {
        None => segment_distance(s, pose.position) - shape.circumradius(),
        Some(poly) => convex_gap(poly.points(), &s),
    }
}

/// [`gap_to_segment`] of a placed shape: the same number, the polygon
/// turned into the world once for many segments.
pub fn placed_gap_to_segment(a: &Placement, s: [P2; 2]) -> f64 {
    match a {
        Placement::Disc { centre, radius } => segment_distance(s, *centre) - radius,
        Placement::Polygon(p) => convex_gap(p.points(), &s),
    }
}

/// The signed distance from the surface of a posed shape to point `p`:
/// positive outside, negative inside (minus the distance to the nearest
/// edge).
pub fn signed_distance(shape: &Shape, pose: Pose, p: P2) -> f64 {
    match shape.placed(pose) {
        None => norm(sub(p, pose.position)) - shape.circumradius(),
        Some(poly) => polygon_signed_distance(poly.points(), p),
    }
}

/// The signed distance from a convex polygon's surface (world vertices,
/// counter-clockwise) to `p`.
fn polygon_signed_distance(pts: &[P2], p: P2) -> f64 {
    let n = pts.len();
    let mut inside = true;
    let mut outside_d2 = f64::INFINITY;
    let mut inside_d = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let e = sub(b, a);
        let side = cross(e, sub(p, a)) / norm(e);
        if side < 0.0 {
            inside = false;
        }
        inside_d = inside_d.min(side);
        outside_d2 = outside_d2.min(segment_distance_sq([a, b], p));
    }
    if inside { -inside_d } else { outside_d2.sqrt() }
}

/// Distance from point `p` to segment `s`.
pub fn segment_distance(s: [P2; 2], p: P2) -> f64 {
    segment_distance_sq(s, p).sqrt()
}

/// The least depth of overlap of the projections of `a` and `b` on the
/// normals of `a`'s edges (`a` may be a segment, two points): the shortest
/// push along an axis that parts them; negative when an axis separates
/// them.
fn least_overlap(a: &[P2], b: &[P2]) -> f64 {
    let n = a.len();
    let edges = if n == 2 { 1 } else { n };
    let mut least = f64::INFINITY;
    for i in 0..edges {
        let e = sub(a[(i + 1) % n], a[i]);
        let l = norm(e);
        if l == 0.0 {
            continue;
        }
        let axis = [-e[1] / l, e[0] / l];
        let (lo_a, hi_a) = project(a, axis);
        let (lo_b, hi_b) = project(b, axis);
        // The shorter way to push them apart along the axis (not the
        // length the two intervals share: one may hold the other).
        least = least.min((hi_a - lo_b).min(hi_b - lo_a));
        if least <= 0.0 {
            // A separating axis: they are apart, by however much.
            return least;
        }
    }
    least
}

fn project(pts: &[P2], axis: P2) -> (f64, f64) {
    pts.iter()
        .map(|&p| dot(p, axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// The signed gap between two convex point sets in the world (a polygon
/// or a segment each).
fn convex_gap(a: &[P2], b: &[P2]) -> f64 {
    // An axis of `a` that parts them: apart, whatever `b`'s axes say.
    let first = least_overlap(a, b);
    let overlap = if first > 0.0 {
        first.min(least_overlap(b, a))
    } else {
        first
    };
    if overlap > 0.0 {
        return -overlap;
    }
    // Apart (or touching): the nearest pair is a vertex of one and an edge
    // of the other (squared distances, one root). A vertex nearest to a
    // polygon's edge lies on the edge's outer side (or on its line): a
    // vertex strictly inside an edge's half-plane is nearer to another
    // edge, and is not measured to this one.
    let mut d2 = f64::INFINITY;
    for (x, y) in [(a, b), (b, a)] {
        let n = y.len();
        let edges = if n == 2 { 1 } else { n };
        for i in 0..edges {
            let s = [y[i], y[(i + 1) % n]];
            let e = sub(s[1], s[0]);
            for &p in x {
                if n > 2 && cross(e, sub(p, s[0])) > 0.0 {
                    continue;
                }
                d2 = d2.min(segment_distance_sq(s, p));
            }
        }
    }
    d2.sqrt()
}

/// Squared distance from point `p` to segment `s`.
fn segment_distance_sq(s: [P2; 2], p: P2) -> f64 {
    let d = sub(s[1], s[0]);
    let l2 = dot(d, d);
    let t = if l2 > 0.0 {
        (dot(sub(p, s[0]), d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = sub(p, [s[0][0] + t * d[0], s[0][1] + t * d[1]]);
    dot(q, q)
}

#[cfg(test)]
mod tests;
