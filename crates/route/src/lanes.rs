//! Keeping to one side (crate documentation, "Lanes").

use crate::grid::Clearance;
use crate::{P, Path, dist};

/// Which side of its direction of travel a route keeps to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The right of the direction of travel.
    Right,
    /// The left of the direction of travel.
    Left,
}

/// How steeply the offset may change along the route (metres sideways a
/// metre along): a lane is entered and left at about 27 degrees.
const SLOPE: f64 = 0.5;

impl Clearance {
    /// `path` moved up to `offset` towards `side` of its direction of
    /// travel wherever every point between it and its moved place keeps at
    /// least `need` of clearance (crate documentation, "Lanes"); the start
    /// and the goal stay where they are. The path itself if the moved one
    /// would anywhere come nearer a wall than `radius`.
    pub fn keep_to(&self, path: &Path, side: Side, offset: f64, need: f64, radius: f64) -> Path {
        let len = path.length();
        if offset.is_nan() || offset <= 0.0 || len.is_nan() || len <= 0.0 {
            return path.clone();
        }
        let step = (self.res / 2.0).min(offset / 2.0).max(len / 20_000.0);
        let n = (len / step).ceil().max(1.0) as usize;
        let s: Vec<f64> = (0..=n).map(|k| len * k as f64 / n as f64).collect();
        let p: Vec<P> = s.iter().map(|&s| path.at(s)).collect();
        let sign = match side {
            Side::Right => 1.0,
            Side::Left => -1.0,
        };
        // The sideways unit vector at each sample: the direction of travel
        // over the samples either side, turned a right angle.
        let normal: Vec<P> = (0..=n)
            .map(|k| {
                let (a, b) = (p[k.saturating_sub(1)], p[(k + 1).min(n)]);
                let d = dist(a, b);
                if d <= 0.0 {
                    [0.0, 0.0]
                } else {
                    [sign * (b[1] - a[1]) / d, -sign * (b[0] - a[0]) / d]
                }
            })
            .collect();
        let probe = self.res / 2.0;
        let mut o: Vec<f64> = (0..=n)
            .map(|k| {
                let (q, m) = (p[k], normal[k]);
                let mut room = 0.0;
                while room < offset {
                    let next = (room + probe).min(offset);
                    if self.at([q[0] + m[0] * next, q[1] + m[1] * next]) < need {
                        break;
                    }
                    room = next;
                }
                // None at the ends, entered and left gently.
                room.min(SLOPE * s[k]).min(SLOPE * (len - s[k]))
            })
            .collect();
        for k in 1..=n {
            o[k] = o[k].min(o[k - 1] + SLOPE * (s[k] - s[k - 1]));
        }
        for k in (0..n).rev() {
            o[k] = o[k].min(o[k + 1] + SLOPE * (s[k + 1] - s[k]));
        }
        let moved: Vec<P> = (0..=n)
            .map(|k| [p[k][0] + normal[k][0] * o[k], p[k][1] + normal[k][1] * o[k]])
            .collect();
        let mut pts = simplify(&moved, self.res / 4.0);
        pts[0] = path.points()[0];
        if let (Some(last), Some(goal)) = (pts.last_mut(), path.points().last()) {
            *last = *goal;
        }
        let fits = pts
            .windows(2)
            .all(|w| self.line_clear(w[0], w[1], radius, &|k| self.c[k]));
        if fits { Path::new(pts) } else { path.clone() }
    }
}

/// Douglas-Peucker: the fewest of `pts` whose polyline stays within `tol`
/// of all of them (first and last kept).
fn simplify(pts: &[P], tol: f64) -> Vec<P> {
    let mut keep = vec![false; pts.len()];
    keep[0] = true;
    keep[pts.len() - 1] = true;
    let mut stack = vec![(0, pts.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (pa, pb) = (pts[a], pts[b]);
        let d = dist(pa, pb);
        let (mut far, mut at) = (0.0, a);
        for (k, q) in pts.iter().enumerate().take(b).skip(a + 1) {
            let e = if d <= 0.0 {
                dist(*q, pa)
            } else {
                ((pb[0] - pa[0]) * (pa[1] - q[1]) - (pa[0] - q[0]) * (pb[1] - pa[1])).abs() / d
            };
            if e > far {
                far = e;
                at = k;
            }
        }
        if far > tol {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    pts.iter()
        .zip(keep)
        .filter_map(|(p, k)| k.then_some(*p))
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::{Clearance, Path, Side};

    /// A corridor 2 wide along x from 0 to 20, closed at both ends.
    fn corridor() -> Clearance {
        let walls = [
            [[0.0, 0.0], [20.0, 0.0]],
            [[20.0, 0.0], [20.0, 2.0]],
            [[20.0, 2.0], [0.0, 2.0]],
            [[0.0, 2.0], [0.0, 0.0]],
        ];
        Clearance::of_walls(&walls)
    }

    #[test]
    fn a_route_along_a_corridor_moves_to_the_right_of_travel_and_keeps_its_ends() {
        let g = corridor();
        let east = Path::new(vec![[1.0, 1.0], [19.0, 1.0]]);
        let moved = g.keep_to(&east, Side::Right, 0.4, 0.5, 0.25);
        let pts = moved.points();
        assert_eq!(pts.first(), Some(&[1.0, 1.0]));
        assert_eq!(pts.last(), Some(&[19.0, 1.0]));
        // Mid-corridor: 0.4 to the right of east, which is -y.
        let mid = moved.at(moved.length() / 2.0);
        assert!((mid[1] - 0.6).abs() < 0.02, "{mid:?}");
        // Westwards the other way: +y.
        let west = Path::new(vec![[19.0, 1.0], [1.0, 1.0]]);
        let mid = g.keep_to(&west, Side::Right, 0.4, 0.5, 0.25);
        let mid = mid.at(mid.length() / 2.0);
        assert!((mid[1] - 1.4).abs() < 0.02, "{mid:?}");
        let left = g.keep_to(&east, Side::Left, 0.4, 0.5, 0.25);
        let mid = left.at(left.length() / 2.0);
        assert!((mid[1] - 1.4).abs() < 0.02, "{mid:?}");
    }

    #[test]
    fn the_offset_is_what_the_walls_leave_and_none_in_a_corridor_too_narrow() {
        let g = corridor();
        let east = Path::new(vec![[1.0, 1.0], [19.0, 1.0]]);
        // Keeping 0.7 from the walls leaves 0.3 of the 0.4 asked.
        let moved = g.keep_to(&east, Side::Right, 0.4, 0.7, 0.25);
        let mid = moved.at(moved.length() / 2.0);
        assert!((mid[1] - 0.7).abs() < 0.03, "{mid:?}");
        // Keeping 1.1 leaves nothing: the route is unchanged.
        let same = g.keep_to(&east, Side::Right, 0.4, 1.1, 0.25);
        assert_eq!(same.points(), east.points());
    }
}
