//! The nearest place off another robot's way: where a robot that yields at
//! a narrow passage goes to wait (the rule is the route layer's, in the
//! agents crate).

use crate::grid::Clearance;
use crate::{Entry, P, Path, along, dist};
use std::collections::BinaryHeap;

/// Distance from `p` to the segment `a`-`b`.
fn to_segment(p: P, a: P, b: P) -> f64 {
    let t = along(p, a, b);
    dist(p, [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t])
}

/// Distance from `p` to the polyline `way` (to its point if it has one, +inf if
/// empty).
pub fn to_way(p: P, way: &[P]) -> f64 {
    match way {
        [] => f64::INFINITY,
        [q] => dist(p, *q),
        _ => way
            .windows(2)
            .map(|w| to_segment(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min),
    }
}

/// Where to wait, off a way others need.
#[derive(Debug, Clone, Copy)]
pub struct Refuge<'a> {
    /// Where the robot stands.
    pub from: P,
    /// Its radius: it crosses only cells with at least this clearance.
    pub radius: f64,
    /// The clearance the place itself must have (at least `radius`).
    pub room: f64,
    /// The way to leave free, a polyline.
    pub way: &'a [P],
    /// How far from `way` the place must be.
    pub off: f64,
    /// Other bodies (centre, radius), as obstacles.
    pub blocked: &'a [(P, f64)],
    /// How far (along the way there) to look at most.
    pub within: f64,
}

impl Clearance {
    /// The way to the nearest cell centre, by the length of the way there
    /// (Dijkstra over the cells a disc of `radius` fits in, around
    /// `blocked`), that has at least `room` of clearance and lies at least
    /// `off` from `way`; none within `within`. The way starts at `from`
    /// and ends at that centre, through the centres of every other cell.
    pub fn refuge(&self, q: &Refuge) -> Option<Path> {
        let (s0, s1) = self.cell(q.from)?;
        let w = self.w;
        let near = q.radius + self.res * 1.5;
        let clear = |k: usize| -> f64 {
            let p = self.centre(k % w, k / w);
            let mut c = self.c[k];
            for &(b, r) in q.blocked {
                c = c.min(dist(p, b) - r);
            }
            c
        };
        let mut cost = vec![f64::INFINITY; w * self.h];
        let mut from = vec![usize::MAX; w * self.h];
        let mut open = BinaryHeap::new();
        let sk = s1 * w + s0;
        cost[sk] = 0.0;
        open.push(Entry { key: 0.0, cell: sk });
        while let Some(Entry { key: c0, cell }) = open.pop() {
            if c0 > cost[cell] {
                continue;
            }
            let p = self.centre(cell % w, cell / w);
            if clear(cell) >= q.room && to_way(p, q.way) >= q.off {
                let mut cells = vec![cell];
                while let Some(&k) = cells.last() {
                    if k == sk {
                        break;
                    }
                    cells.push(from[k]);
                }
                let mut pts = vec![q.from];
                pts.extend(
                    cells
                        .iter()
                        .rev()
                        .skip(1)
                        .step_by(2)
                        .map(|&k| self.centre(k % w, k / w)),
                );
                if pts.last() != Some(&p) {
                    pts.push(p);
                }
                return Some(Path::new(pts));
            }
            let (i, j) = ((cell % w) as i64, (cell / w) as i64);
            for (di, dj, len) in crate::search::NEIGHBOURS {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= w as i64 || nj >= self.h as i64 {
                    continue;
                }
                let n = nj as usize * w + ni as usize;
                let next = c0 + len * self.res;
                if next > q.within || next >= cost[n] {
                    continue;
                }
                let np = self.centre(ni as usize, nj as usize);
                if clear(n) < q.radius && dist(np, q.from) > near {
                    continue;
                }
                cost[n] = next;
                from[n] = cell;
                open.push(Entry { key: next, cell: n });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A corridor 1 m wide along y = 0 from x = 0 to 10, with a bay 1.2 m
    /// deep on its upper side between x = 6 and x = 7.
    fn corridor_with_bay() -> Clearance {
        let walls = [
            [[0.0, -0.5], [10.0, -0.5]],
            [[0.0, 0.5], [6.0, 0.5]],
            [[6.0, 0.5], [6.0, 1.7]],
            [[6.0, 1.7], [7.0, 1.7]],
            [[7.0, 1.7], [7.0, 0.5]],
            [[7.0, 0.5], [10.0, 0.5]],
            [[0.0, -0.5], [0.0, 0.5]],
            [[10.0, -0.5], [10.0, 0.5]],
        ];
        Clearance::of_walls(&walls)
    }

    #[test]
    fn the_refuge_is_the_nearest_bay_off_the_way_not_back_down_the_corridor() {
        let g = corridor_with_bay();
        let way = [[9.0, 0.0], [4.0, 0.0], [0.0, 0.0]];
        let q = Refuge {
            from: [4.0, 0.0],
            radius: 0.2,
            room: 0.25,
            way: &way,
            off: 0.65,
            blocked: &[([5.0, 0.0], 0.2)],
            within: 8.0,
        };
        // Only the bay is 0.65 m off the corridor's axis; the robot ahead
        // at x = 5 blocks the corridor, so no refuge is reachable.
        assert_eq!(g.refuge(&q), None);
        let q = Refuge {
            blocked: &[([8.5, 0.0], 0.2)],
            ..q
        };
        let way = g.refuge(&q).expect("the bay");
        assert_eq!(way.points()[0], [4.0, 0.0]);
        let p = *way.points().last().expect("an end");
        assert!((6.0..=7.0).contains(&p[0]) && p[1] >= 0.65, "{p:?}");
        assert!(g.at(p) >= 0.25, "{p:?}");
    }

    #[test]
    fn no_refuge_beyond_the_distance_looked_at() {
        let g = corridor_with_bay();
        let way = [[9.0, 0.0], [0.0, 0.0]];
        let q = Refuge {
            from: [2.0, 0.0],
            radius: 0.2,
            room: 0.25,
            way: &way,
            off: 0.65,
            blocked: &[],
            within: 3.0,
        };
        assert_eq!(g.refuge(&q), None);
        assert!(g.refuge(&Refuge { within: 6.0, ..q }).is_some());
    }
}
