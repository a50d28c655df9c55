//! A* over the clearance grid, the widest way when A* finds none, and the
//! string pulling that straightens the grid path (crate documentation).

use crate::grid::Clearance;
use crate::{Entry, NARROW_COST, P, Path, RouteError};
use std::collections::BinaryHeap;

pub(crate) const NEIGHBOURS: [(i64, i64, f64); 8] = [
    (1, 0, 1.0),
    (-1, 0, 1.0),
    (0, 1, 1.0),
    (0, -1, 1.0),
    (1, 1, std::f64::consts::SQRT_2),
    (1, -1, std::f64::consts::SQRT_2),
    (-1, 1, std::f64::consts::SQRT_2),
    (-1, -1, std::f64::consts::SQRT_2),
];

impl Clearance {
    /// The shortest route for a disc of `radius` from `start` to `goal`
    /// keeping `margin` more where it can (crate documentation), with the
    /// discs of `blocked` (centre, radius: robots standing in the way, for
    /// a replan) as extra obstacles. First point `start`, last `goal`.
    pub fn route(
        &self,
        start: P,
        goal: P,
        radius: f64,
        margin: f64,
        blocked: &[(P, f64)],
    ) -> Result<Path, RouteError> {
        let s = self.cell(start).ok_or(RouteError::Outside {
            which: "start",
            at: start,
        })?;
        let g = self.cell(goal).ok_or(RouteError::Outside {
            which: "goal",
            at: goal,
        })?;
        let (w, h) = (self.w, self.h);
        let (sk, gk) = (s.1 * w + s.0, g.1 * w + g.0);
        // Cells near the start and goal are open whatever the grid says
        // (the scenario checked those places; the grid is a cell coarse).
        let near = radius + self.res * 1.5;
        let clear = |k: usize| -> f64 {
            let p = self.centre(k % w, k / w);
            let mut c = self.c[k];
            for &(q, r) in blocked {
                c = c.min(crate::dist(p, q) - r);
            }
            if crate::dist(p, start) <= near || crate::dist(p, goal) <= near {
                c = c.max(radius + margin);
            }
            c
        };
        let want = radius + margin;
        let factor = |c: f64| {
            if c >= want || margin <= 0.0 {
                1.0
            } else {
                1.0 + (NARROW_COST - 1.0) * ((want - c) / margin).clamp(0.0, 1.0)
            }
        };
        let gc = self.centre(g.0, g.1);
        let heur = |k: usize| crate::dist(self.centre(k % w, k / w), gc);
        let mut cost = vec![f64::INFINITY; w * h];
        let mut from = vec![usize::MAX; w * h];
        let mut open = BinaryHeap::new();
        cost[sk] = 0.0;
        open.push(Entry {
            key: heur(sk),
            cell: sk,
        });
        let mut found = false;
        while let Some(Entry { key, cell }) = open.pop() {
            if cell == gk {
                found = true;
                break;
            }
            if key - heur(cell) > cost[cell] + 1e-9 {
                continue;
            }
            let (i, j) = ((cell % w) as i64, (cell / w) as i64);
            for (di, dj, len) in NEIGHBOURS {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                    continue;
                }
                let n = nj as usize * w + ni as usize;
                let c = clear(n);
                if c < radius {
                    continue;
                }
                let next = cost[cell] + len * self.res * factor(c);
                if next < cost[n] {
                    cost[n] = next;
                    from[n] = cell;
                    open.push(Entry {
                        key: next + heur(n),
                        cell: n,
                    });
                }
            }
        }
        if !found {
            return Err(RouteError::TooNarrow {
                radius,
                widest: self.widest(sk, gk, &clear),
            });
        }
        let mut cells = vec![gk];
        while let Some(&k) = cells.last() {
            if k == sk {
                break;
            }
            cells.push(from[k]);
        }
        cells.reverse();
        let mut pts: Vec<(P, f64)> = cells
            .iter()
            .map(|&k| (self.centre(k % w, k / w), clear(k)))
            .collect();
        pts[0].0 = start;
        if let Some(last) = pts.last_mut() {
            last.0 = goal;
        }
        if pts.len() == 1 {
            pts.push((goal, want));
        }
        Ok(Path::new(self.pull(&pts, want, &clear)))
    }

    /// The clearance at the narrowest point of the widest way from cell
    /// `s` to cell `g` (a bottleneck search: largest first).
    fn widest(&self, s: usize, g: usize, clear: &dyn Fn(usize) -> f64) -> f64 {
        let (w, h) = (self.w, self.h);
        let mut best = vec![f64::NEG_INFINITY; w * h];
        let mut open = BinaryHeap::new();
        best[s] = f64::INFINITY;
        open.push(Entry {
            key: f64::NEG_INFINITY,
            cell: s,
        });
        while let Some(Entry { key, cell }) = open.pop() {
            let width = -key;
            if cell == g {
                return width;
            }
            if width < best[cell] {
                continue;
            }
            let (i, j) = ((cell % w) as i64, (cell / w) as i64);
            for (di, dj, _) in NEIGHBOURS {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                    continue;
                }
                let n = nj as usize * w + ni as usize;
                let b = width.min(clear(n));
                if b > best[n] {
                    best[n] = b;
                    open.push(Entry { key: -b, cell: n });
                }
            }
        }
        0.0
    }

    /// String pulling: from each kept point, the furthest later point of
    /// the grid path whose straight line keeps as much clearance as the
    /// grid path between them (or `want`, whichever is less).
    fn pull(&self, pts: &[(P, f64)], want: f64, clear: &dyn Fn(usize) -> f64) -> Vec<P> {
        let mut out = vec![pts[0].0];
        let mut a = 0;
        while a + 1 < pts.len() {
            let mut need = f64::INFINITY;
            let mut best = a + 1;
            for (b, &(_, c)) in pts.iter().enumerate().skip(a + 1) {
                need = need.min(c);
                if self.line_clear(pts[a].0, pts[b].0, need.min(want), clear) {
                    best = b;
                }
            }
            out.push(pts[best].0);
            a = best;
        }
        out
    }

    /// Can a disc of `radius` go straight from `a` to `b`: does every
    /// cell the line crosses have at least `radius` of clearance?
    /// Cells within `radius` of `a` are not looked at (the disc is there
    /// already).
    pub fn sees(&self, a: P, b: P, radius: f64) -> bool {
        self.line_clear(a, b, radius, &|k| {
            let c = self.centre(k % self.w, k / self.w);
            if crate::dist(c, a) <= radius {
                f64::INFINITY
            } else {
                self.c[k]
            }
        })
    }

    /// Does every cell the line from `a` to `b` crosses have at least
    /// `need` of clearance?
    pub(crate) fn line_clear(&self, a: P, b: P, need: f64, clear: &dyn Fn(usize) -> f64) -> bool {
        let n = (crate::dist(a, b) / (self.res * 0.5)).ceil().max(1.0) as usize;
        (0..=n).all(|k| {
            let t = k as f64 / n as f64;
            let p = [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
            self.cell(p)
                .is_some_and(|(i, j)| clear(j * self.w + i) >= need - 1e-9)
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::{Clearance, RouteError};

    /// A 10 x 6 room split by a wall at x = 5 with a gap of `gap` at y = 3.
    fn room(gap: f64) -> Clearance {
        let walls = [
            [[0.0, 0.0], [10.0, 0.0]],
            [[10.0, 0.0], [10.0, 6.0]],
            [[10.0, 6.0], [0.0, 6.0]],
            [[0.0, 6.0], [0.0, 0.0]],
            [[5.0, 0.0], [5.0, 3.0 - gap / 2.0]],
            [[5.0, 3.0 + gap / 2.0], [5.0, 6.0]],
        ];
        Clearance::of_walls(&walls)
    }

    #[test]
    fn a_route_goes_through_the_gap_in_straight_legs() {
        let g = room(1.0);
        let p = g
            .route([2.0, 1.0], [8.0, 1.0], 0.2, 0.1, &[])
            .expect("a way");
        let pts = p.points();
        assert_eq!(pts.first(), Some(&[2.0, 1.0]));
        assert_eq!(pts.last(), Some(&[8.0, 1.0]));
        // Through the gap: some leg crosses x = 5 within y in (2.5, 3.5).
        assert!(pts.len() <= 5, "{pts:?}");
        let crossing = pts.windows(2).find(|w| w[0][0] < 5.0 && w[1][0] >= 5.0);
        let [a, b] = crossing.expect("crosses the wall").try_into().expect("two");
        let y = a[1] + (b[1] - a[1]) * (5.0 - a[0]) / (b[0] - a[0]);
        assert!((2.7..=3.3).contains(&y), "{y}");
        // About the length of the two straight lines to the gap's middle.
        let direct = 2.0 * (3.0f64.powi(2) + 2.0f64.powi(2)).sqrt();
        assert!(p.length() < direct + 0.3, "{} vs {direct}", p.length());
    }

    #[test]
    fn a_gap_narrower_than_the_disc_is_refused_and_its_width_told() {
        let g = room(0.3);
        let err = g
            .route([2.0, 1.0], [8.0, 1.0], 0.2, 0.1, &[])
            .expect_err("no way for a 0.4 m disc through 0.3 m");
        let RouteError::TooNarrow { widest, .. } = err else {
            panic!("{err}");
        };
        assert!((widest - 0.15).abs() < 0.03, "{widest}");
        // A smaller disc passes.
        assert!(g.route([2.0, 1.0], [8.0, 1.0], 0.1, 0.1, &[]).is_ok());
    }

    #[test]
    fn a_robot_in_the_gap_closes_it_for_a_replan() {
        let g = room(1.0);
        let blocked = [([5.0, 3.0], 0.3)];
        assert!(matches!(
            g.route([2.0, 1.0], [8.0, 1.0], 0.2, 0.1, &blocked),
            Err(RouteError::TooNarrow { .. })
        ));
    }
}
