//! ORCA's static obstacles (van den Berg et al. 2011, section 5.2; RVO2's
//! `Obstacle` polygons and the obstacle ORCA lines of
//! `Agent::computeNewVelocity`).
//!
//! The scenario's walls are segments; RVO2's obstacles are polygons whose
//! vertices know their neighbours. [`WallChain::join`] joins segments that
//! share endpoints back into chains, and [`ObstacleSet::push_chains`] turns
//! each chain into RVO2's polygon as seen from the robot. Each edge near
//! enough to matter ([`ObstacleSet::select_neighbors`]) then adds one
//! half-plane of admissible velocities ([`ObstacleSet::push_lines`]): the
//! velocity obstacle of the edge truncated at `time_horizon_obst`, with the
//! full responsibility (obstacles do not move).

use super::linear_program::{Line, RVO_EPSILON, det, normalize_or};
use crate::{Segment, Vec2};

/// The unit normal from the edge `a -> b` towards `p`, at the edge's point
/// nearest `p` (the edge's right-hand normal when `p` is on it).
fn edge_normal(a: Vec2, b: Vec2, p: Vec2) -> Vec2 {
    let right = Vec2::new(b.y - a.y, a.x - b.x);
    normalize_or(
        p - Segment { a, b }.closest_point(p),
        normalize_or(right, Vec2::x()),
    )
}

/// Positive when `c` lies to the left of the directed line `a -> b`.
pub(super) fn left_of(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    det(a - c, b - a)
}

/// The radius a robot keeps from a wall edge.
///
/// A robot seen as its own disc keeps `radius` from every wall. A unicycle
/// driven through its look-ahead point p ([`crate::unicycle`]) is seen as
/// p with `radius` = r + l, the disc that covers its real disc (radius r,
/// centred c = p - l h for the unit heading h) at any heading. Against a
/// wall whose outward unit normal at the point nearest p is n (k = h . n),
/// c's distance to the wall is p's less l k, and to a corner at least
/// that, so p kept at any distance from r + l max(0, k) up keeps c at
/// least r off it. p is kept at r + l (1 + k) / 2: the bare radius when
/// the robot heads straight at the wall (c is then l further off than p),
/// r + l / 2 when it drives along the wall, r + l when it heads straight
/// away (as with the enlarged disc). c then keeps r + l (1 - k) / 2: half
/// the look-ahead to spare while driving along a wall, where the enlarged
/// disc kept all of it. A door as narrow as twice the enlarged disc, which
/// the enlarged disc could pass only by touching both jambs, is passed
/// with l to spare. The spare is kept because the controller moves p
/// sideways only as fast as the turn rate's limits let it (module
/// documentation of [`crate::unicycle`], 3): with none (p at r + l max(0,
/// k), the least that keeps c off), robots driving along walls graze them
/// wherever they turn. Other robots are still kept off the enlarged disc,
/// as their own planners see them as their centres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WallRadius {
    /// The radius the robot is seen with, padding included.
    pub(super) radius: f64,
    /// How far behind the seen position the real disc's centre lies along
    /// `heading`, l (0 for a robot seen at its centre).
    pub(super) behind: f64,
    /// Unit heading h.
    pub(super) heading: Vec2,
}

impl WallRadius {
    /// The radius kept from the edge `a -> b` by a robot seen at `p`.
    pub(super) fn for_edge(&self, a: Vec2, b: Vec2, p: Vec2) -> f64 {
        if self.behind <= 0.0 {
            return self.radius;
        }
        let normal = edge_normal(a, b, p);
        self.radius - self.behind * (1.0 - self.heading.dot(&normal)) / 2.0
    }
}

/// One vertex of a static obstacle, RVO2-style: the edge from it to `next`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ObstacleVertex {
    pub(super) point: Vec2,
    /// Unit direction of the edge to the next vertex.
    pub(super) unit_dir: Vec2,
    pub(super) convex: bool,
    pub(super) next: usize,
    pub(super) prev: usize,
}

/// Static obstacles as RVO2 stores them: closed chains of vertices.
#[derive(Debug, Clone, Default)]
pub(super) struct ObstacleSet {
    pub(super) vertices: Vec<ObstacleVertex>,
}

impl ObstacleSet {
    /// Forgets every obstacle.
    pub(super) fn clear(&mut self) {
        self.vertices.clear();
    }

    /// Adds a polygon given counter-clockwise (the inside on the left of
    /// every edge), or a wall segment as two points. Fewer than two points,
    /// or a zero-length edge, adds nothing.
    pub(super) fn push_polygon(&mut self, points: &[Vec2]) {
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
    /// `points` is scratch space, reused across calls.
    pub(super) fn push_chains(
        &mut self,
        chains: &[WallChain],
        position: Vec2,
        points: &mut Vec<Vec2>,
    ) {
        for c in chains {
            points.clear();
            points.extend_from_slice(&c.points);
            if c.closed {
                let ccw = signed_area(points) > 0.0;
                if ccw == contains(points, position) {
                    points.reverse();
                }
            } else if points.len() > 2 {
                // There and back: p0..pk, then pk-1..p1.
                for i in (1..c.points.len() - 1).rev() {
                    points.push(c.points[i]);
                }
            }
            self.push_polygon(points);
        }
    }

    /// Adds wall segments, joined into chains where they share endpoints
    /// (see [`WallChain::join`]), as seen from `position`.
    #[cfg(test)]
    pub(super) fn push_walls(&mut self, walls: &[Segment], position: Vec2) {
        self.push_chains(&WallChain::join(walls), position, &mut Vec::new());
    }

    /// The edges that can matter within `time_horizon_obst`, seen from their
    /// outer (right) side, nearest first, as (squared distance, vertex
    /// index) into `out` (RVO2's `computeNeighbors` for obstacles).
    pub(super) fn select_neighbors(
        &self,
        position: Vec2,
        radius: f64,
        max_speed: f64,
        time_horizon_obst: f64,
        out: &mut Vec<(f64, usize)>,
    ) {
        let range = time_horizon_obst * max_speed + radius;
        let range_sq = range * range;
        out.clear();
        for (i, o1) in self.vertices.iter().enumerate() {
            let o2 = &self.vertices[o1.next];
            // Only an edge the robot is on the right of (outside) can be seen.
            if left_of(o1.point, o2.point, position) >= 0.0 {
                continue;
            }
            let e = o2.point - o1.point;
            let s = ((position - o1.point).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            let dist_sq = (position - (o1.point + e * s)).norm_squared();
            if dist_sq < range_sq {
                out.push((dist_sq, i));
            }
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }

    /// Appends the half-planes of the edges `neighbors` (from
    /// [`Self::select_neighbors`]) for a robot at `position` with
    /// `velocity`, keeping the radius `walls` gives each edge, to `lines`
    /// (RVO2's obstacle ORCA lines).
    pub(super) fn push_lines(
        &self,
        neighbors: &[(f64, usize)],
        time_horizon_obst: f64,
        position: Vec2,
        velocity: Vec2,
        walls: WallRadius,
        lines: &mut Vec<Line>,
    ) {
        let inv_tau = 1.0 / time_horizon_obst;
        let verts = &self.vertices;
        for &(_, first) in neighbors {
            let mut i1 = first;
            let mut i2 = verts[i1].next;
            let rel1 = verts[i1].point - position;
            let rel2 = verts[i2].point - position;
            let radius = walls.for_edge(verts[i1].point, verts[i2].point, position);

            // Already covered: both ends' cut-off discs lie beyond a line
            // built for a nearer edge.
            let covered = lines.iter().any(|l| {
                det(rel1 * inv_tau - l.point, l.direction) - inv_tau * radius >= -RVO_EPSILON
                    && det(rel2 * inv_tau - l.point, l.direction) - inv_tau * radius >= -RVO_EPSILON
            });
            if covered {
                continue;
            }

            // RVO2 treats a non-convex vertex as the joint with the
            // neighbouring edge, which then takes over beyond it: the leg
            // there extends the edge's own line, and a collision with the
            // vertex is left to the neighbour. That holds only while the
            // robot sees the neighbour (is on its right). A wall chain
            // that ends, or meets another where three or more walls join,
            // is a polygon of no thickness (there and back), and a robot
            // can see an edge but not its neighbour at the turn: the
            // extended line would then run through free space and forbid
            // velocities that hit nothing. Such a vertex is taken as the
            // convex end it is from the robot's side.
            let sees =
                |k: usize| left_of(verts[k].point, verts[verts[k].next].point, position) < 0.0;
            let convex1 = verts[i1].convex || !sees(verts[i1].prev);
            let convex2 = verts[i2].convex || !sees(i2);

            let dist_sq1 = rel1.norm_squared();
            let dist_sq2 = rel2.norm_squared();
            let radius_sq = radius * radius;
            let edge = verts[i2].point - verts[i1].point;
            let s = (-rel1).dot(&edge) / edge.norm_squared();
            let dist_sq_line = (-rel1 - edge * s).norm_squared();

            if s < 0.0 && dist_sq1 <= radius_sq {
                // Collision with left vertex (ignored if non-convex).
                if convex1 {
                    lines.push(Line {
                        point: Vec2::zeros(),
                        direction: normalize_or(Vec2::new(-rel1.y, rel1.x), -verts[i1].unit_dir),
                    });
                }
                continue;
            } else if s > 1.0 && dist_sq2 <= radius_sq {
                // Collision with right vertex (ignored if non-convex, or if
                // the next edge will take care of it).
                if convex2 && det(rel2, verts[i2].unit_dir) >= 0.0 {
                    lines.push(Line {
                        point: Vec2::zeros(),
                        direction: normalize_or(Vec2::new(-rel2.y, rel2.x), -verts[i1].unit_dir),
                    });
                }
                continue;
            } else if (0.0..=1.0).contains(&s) && dist_sq_line <= radius_sq {
                // Collision with obstacle segment (both ends included, as
                // in RVO2: a robot exactly abreast of the end, s = 1, is
                // still colliding with the segment).
                lines.push(Line {
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
                if !convex1 {
                    continue;
                }
                i2 = i1;
                left_leg = left_tangent(rel1, dist_sq1);
                right_leg = right_tangent(rel1, dist_sq1);
            } else if s > 1.0 && dist_sq_line <= radius_sq {
                // Obstacle viewed obliquely: the right vertex defines the
                // velocity obstacle.
                if !convex2 {
                    continue;
                }
                i1 = i2;
                left_leg = left_tangent(rel2, dist_sq2);
                right_leg = right_tangent(rel2, dist_sq2);
            } else {
                // Usual situation.
                left_leg = if convex1 {
                    left_tangent(rel1, dist_sq1)
                } else {
                    // Left vertex non-convex: the left leg extends the
                    // cut-off line.
                    -verts[i1].unit_dir
                };
                right_leg = if convex2 {
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
                lines.push(Line {
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
                lines.push(Line {
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
                lines.push(shifted(left_cutoff, -verts[i1].unit_dir));
            } else if dist_sq_left <= dist_sq_right {
                // Project on left leg.
                if !left_foreign {
                    lines.push(shifted(left_cutoff, left_leg));
                }
            } else {
                // Project on right leg.
                if !right_foreign {
                    lines.push(shifted(right_cutoff, -right_leg));
                }
            }
        }
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
pub(super) struct WallChain {
    /// The chain's points in order (a closed chain does not repeat its
    /// first point).
    pub(super) points: Vec<Vec2>,
    /// Does the last point join the first?
    pub(super) closed: bool,
}

impl WallChain {
    /// Joins `walls` into chains (zero-length segments are dropped).
    pub(super) fn join(walls: &[Segment]) -> Vec<WallChain> {
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
