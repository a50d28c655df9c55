//! Clearance geometry: distances from points to wall segments, and each
//! robot's smallest surface distance to any other body per tick, on the
//! grids of [`mrsim_spatial`].

use mrsim_shape::{Pose, Shape};
use mrsim_spatial::{BoundedGrid as Cells, Buckets, Disc, HashedGrid as Fine, bounds};

/// `p` minus the point of segment `w` nearest to it.
fn segment_offset(w: [[f64; 2]; 2], p: [f64; 2]) -> [f64; 2] {
    let (a, b) = (w[0], w[1]);
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [p[0] - a[0] - ab[0] * t, p[1] - a[1] - ab[1] * t]
}

/// Squared distance from `p` to the segment `w`, without a square root
/// (to rule a wall out cheaply; [`segment_distance`] gives the distance).
pub fn segment_distance_sq(w: [[f64; 2]; 2], p: [f64; 2]) -> f64 {
    let [dx, dy] = segment_offset(w, p);
    dx * dx + dy * dy
}

/// Distance from `p` to the segment `w`.
pub fn segment_distance(w: [[f64; 2]; 2], p: [f64; 2]) -> f64 {
    let [dx, dy] = segment_offset(w, p);
    dx.hypot(dy)
}

/// Each robot's smallest surface distance to any other body, per tick,
/// through a uniform grid instead of all pairs: bodies are bucketed into
/// about one cell per body (never smaller than the largest diameter).
///
/// A robot with no bound searches rings of cells outwards until no
/// unsearched body can be nearer. A robot with a bound `b` (the world
/// passes the smallest clearance it has already recorded for it: only a
/// smaller one changes anything) looks only at the cells that can hold a
/// body nearer than `b`, usually one to four instead of nine or more. Either
/// way a clearance below the bound is the same number, bit for bit, as the
/// all-pairs minimum (the same expression, minimised over the same bodies).
///
/// Once most robots have a bound, one cell per body is far too coarse
/// where bodies crowd a small part of the box they span (two streams
/// crossing a 760 m arena: ~30 bodies a cell), so robots with a small
/// bound search a second, fine grid instead: cells twice as wide as nine
/// in ten robots' search reach (so such a robot's box meets at most 2 x 2
/// cells), hashed into about 2n buckets (only the occupied cells cost
/// anything; bodies of other cells that share a bucket are ruled out by
/// their distance), each bucket's centres and radii copied side by side.
#[derive(Debug, Clone, Default)]
pub struct ClearanceGrid {
    coarse: Buckets,
    fine: Buckets,
    /// The robots' search reaches, reordered to find the ninetieth
    /// percentile.
    scratch: Vec<f64>,
}

/// True if a point at squared distance `d2` is clearly farther than `reach`
/// (a margin covers the rounding of both sides): it can be ruled out without
/// a square root. A negative reach rules nothing out.
pub fn clearly_beyond(d2: f64, reach: f64) -> bool {
    reach >= 0.0 && d2 > reach * reach * (1.0 + 1e-9) + 1e-300
}

/// A body as a disc: centre and radius.
fn disc(q: &mrsim_proto::BodyState) -> Disc {
    [q.position[0], q.position[1], q.radius]
}

/// Sorts `states` into `buckets` buckets by `keys` (one per body).
fn sort_states(
    into: &mut Buckets,
    states: &[mrsim_proto::BodyState],
    buckets: usize,
    keys: impl Iterator<Item = usize>,
) {
    into.sort(buckets, keys.zip(states.iter().map(disc)));
}

/// The clearance searches over one [`Buckets`].
trait Nearest {
    fn nearest_in_box(
        &self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        i: usize,
        reach: f64,
        cell: impl Fn(f64, usize) -> i64,
        bucket: impl Fn(i64, i64) -> usize,
    ) -> f64;
    fn nearest_in(
        &self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        i: usize,
        c: usize,
        best: f64,
    ) -> f64;
}

impl Nearest for Buckets {
    /// Robot `i`'s smallest clearance to the bodies whose centres may lie
    /// within `reach` of its own (infinity if none): the buckets of the
    /// cells of that box, `cell(v, axis)` giving a coordinate's cell (never
    /// decreasing in `v`) and `bucket(x, y)` a cell's bucket.
    fn nearest_in_box(
        &self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        i: usize,
        reach: f64,
        cell: impl Fn(f64, usize) -> i64,
        bucket: impl Fn(i64, i64) -> usize,
    ) -> f64 {
        let p = states[i].position;
        let (x0, x1) = (cell(p[0] - reach, 0), cell(p[0] + reach, 0));
        let (y0, y1) = (cell(p[1] - reach, 1), cell(p[1] + reach, 1));
        let mut best = f64::INFINITY;
        for y in y0..=y1 {
            for x in x0..=x1 {
                best = self.nearest_in(states, shapes, i, bucket(x, y), best);
            }
        }
        best
    }

    /// Robot `i`'s smallest clearance to the bodies of bucket `c` where it
    /// is below `best` (otherwise `best`).
    fn nearest_in(
        &self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        i: usize,
        c: usize,
        mut best: f64,
    ) -> f64 {
        let s = &states[i];
        let (order, at) = self.bucket(c);
        for (&j, &[qx, qy, qr]) in order.iter().zip(at) {
            if j as usize == i {
                continue;
            }
            // No square root for a body clearly farther than the best so far.
            let (dx, dy) = (qx - s.position[0], qy - s.position[1]);
            let d2 = dx * dx + dy * dy;
            if clearly_beyond(d2, best + qr + s.radius) {
                continue;
            }
            // As `centre_distance(q, s)`, the same expression as `brute`;
            // the true gap where a body is not a disc (never below the
            // discs' gap, so the discs rule bodies out as before).
            let g = d2.sqrt() - qr - s.radius;
            best = best.min(shape_gap(states, shapes, i, j as usize, g));
        }
        best
    }
}

/// The gap of bodies `i` and `j` whose circumscribed discs are `disc_gap`
/// apart: that, unless one of them has another shape (`shapes`, by body
/// id; empty when every body is a disc).
fn shape_gap(
    states: &[mrsim_proto::BodyState],
    shapes: &[Shape],
    i: usize,
    j: usize,
    disc_gap: f64,
) -> f64 {
    match (shapes.get(i), shapes.get(j)) {
        (Some(a), Some(b)) if !(a.is_disc() && b.is_disc()) => {
            let pose = |s: &mrsim_proto::BodyState| Pose::new(s.position, s.heading);
            mrsim_shape::gap(a, pose(&states[i]), b, pose(&states[j]))
        }
        _ => disc_gap,
    }
}

/// Distance between two bodies' centres: the plain square root of the sum
/// of squares (positions are nowhere near 1e150, and `hypot`'s overflow
/// guard would cost much of the clearance pass).
fn centre_distance(a: &mrsim_proto::BodyState, b: &mrsim_proto::BodyState) -> f64 {
    let (dx, dy) = (a.position[0] - b.position[0], a.position[1] - b.position[1]);
    (dx * dx + dy * dy).sqrt()
}

impl ClearanceGrid {
    /// Fills `out[i]` for each of the first `robots` bodies of `states`:
    /// min over j != i of |p_i - p_j| - r_j - r_i (infinity if alone).
    pub fn clearances(
        &mut self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        robots: usize,
        out: &mut Vec<f64>,
    ) {
        self.clearances_below(states, shapes, robots, |_| f64::INFINITY, out);
    }

    /// As [`clearances`](Self::clearances), but robot `i` only needs its
    /// clearance where it is below `bound(i)`: there `out[i]` is exact,
    /// elsewhere it is some value at or above the bound (so
    /// `min(bound(i), out[i])` is always exact).
    pub fn clearances_below(
        &mut self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        robots: usize,
        bound: impl Fn(usize) -> f64,
        out: &mut Vec<f64>,
    ) {
        out.clear();
        out.resize(robots.min(states.len()), f64::INFINITY);
        let n = states.len();
        if n < 2 {
            return;
        }
        let Some((lo, hi, rmax)) = bounds(states.iter().map(disc)) else {
            // Non-finite positions: fall back to all pairs.
            for (i, o) in out.iter_mut().enumerate() {
                *o = brute(states, shapes, i);
            }
            return;
        };
        // Each robot's search reach: every body nearer than its bound has
        // its centre within this distance of the robot's.
        let reach_of = |i: usize| bound(i) + states[i].radius + rmax;
        let fine = self.fine_grid(states, out.len(), &reach_of, lo, hi, rmax);
        let mut coarse: Option<Cells> = None;
        for (i, o) in out.iter_mut().enumerate() {
            let reach = reach_of(i);
            if reach < 0.0 {
                // Deeper than any overlap can be: nothing to search.
                *o = bound(i);
                continue;
            }
            if let Some(f) = fine.filter(|f| reach <= f.cell) {
                *o = self.fine.nearest_in_box(
                    states,
                    shapes,
                    i,
                    reach,
                    |v, k| f.at(v, k),
                    |x, y| f.bucket(x, y),
                );
                continue;
            }
            let g = *coarse.get_or_insert_with(|| {
                let g = Cells::spanning(lo, hi, n, rmax);
                sort_states(
                    &mut self.coarse,
                    states,
                    g.buckets(),
                    states
                        .iter()
                        .map(|s| g.bucket_at(s.position[0], s.position[1])),
                );
                g
            });
            if reach.is_finite() && reach <= g.cell {
                *o = self.coarse.nearest_in_box(
                    states,
                    shapes,
                    i,
                    reach,
                    |v, k| g.at(v, k) as i64,
                    |x, y| g.bucket(x as usize, y as usize),
                );
                continue;
            }
            // Unbounded (or a bound wider than a cell): rings outwards.
            *o = self.rings(states, shapes, i, g, bound(i), rmax);
        }
    }

    /// Sorts the bodies into the fine grid when nine in ten robots have a
    /// finite reach: cells twice as wide as the largest of those reaches
    /// (or the largest radius). `None` when too few robots are bounded.
    fn fine_grid(
        &mut self,
        states: &[mrsim_proto::BodyState],
        robots: usize,
        reach_of: &dyn Fn(usize) -> f64,
        lo: [f64; 2],
        hi: [f64; 2],
        rmax: f64,
    ) -> Option<Fine> {
        if robots < 16 {
            return None;
        }
        let k = robots * 9 / 10;
        self.scratch.clear();
        self.scratch.extend((0..robots).map(reach_of));
        let (_, p90, _) = self.scratch.select_nth_unstable_by(k, f64::total_cmp);
        let cell = 2.0 * p90.max(rmax);
        // Cell indices far beyond 2^53 would lose their meaning (and a
        // search box its size): no fine grid at such scales.
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let f = Fine::new(lo, cell, states.len(), span)?;
        sort_states(
            &mut self.fine,
            states,
            f.buckets(),
            states
                .iter()
                .map(|s| f.bucket(f.at(s.position[0], 0), f.at(s.position[1], 1))),
        );
        Some(f)
    }

    /// Robot `i`'s clearance by rings of cells around its own, stopping
    /// once no unsearched body can be nearer than the best found or than
    /// `bound`.
    fn rings(
        &self,
        states: &[mrsim_proto::BodyState],
        shapes: &[Shape],
        i: usize,
        g: Cells,
        bound: f64,
        rmax: f64,
    ) -> f64 {
        let s = &states[i];
        let (cx, cy) = (
            g.at(s.position[0], 0) as isize,
            g.at(s.position[1], 1) as isize,
        );
        let mut best = f64::INFINITY;
        let rings = g.nx.max(g.ny) as isize;
        for ring in 0..=rings {
            for dy in -ring..=ring {
                let y = cy + dy;
                if y < 0 || y >= g.ny as isize {
                    continue;
                }
                // Whole rows at the ring's top and bottom, two cells between.
                let step = if dy.abs() == ring { 1 } else { 2 * ring.max(1) };
                let mut dx = -ring;
                while dx <= ring {
                    let x = cx + dx;
                    if x >= 0 && x < g.nx as isize {
                        best = self.coarse.nearest_in(
                            states,
                            shapes,
                            i,
                            g.bucket(x as usize, y as usize),
                            best,
                        );
                    }
                    dx += step;
                }
            }
            // Every body not yet searched is at least ring * cell away.
            if best.min(bound) <= ring as f64 * g.cell - s.radius - rmax {
                break;
            }
        }
        best
    }
}

fn brute(states: &[mrsim_proto::BodyState], shapes: &[Shape], i: usize) -> f64 {
    let s = &states[i];
    let mut clear = f64::INFINITY;
    for (j, o) in states.iter().enumerate() {
        if j != i {
            let d = centre_distance(o, s);
            clear = clear.min(shape_gap(states, shapes, i, j, d - o.radius - s.radius));
        }
    }
    clear
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::BodyState;

    fn scatter(n: usize, seed: u64, spread: f64) -> Vec<BodyState> {
        let mut x = seed;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| BodyState {
                position: [spread * (next() - 0.5), spread * 0.3 * (next() - 0.5)],
                radius: 0.1 + 0.4 * next(),
                ..Default::default()
            })
            .collect()
    }

    #[test]
    fn with_shapes_the_grid_gives_the_all_pairs_minimum_of_the_true_gaps() {
        let mut grid = ClearanceGrid::default();
        let mut out = Vec::new();
        for (n, spread) in [(17, 5.0), (300, 40.0), (1000, 60.0)] {
            let mut states = scatter(n, n as u64 + 7, spread);
            // Every third body a rectangle, every third a triangle, each
            // turned; their radii the circumscribed ones.
            let shapes: Vec<Shape> = states
                .iter_mut()
                .enumerate()
                .map(|(k, s)| {
                    s.heading = k as f64 * 0.7;
                    let shape = match k % 3 {
                        0 => Shape::disc(s.radius),
                        1 => Shape::Polygon(
                            mrsim_shape::Polygon::rectangle(2.0 * s.radius, s.radius).unwrap(),
                        ),
                        _ => Shape::Polygon(
                            mrsim_shape::Polygon::new(&[
                                [-s.radius, -s.radius],
                                [s.radius, 0.0],
                                [-s.radius, s.radius],
                            ])
                            .unwrap(),
                        ),
                    };
                    s.radius = shape.circumradius();
                    shape
                })
                .collect();
            grid.clearances(&states, &shapes, n, &mut out);
            for (i, c) in out.iter().enumerate() {
                let exact = (0..n)
                    .filter(|&j| j != i)
                    .map(|j| {
                        let p = |k: usize| Pose::new(states[k].position, states[k].heading);
                        mrsim_shape::gap(&shapes[i], p(i), &shapes[j], p(j))
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!((c - exact).abs() < 1e-12, "n {n} robot {i}: {c} vs {exact}");
            }
        }
    }

    #[test]
    fn the_grid_gives_exactly_the_all_pairs_minimum_clearance() {
        let mut grid = ClearanceGrid::default();
        let mut out = Vec::new();
        for (n, spread) in [
            (2, 1.0),
            (17, 5.0),
            (300, 40.0),
            (300, 4000.0),
            (1000, 60.0),
        ] {
            let states = scatter(n, n as u64, spread);
            let robots = n * 3 / 4;
            grid.clearances(&states, &[], robots, &mut out);
            assert_eq!(out.len(), robots);
            for (i, c) in out.iter().enumerate() {
                assert_eq!(
                    c.to_bits(),
                    brute(&states, &[], i).to_bits(),
                    "n {n} robot {i}"
                );
            }
        }
    }

    #[test]
    fn squared_segment_distance_is_the_square_of_the_distance() {
        let w = [[-1.0, 2.0], [3.0, -0.5]];
        for p in [
            [0.0, 0.0],
            [-4.0, 2.0],
            [5.0, -3.0],
            [1.0, 1.0],
            [-1.0, 2.0],
        ] {
            let (d, d2) = (segment_distance(w, p), segment_distance_sq(w, p));
            assert!((d * d - d2).abs() <= 1e-12 * (1.0 + d2), "{p:?}: {d} {d2}");
        }
        // A segment of zero length is a point.
        assert_eq!(
            segment_distance_sq([[1.0, 1.0], [1.0, 1.0]], [4.0, 5.0]),
            25.0
        );
    }

    #[test]
    fn a_bound_changes_nothing_below_it() {
        let mut grid = ClearanceGrid::default();
        let mut out = Vec::new();
        for (n, spread) in [(2, 1.0), (40, 5.0), (500, 30.0), (500, 3000.0)] {
            let states = scatter(n, 7 * n as u64, spread);
            // Bounds from deep overlap to none: some below each robot's
            // clearance, some above, some within a cell, some wider.
            let bound = |i: usize| match i % 5 {
                0 => f64::INFINITY,
                1 => -1.0,
                2 => 0.05 * (i % 7) as f64,
                3 => spread / 10.0,
                _ => brute(&states, &[], i) + 1e-9,
            };
            grid.clearances_below(&states, &[], n, bound, &mut out);
            for (i, c) in out.iter().enumerate() {
                let exact = brute(&states, &[], i);
                assert_eq!(
                    c.min(bound(i)).to_bits(),
                    exact.min(bound(i)).to_bits(),
                    "n {n} robot {i}: {c} with bound {}, exact {exact}",
                    bound(i)
                );
            }
        }
    }

    #[test]
    fn robots_with_small_bounds_get_the_same_clearance_from_the_fine_grid() {
        let mut grid = ClearanceGrid::default();
        let mut out = Vec::new();
        // Scattered, and two long crossing lines (one coarse cell then
        // holds dozens of bodies: what the fine grid is for).
        let mut layouts: Vec<Vec<BodyState>> = [(40, 5.0), (500, 30.0), (1000, 3000.0)]
            .iter()
            .map(|&(n, spread)| scatter(n, 11 * n as u64, spread))
            .collect();
        let mut lines = scatter(600, 5, 1.0);
        for (k, b) in lines.iter_mut().enumerate() {
            let t = (k / 2) as f64 * 0.6 + 0.01 * (k % 7) as f64;
            b.position = if k % 2 == 0 {
                [t - 90.0, 0.3]
            } else {
                [0.2, t - 90.0]
            };
        }
        layouts.push(lines);
        for states in &layouts {
            let n = states.len();
            // Nine in ten bounds small (fine grid); a few wide or none
            // (the coarse grid's box and rings).
            let bound = |i: usize| match (i % 25, i % 4) {
                (0, _) => f64::INFINITY,
                (1, _) => 40.0,
                (_, 0) => -1.0,
                (_, 1) => 0.05 * (i % 7) as f64,
                (_, 2) => brute(states, &[], i) + 1e-9,
                _ => brute(states, &[], i) - 1e-9,
            };
            grid.clearances_below(states, &[], n, bound, &mut out);
            for (i, c) in out.iter().enumerate() {
                let exact = brute(states, &[], i);
                assert_eq!(
                    c.min(bound(i)).to_bits(),
                    exact.min(bound(i)).to_bits(),
                    "n {n} robot {i}: {c} with bound {}, exact {exact}",
                    bound(i)
                );
            }
        }
        // The fine grid was used (nine in ten robots bounded).
        assert!(!grid.fine.is_empty());
    }

    #[test]
    fn a_lone_robot_has_no_clearance_and_stacked_robots_overlap() {
        let mut grid = ClearanceGrid::default();
        let mut out = Vec::new();
        let one = scatter(1, 1, 1.0);
        grid.clearances(&one, &[], 1, &mut out);
        assert_eq!(out, vec![f64::INFINITY]);
        let mut two = scatter(2, 2, 1.0);
        two[1].position = two[0].position;
        grid.clearances(&two, &[], 2, &mut out);
        assert!(out.iter().all(|c| *c < 0.0));
    }
}
