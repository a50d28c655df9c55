//! One uniform-grid spatial hash over discs (centre and radius), for the
//! two neighbour searches of mrsim: the world's clearance metric (each
//! robot's nearest body) and the in-process pool's observations (the
//! bodies a robot can sense).
//!
//! The pieces, from the bottom:
//!
//! - [`Buckets`]: discs sorted by bucket with a counting sort, each
//!   bucket's indices and discs side by side, so a bucket's search reads
//!   one run of memory.
//! - Two ways of naming a disc's bucket: [`BoundedGrid`], a grid over a
//!   box with one bucket per cell (about one cell per disc; coordinates
//!   outside clamp to the border), and [`HashedGrid`], an unbounded grid
//!   of a chosen cell size whose cells hash into about two buckets per
//!   disc (only occupied cells cost anything; discs of other cells that
//!   share a bucket are told apart by their cell, or ruled out by their
//!   distance).
//! - [`NeighbourGrid`]: a [`HashedGrid`] with cells as wide as a sensing
//!   reach plus the largest radius, asked for the discs of the 3 x 3 cells
//!   around a point that come within reach of it, in ascending index
//!   order.
//!
//! # How the in-process pool uses it
//!
//! Once per snapshot the pool calls
//! `grid.build(bodies.iter().map(|b| [b.position[0], b.position[1], b.radius]), reach)`
//! with the largest finite sensing reach of its robots; for each robot,
//! `grid.near(position, robot_reach, &mut candidates)`. When `build` or
//! `near` says `false` (no finite reach, a position not finite, a reach
//! wider than a cell) the robot's observation scans every body; otherwise
//! it scans only `candidates`, which hold every body whose disc comes
//! within the reach, in the order of a full scan, so the observation is
//! the same.
#![warn(missing_docs)]

/// A disc: centre x, centre y, radius.
pub type Disc = [f64; 3];

/// Discs sorted by bucket (a counting sort): bucket `c` holds discs
/// `order[start[c]..start[c + 1]]` (their indices in the input), whose
/// discs are copied in the same order into `at`.
#[derive(Debug, Clone, Default)]
pub struct Buckets {
    start: Vec<u32>,
    order: Vec<u32>,
    at: Vec<Disc>,
    key: Vec<u32>,
    fill: Vec<u32>,
    unsorted: Vec<Disc>,
}

impl Buckets {
    /// Sorts the discs of `items` (bucket, disc), disc `j` being the `j`th
    /// item, into `buckets` buckets. A bucket must be below `buckets`.
    pub fn sort(&mut self, buckets: usize, items: impl Iterator<Item = (usize, Disc)>) {
        self.start.clear();
        self.start.resize(buckets + 1, 0);
        self.key.clear();
        self.unsorted.clear();
        for (c, d) in items {
            self.key.push(c as u32);
            self.unsorted.push(d);
            self.start[c + 1] += 1;
        }
        for c in 0..buckets {
            self.start[c + 1] += self.start[c];
        }
        self.order.clear();
        self.order.resize(self.key.len(), 0);
        self.fill.clear();
        self.fill.extend_from_slice(&self.start[..buckets]);
        for (j, &c) in self.key.iter().enumerate() {
            self.order[self.fill[c as usize] as usize] = j as u32;
            self.fill[c as usize] += 1;
        }
        self.at.clear();
        let unsorted = &self.unsorted;
        self.at
            .extend(self.order.iter().map(|&j| unsorted[j as usize]));
    }

    /// Bucket `c`'s disc indices and discs, side by side.
    pub fn bucket(&self, c: usize) -> (&[u32], &[Disc]) {
        let range = self.start[c] as usize..self.start[c + 1] as usize;
        (&self.order[range.clone()], &self.at[range])
    }

    /// The bucket disc `j` was sorted into.
    pub fn bucket_of(&self, j: usize) -> usize {
        self.key[j] as usize
    }

    /// Renames every sorted disc `j` to `name(j)` in what
    /// [`Self::bucket`] reports ([`Self::bucket_of`] still takes the
    /// position in the sorted input).
    pub fn rename(&mut self, name: impl Fn(u32) -> u32) {
        for j in &mut self.order {
            *j = name(*j);
        }
    }

    /// Number of discs sorted.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// True if no disc was sorted.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }
}

/// The smallest box holding every centre, and the largest radius; `None`
/// when there are no discs or a centre is not finite.
pub fn bounds(discs: impl Iterator<Item = Disc>) -> Option<([f64; 2], [f64; 2], f64)> {
    let (mut lo, mut hi, mut rmax, mut any) = ([f64::MAX; 2], [f64::MIN; 2], 0.0f64, false);
    let mut finite = true;
    for [x, y, r] in discs {
        // min and max pass over a NaN: look for it.
        finite &= x.is_finite() && y.is_finite();
        for (k, v) in [x, y].into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
        rmax = rmax.max(r);
        any = true;
    }
    (any && finite).then_some((lo, hi, rmax))
}

/// A grid over a box, one bucket per cell: origin, cell size and cell
/// counts. Coordinates outside the box clamp to its border cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedGrid {
    /// The box's lower corner.
    pub lo: [f64; 2],
    /// Cell width.
    pub cell: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
}

impl BoundedGrid {
    /// About one cell per disc over the box `lo`..`hi` for `n` discs,
    /// never narrower than the largest diameter, at most about 4n cells
    /// whatever the box's shape.
    pub fn spanning(lo: [f64; 2], hi: [f64; 2], n: usize, rmax: f64) -> Self {
        let (w, h) = ((hi[0] - lo[0]).max(1e-9), (hi[1] - lo[1]).max(1e-9));
        let mut cell = (w * h / n as f64).sqrt().max(2.0 * rmax).max(1e-9);
        while (w / cell + 1.0) * (h / cell + 1.0) > 4.0 * n as f64 + 4.0 {
            cell *= 1.5;
        }
        Self {
            lo,
            cell,
            nx: (w / cell) as usize + 1,
            ny: (h / cell) as usize + 1,
        }
    }

    /// The cell column (`k` = 0) or row (`k` = 1) of coordinate `v`,
    /// clamped into the grid.
    pub fn at(&self, v: f64, k: usize) -> usize {
        let n = if k == 0 { self.nx } else { self.ny };
        // `as` saturates: below the origin gives 0.
        (((v - self.lo[k]) / self.cell) as usize).min(n - 1)
    }

    /// Number of buckets (cells).
    pub fn buckets(&self) -> usize {
        self.nx * self.ny
    }

    /// The bucket of cell (`x`, `y`).
    pub fn bucket(&self, x: usize, y: usize) -> usize {
        y * self.nx + x
    }

    /// The bucket of the cell holding point (`x`, `y`).
    pub fn bucket_at(&self, x: f64, y: f64) -> usize {
        self.bucket(self.at(x, 0), self.at(y, 1))
    }
}

/// An unbounded grid of cells of a given width from an origin, hashed
/// into `1 << bits` buckets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HashedGrid {
    /// The origin.
    pub lo: [f64; 2],
    /// Cell width.
    pub cell: f64,
    /// Log2 of the number of buckets.
    pub bits: u32,
}

impl HashedGrid {
    /// Cells of `cell` from `lo` for `n` discs spanning `span` (the larger
    /// side of their box): about two buckets per disc, at least 16. `None`
    /// when the cell is not a positive finite width or the cells would be
    /// too many to index (beyond 2^40 along a side).
    pub fn new(lo: [f64; 2], cell: f64, n: usize, span: f64) -> Option<Self> {
        if !cell.is_finite() || cell <= 0.0 || span / cell > 1e12 {
            return None;
        }
        let bits = (2 * n).next_power_of_two().trailing_zeros().max(4);
        Some(Self { lo, cell, bits })
    }

    /// The cell index of coordinate `v` on axis `k`: truncated, not
    /// floored (no libm call), which merges cells -1 and 0 but keeps the
    /// index monotonic in `v`, all a search box needs. `as` saturates.
    pub fn at(&self, v: f64, k: usize) -> i64 {
        ((v - self.lo[k]) / self.cell) as i64
    }

    /// Number of buckets.
    pub fn buckets(&self) -> usize {
        1 << self.bits
    }

    /// The bucket of cell (`x`, `y`).
    pub fn bucket(&self, x: i64, y: i64) -> usize {
        let h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        (h >> (64 - self.bits)) as usize
    }
}

/// The discs of one moment bucketed in square cells at least as wide as a
/// sensing reach plus the largest radius, so that every disc within reach
/// of a point lies in the 3 x 3 cells around it.
#[derive(Debug, Clone, Default)]
pub struct NeighbourGrid {
    grid: Option<HashedGrid>,
    buckets: Buckets,
    /// Each sorted disc's cell, in bucket order (bodies of other cells that
    /// share a bucket are told apart by it).
    cells: Vec<(i64, i64)>,
}

impl NeighbourGrid {
    /// Buckets `discs` for searches of up to `reach` (surface to centre);
    /// false (no grid) when `reach` is not finite, a centre is not finite,
    /// or the discs span too many cells.
    pub fn build(
        &mut self,
        discs: impl ExactSizeIterator<Item = Disc> + Clone,
        reach: f64,
    ) -> bool {
        self.grid = None;
        self.cells.clear();
        let Some((lo, hi, rmax)) = bounds(discs.clone()) else {
            return false;
        };
        let cell = (reach + rmax) * (1.0 + 1e-9) + 1e-9;
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let Some(g) = HashedGrid::new(lo, cell, discs.len(), span) else {
            return false;
        };
        self.buckets.sort(
            g.buckets(),
            discs.map(|d| (g.bucket(g.at(d[0], 0), g.at(d[1], 1)), d)),
        );
        self.cells.extend(
            self.buckets
                .at
                .iter()
                .map(|d| (g.at(d[0], 0), g.at(d[1], 1))),
        );
        self.grid = Some(g);
        true
    }

    /// [`Self::build`] over some of the discs, each named by the index
    /// that [`Self::near`] reports for it: a caller that buckets only the
    /// discs that can matter (those near the points it will ask about)
    /// names them by their index among all the discs. Names must ascend
    /// in `named`'s order, so that answers stay in ascending order.
    pub fn build_named(&mut self, named: &[(u32, Disc)], reach: f64) -> bool {
        let built = self.build(named.iter().map(|(_, d)| *d), reach);
        if built {
            self.buckets.rename(|j| named[j as usize].0);
        }
        built
    }

    /// Fills `out` with the indices of every disc that may come within
    /// `reach` of `p` (every one whose surface does, and others within
    /// rounding of it),
    /// ascending; false, with `out` empty, if the grid cannot answer
    /// (none built, `reach` wider than it was built for, `p` not finite).
    pub fn near(&self, p: [f64; 2], reach: f64, out: &mut Vec<u32>) -> bool {
        self.near_from(p, reach, 0, out)
    }

    /// [`Self::near`], keeping only the discs of index `first` or more: a
    /// caller that visits each pair once (i < j) skips the other half
    /// before it is sorted.
    pub fn near_from(&self, p: [f64; 2], reach: f64, first: u32, out: &mut Vec<u32>) -> bool {
        out.clear();
        let Some(g) = self.grid else {
            return false;
        };
        if reach.is_nan() || reach > g.cell || !p.iter().all(|v| v.is_finite()) {
            return false;
        }
        // Floored, so a point below the origin has its own cell.
        let cx = ((p[0] - g.lo[0]) / g.cell).floor();
        let cy = ((p[1] - g.lo[1]) / g.cell).floor();
        if !(cx.abs() < 1e15 && cy.abs() < 1e15) {
            return false;
        }
        self.each_around(g, (cx as i64, cy as i64), |j, _, d| {
            // Only discs whose surface may come within reach: fewer to
            // sort, and fewer for the caller to rule out.
            if j >= first && within(d, p, reach) {
                out.push(j);
            }
        });
        out.sort_unstable();
        true
    }
}

impl NeighbourGrid {
    /// The discs in the order the grid holds them, bucket by bucket, each
    /// with its cell: a caller that asks about every disc's neighbours
    /// visits them in this order, so that the discs of one cell come
    /// together and one [`Self::around_cell`] serves them all.
    pub fn in_cell_order(&self) -> impl Iterator<Item = (u32, (i64, i64))> + '_ {
        self.buckets
            .order
            .iter()
            .copied()
            .zip(self.cells.iter().copied())
    }

    /// Fills `out` with the index, slot and disc of every disc in the 3 x 3
    /// cells around `cell` (a cell of [`Self::in_cell_order`]), ascending
    /// by index: what [`Self::near`] chooses from for any point of that
    /// cell, so that keeping those for which [`within`] holds gives its
    /// answer for the point. A disc's slot is its place in
    /// [`Self::in_cell_order`], so that what a caller keeps of each disc
    /// in that order (a velocity, say) is read from the runs of memory of
    /// the nine cells, not picked out by index. Empty when no grid was
    /// built.
    pub fn around_cell(&self, cell: (i64, i64), out: &mut Vec<(u32, u32, Disc)>) {
        out.clear();
        let Some(g) = self.grid else {
            return;
        };
        self.each_around(g, cell, |j, slot, d| out.push((j, slot, *d)));
        out.sort_unstable_by_key(|&(j, _, _)| j);
    }
}

impl NeighbourGrid {
    /// Calls `f` with the index, slot and disc of every disc in the 3 x 3
    /// cells around `(cx, cy)` of grid `g`, bucket by bucket.
    fn each_around(&self, g: HashedGrid, (cx, cy): (i64, i64), mut f: impl FnMut(u32, u32, &Disc)) {
        let mut seen = [usize::MAX; 9];
        for (n, (dx, dy)) in (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
            .enumerate()
        {
            let b = g.bucket(cx + dx, cy + dy);
            // Two of the nine cells in one bucket: its discs once.
            if seen[..n].contains(&b) {
                continue;
            }
            seen[n] = b;
            let start = self.buckets.start[b] as usize;
            let (idx, discs) = self.buckets.bucket(b);
            for (k, (&j, d)) in idx.iter().zip(discs).enumerate() {
                let (x, y) = self.cells[start + k];
                if (x - cx).abs() <= 1 && (y - cy).abs() <= 1 {
                    f(j, (start + k) as u32, d);
                }
            }
        }
    }
}

/// Whether disc `d`'s surface may come within `reach` of `p`: every disc
/// whose surface does, and others within rounding of it, so that none
/// within reach is lost to rounding. [`NeighbourGrid::near`] answers the
/// discs of the 3 x 3 cells for which this holds.
pub fn within(d: &Disc, p: [f64; 2], reach: f64) -> bool {
    let (dx, dy) = (d[0] - p[0], d[1] - p[1]);
    let r = (reach + d[2]) * (1.0 + 1e-9) + 1e-9;
    dx * dx + dy * dy <= r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scatter(n: usize, seed: u64, spread: f64) -> Vec<Disc> {
        let mut x = seed;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                [
                    spread * (next() - 0.5),
                    spread * (next() - 0.5),
                    0.1 + 0.4 * next(),
                ]
            })
            .collect()
    }

    #[test]
    fn buckets_hold_every_disc_once_in_input_order_within_a_bucket() {
        let discs = scatter(200, 3, 10.0);
        let mut b = Buckets::default();
        b.sort(7, discs.iter().enumerate().map(|(j, d)| (j % 7, *d)));
        assert_eq!(b.len(), 200);
        let mut all = Vec::new();
        for c in 0..7 {
            let (idx, at) = b.bucket(c);
            assert!(idx.windows(2).all(|w| w[0] < w[1]));
            for (&j, d) in idx.iter().zip(at) {
                assert_eq!(j as usize % 7, c);
                assert_eq!(*d, discs[j as usize]);
                assert_eq!(b.bucket_of(j as usize), c);
            }
            all.extend_from_slice(idx);
        }
        all.sort_unstable();
        assert_eq!(all, (0..200).collect::<Vec<u32>>());
    }

    #[test]
    fn a_bounded_grid_clamps_points_outside_its_box_to_the_border() {
        let g = BoundedGrid::spanning([0.0, 0.0], [10.0, 5.0], 50, 0.1);
        assert!(g.nx * g.ny <= 4 * 50 + 4);
        assert_eq!(g.at(-3.0, 0), 0);
        assert_eq!(g.at(1e9, 1), g.ny - 1);
        assert_eq!(g.bucket_at(1e9, 1e9), g.buckets() - 1);
        // Never narrower than the largest diameter.
        assert!(BoundedGrid::spanning([0.0; 2], [1.0; 2], 1000, 0.3).cell >= 0.6);
    }

    #[test]
    fn neighbours_are_the_discs_within_reach_in_index_order() {
        for (n, spread, reach) in [(400, 40.0, 3.0), (50, 2.0, 0.5), (300, 4000.0, 1.0)] {
            let discs = scatter(n, n as u64, spread);
            let mut grid = NeighbourGrid::default();
            assert!(grid.build(discs.iter().copied(), reach));
            let mut out = Vec::new();
            for me in &discs {
                assert!(grid.near([me[0], me[1]], reach, &mut out));
                assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending");
                for (j, d) in discs.iter().enumerate() {
                    let dist = (d[0] - me[0]).hypot(d[1] - me[1]) - d[2];
                    if dist <= reach {
                        assert!(out.contains(&(j as u32)), "disc {j} missed");
                    } else if dist > reach * 1.001 + 1e-6 {
                        assert!(!out.contains(&(j as u32)), "disc {j} beyond reach");
                    }
                }
            }
            // A point outside the discs' box: still every disc within reach.
            let p = [-spread, spread];
            assert!(grid.near(p, reach, &mut out));
            for (j, d) in discs.iter().enumerate() {
                if (d[0] - p[0]).hypot(d[1] - p[1]) - d[2] <= reach {
                    assert!(out.contains(&(j as u32)));
                }
            }
        }
    }

    #[test]
    fn a_grid_of_some_named_discs_answers_with_their_names() {
        let discs = scatter(400, 5, 40.0);
        let mut all = NeighbourGrid::default();
        assert!(all.build(discs.iter().copied(), 3.0));
        // Only the discs of the left half, named by their index among all.
        let named: Vec<(u32, Disc)> = discs
            .iter()
            .enumerate()
            .filter(|(_, d)| d[0] < 0.0)
            .map(|(j, d)| (j as u32, *d))
            .collect();
        let mut some = NeighbourGrid::default();
        assert!(some.build_named(&named, 3.0));
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for me in discs.iter().filter(|d| d[0] < -10.0) {
            assert!(all.near([me[0], me[1]], 3.0, &mut a));
            assert!(some.near([me[0], me[1]], 3.0, &mut b));
            // Far from the cut, the left half's answer is the whole one's
            // among the left half, under the same names.
            a.retain(|&j| discs[j as usize][0] < 0.0);
            let exact = |v: &Vec<u32>| -> Vec<u32> {
                v.iter()
                    .copied()
                    .filter(|&j| {
                        let d = discs[j as usize];
                        (d[0] - me[0]).hypot(d[1] - me[1]) - d[2] <= 3.0
                    })
                    .collect()
            };
            assert_eq!(exact(&a), exact(&b));
            assert!(b.windows(2).all(|w| w[0] < w[1]), "ascending");
        }
    }

    #[test]
    fn a_cells_neighbours_within_reach_of_each_of_its_discs_are_that_discs_neighbours() {
        let discs = scatter(500, 7, 30.0);
        let reach = 2.0;
        let mut grid = NeighbourGrid::default();
        assert!(grid.build(discs.iter().copied(), reach));
        let (mut near, mut around) = (Vec::new(), Vec::new());
        let mut visited = vec![false; discs.len()];
        let order: Vec<_> = grid.in_cell_order().collect();
        for &(j, cell) in &order {
            visited[j as usize] = true;
            let p = [discs[j as usize][0], discs[j as usize][1]];
            assert!(grid.near(p, reach, &mut near));
            grid.around_cell(cell, &mut around);
            let kept: Vec<u32> = around
                .iter()
                .filter(|(_, _, d)| within(d, p, reach))
                .map(|(k, _, _)| *k)
                .collect();
            assert_eq!(kept, near, "disc {j}");
            for &(k, slot, d) in &around {
                assert_eq!(order[slot as usize].0, k, "disc {k}'s slot");
                assert_eq!(d, discs[k as usize]);
            }
        }
        assert!(visited.iter().all(|&v| v), "every disc once");
    }

    #[test]
    fn neighbours_from_an_index_are_the_neighbours_of_that_index_or_more() {
        let discs = scatter(300, 9, 20.0);
        let mut grid = NeighbourGrid::default();
        assert!(grid.build(discs.iter().copied(), 2.0));
        let (mut all, mut from) = (Vec::new(), Vec::new());
        for (i, me) in discs.iter().enumerate() {
            let first = i as u32 + 1;
            assert!(grid.near([me[0], me[1]], 2.0, &mut all));
            assert!(grid.near_from([me[0], me[1]], 2.0, first, &mut from));
            all.retain(|&j| j >= first);
            assert_eq!(from, all, "disc {i}");
        }
    }

    #[test]
    fn no_neighbour_grid_without_a_finite_reach_or_finite_centres() {
        let discs = scatter(30, 1, 5.0);
        let mut grid = NeighbourGrid::default();
        assert!(!grid.build(discs.iter().copied(), f64::INFINITY));
        let mut bad = discs.clone();
        bad[3][0] = f64::NAN;
        assert!(!grid.build(bad.iter().copied(), 1.0));
        let mut out = vec![1];
        assert!(!grid.near([0.0, 0.0], 1.0, &mut out));
        assert!(out.is_empty());
        // Built for a reach of 1: a wider one needs a full scan.
        assert!(grid.build(discs.iter().copied(), 1.0));
        assert!(!grid.near([0.0, 0.0], 5.0, &mut out));
        assert!(grid.near([0.0, 0.0], 1.0, &mut out));
    }
}
