//! A bucket grid of a run's wall segments, so that dwa on true states
//! checks each chord of an arc against the few walls near it rather than
//! against every wall within the robot's reach (a map's traced outlines
//! hold thousands of segments).
//!
//! Built once for the walls a planner is given (a run's walls are fixed:
//! the grid is rebuilt only when the slice given changes), each segment
//! entered in every cell its bounding box covers; a query returns, once
//! each and in their order in the slice, the segments whose cells meet a
//! box. A segment the box does not reach may be returned (it shares a
//! cell); one it reaches always is.

use crate::{Segment, Vec2};

/// Cells per axis at most (the cell grows on very large maps).
const MAX_CELLS: f64 = 2048.0;

/// Walls bucketed on a square grid.
#[derive(Debug, Clone, Default)]
pub(super) struct WallGrid {
    /// What the grid was built for: the slice's address, length, first
    /// and last segment.
    key: Option<(usize, usize, Segment, Segment)>,
    origin: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `k`'s segments are `items[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Per segment, the query that last returned it (dedup).
    seen: Vec<u32>,
    query: u32,
    /// Per segment, the last [`WallGrid::near`] call that found it within
    /// reach.
    near: Vec<u32>,
    round: u32,
}

impl WallGrid {
    /// Makes the grid hold `walls` (cell side `cell`, or larger on a large
    /// map), unless it already does.
    pub(super) fn prepare(&mut self, walls: &[Segment], cell: f64) {
        let key = match (walls.first(), walls.last()) {
            (Some(&f), Some(&l)) => Some((walls.as_ptr() as usize, walls.len(), f, l)),
            _ => None,
        };
        if key.is_some() && key == self.key {
            return;
        }
        self.key = key;
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        for p in walls.iter().flat_map(|w| [w.a, w.b]) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        if walls.is_empty() || !lo.iter().chain(hi.iter()).all(|x| x.is_finite()) {
            *self = Self::default();
            return;
        }
        let span = (hi - lo).max();
        let cell = if cell.is_finite() && cell > 0.0 {
            cell.max(span / MAX_CELLS)
        } else {
            (span / MAX_CELLS).max(1.0)
        };
        let cell = if cell > 0.0 { cell } else { 1.0 };
        self.origin = lo;
        self.cell = cell;
        self.nx = ((hi.x - lo.x) / cell).floor() as usize + 1;
        self.ny = ((hi.y - lo.y) / cell).floor() as usize + 1;
        // Counting pass, then filling (a compressed row layout).
        let mut counts = vec![0u32; self.nx * self.ny + 1];
        for w in walls {
            let (i0, j0, i1, j1) = self.cells(w.a.inf(&w.b), w.a.sup(&w.b));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    counts[j * self.nx + i + 1] += 1;
                }
            }
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let mut fill = counts.clone();
        self.items = vec![0; counts[counts.len() - 1] as usize];
        for (s, w) in walls.iter().enumerate() {
            let (i0, j0, i1, j1) = self.cells(w.a.inf(&w.b), w.a.sup(&w.b));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let k = j * self.nx + i;
                    self.items[fill[k] as usize] = s as u32;
                    fill[k] += 1;
                }
            }
        }
        self.starts = counts;
        self.seen = vec![0; walls.len()];
        self.query = 0;
        self.near = vec![0; walls.len()];
        self.round = 0;
    }

    /// The segments of `walls` (those the grid was prepared with) whose
    /// closest point is within `reach` of `p`, in their order; remembered
    /// for [`WallGrid::query_near`].
    pub(super) fn near(&mut self, walls: &[Segment], p: Vec2, reach: f64) -> Vec<u32> {
        let mut out = Vec::new();
        let r = Vec2::repeat(reach);
        self.query(p - r, p + r, true, &mut out);
        out.retain(|&s| (walls[s as usize].closest_point(p) - p).norm() <= reach);
        self.round = self.round.wrapping_add(1);
        if self.round == 0 {
            self.near.iter_mut().for_each(|s| *s = 0);
            self.round = 1;
        }
        for &s in &out {
            self.near[s as usize] = self.round;
        }
        out
    }

    /// As [`WallGrid::query`] (unsorted), keeping only the segments the
    /// last [`WallGrid::near`] found.
    pub(super) fn query_near(&mut self, lo: Vec2, hi: Vec2, out: &mut Vec<u32>) {
        self.query(lo, hi, false, out);
        let (near, round) = (&self.near, self.round);
        out.retain(|&s| near[s as usize] == round);
    }

    /// The cell range covering the box `lo`..`hi`, clamped to the grid.
    fn cells(&self, lo: Vec2, hi: Vec2) -> (usize, usize, usize, usize) {
        let f = |x: f64, o: f64, n: usize| {
            (((x - o) / self.cell).floor().max(0.0) as usize).min(n.saturating_sub(1))
        };
        (
            f(lo.x, self.origin.x, self.nx),
            f(lo.y, self.origin.y, self.ny),
            f(hi.x, self.origin.x, self.nx),
            f(hi.y, self.origin.y, self.ny),
        )
    }

    /// Appends to `out` (cleared first) the indices of the segments in
    /// the cells that the box `lo`..`hi` meets, each once, in ascending
    /// order when `sorted`.
    pub(super) fn query(&mut self, lo: Vec2, hi: Vec2, sorted: bool, out: &mut Vec<u32>) {
        out.clear();
        if self.nx == 0
            || hi.x < self.origin.x
            || hi.y < self.origin.y
            || lo.x > self.origin.x + self.cell * self.nx as f64
            || lo.y > self.origin.y + self.cell * self.ny as f64
        {
            return;
        }
        self.query = self.query.wrapping_add(1);
        if self.query == 0 {
            self.seen.iter_mut().for_each(|s| *s = 0);
            self.query = 1;
        }
        let (i0, j0, i1, j1) = self.cells(lo, hi);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.nx + i;
                for &s in &self.items[self.starts[k] as usize..self.starts[k + 1] as usize] {
                    if self.seen[s as usize] != self.query {
                        self.seen[s as usize] = self.query;
                        out.push(s);
                    }
                }
            }
        }
        if sorted {
            out.sort_unstable();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
        Segment {
            a: Vec2::new(ax, ay),
            b: Vec2::new(bx, by),
        }
    }

    #[test]
    fn a_query_returns_every_segment_its_box_reaches_once_and_in_order() {
        // A 10 x 10 square room and a diagonal inside, cells of 1.
        let walls = [
            seg(0.0, 0.0, 10.0, 0.0),
            seg(10.0, 0.0, 10.0, 10.0),
            seg(10.0, 10.0, 0.0, 10.0),
            seg(0.0, 10.0, 0.0, 0.0),
            seg(2.0, 2.0, 8.0, 8.0),
        ];
        let mut grid = WallGrid::default();
        grid.prepare(&walls, 1.0);
        let mut out = Vec::new();
        // Near the bottom-left corner: the two walls meeting there and the
        // diagonal, whose box begins at (2, 2).
        grid.query(Vec2::new(0.5, 0.5), Vec2::new(2.5, 2.5), true, &mut out);
        assert_eq!(out, vec![0, 3, 4]);
        // The middle, away from every wall but the diagonal.
        grid.query(Vec2::new(4.2, 4.2), Vec2::new(4.8, 4.8), true, &mut out);
        assert_eq!(out, vec![4]);
        // The whole room, and a box outside it.
        grid.query(Vec2::new(-1.0, -1.0), Vec2::new(11.0, 11.0), true, &mut out);
        assert_eq!(out, vec![0, 1, 2, 3, 4]);
        grid.query(Vec2::new(20.0, 20.0), Vec2::new(21.0, 21.0), true, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn a_query_finds_what_a_scan_of_every_wall_finds() {
        // Short segments scattered as a map's outlines are: every segment
        // within 0.4 of a point is among those the grid returns for the
        // point's box.
        let walls: Vec<Segment> = (0..400)
            .map(|k| {
                let (x, y) = ((k * 37 % 101) as f64 * 0.1, (k * 53 % 97) as f64 * 0.1);
                seg(x, y, x + 0.07 * (k % 3) as f64, y + 0.05 * (k % 5) as f64)
            })
            .collect();
        let mut grid = WallGrid::default();
        grid.prepare(&walls, 0.5);
        let mut out = Vec::new();
        for p in [
            Vec2::new(3.3, 4.1),
            Vec2::new(0.0, 0.0),
            Vec2::new(9.9, 9.5),
        ] {
            let r = Vec2::repeat(0.4);
            grid.query(p - r, p + r, true, &mut out);
            for (k, w) in walls.iter().enumerate() {
                if (w.closest_point(p) - p).norm() <= 0.4 {
                    assert!(out.contains(&(k as u32)), "{k} near {p:?} missed");
                }
            }
        }
    }

    #[test]
    fn the_grid_is_rebuilt_for_other_walls() {
        let mut grid = WallGrid::default();
        let one = [seg(0.0, 0.0, 1.0, 0.0)];
        grid.prepare(&one, 1.0);
        let two = vec![seg(5.0, 5.0, 6.0, 5.0), seg(5.0, 6.0, 6.0, 6.0)];
        grid.prepare(&two, 1.0);
        let mut out = Vec::new();
        grid.query(Vec2::new(4.0, 4.0), Vec2::new(7.0, 7.0), true, &mut out);
        assert_eq!(out, vec![0, 1]);
        grid.prepare(&[], 1.0);
        grid.query(Vec2::new(4.0, 4.0), Vec2::new(7.0, 7.0), true, &mut out);
        assert!(out.is_empty());
    }
}
