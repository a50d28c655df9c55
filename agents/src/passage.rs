//! Narrow passages on a route: the stretches of a robot's route (`route =
//! "shortest"`) too narrow for two of it side by side (a door), where two
//! robots meeting head-on cannot pass.
//!
//! **Marking them.** Every point of the route, a quarter of the grid's
//! cell apart, whose free width across the route (from the point along the
//! route's normal to the walls on either side, over the route's clearance
//! grid, by sphere tracing) is less than [`need`], three widths of the
//! robot's footprint (two of it side by side, and half a width beside and
//! between them), is narrow; runs of such points nearer than the `join`
//! given (the footprint's length, say) are one stretch ([`narrow`]). A
//! 1.2 m door is such a stretch for a 0.6 m wide AGV (it needs 1.8 m); a
//! 2 m corridor, where two pass, is not.
//!
//! The marking is what a rule of taking turns at doors (the first to
//! arrive goes through, the other holds short of the stretch, as cars give
//! way at crossings in [`crate::car_route`]) starts from; no robot's route
//! following uses it yet.

use mrsim_route::{Clearance, P, Path};

/// The free width across a route below which a robot of footprint width
/// `width` (twice its inscribed radius) cannot pass another there: three
/// widths.
pub fn need(width: f64) -> f64 {
    3.0 * width
}

/// A narrow stretch of a route.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretch {
    /// Where it begins along the route, m.
    pub from: f64,
    /// Where it ends along the route, m.
    pub to: f64,
    /// Its middle point.
    pub mid: P,
    /// The route's direction through it (a unit vector).
    pub dir: P,
    /// Its least free width across the route, m.
    pub width: f64,
}

/// How far from `q` along the unit vector `n` the first wall is on `grid`,
/// up to `cap`: sphere tracing over the clearance (each step the clearance
/// there, less a cell's diagonal for the grid's rounding).
fn ray(grid: &Clearance, q: P, n: P, cap: f64) -> f64 {
    let res = grid.resolution();
    let mut a = 0.0;
    while a < cap {
        let d = grid.at([q[0] + n[0] * a, q[1] + n[1] * a]);
        if d < res {
            return a + d;
        }
        a += (d - res * std::f64::consts::SQRT_2).max(res / 4.0);
    }
    cap
}

/// The unit direction of `path` at `s` (over a stretch `h` either side).
fn direction(path: &Path, s: f64, h: f64) -> Option<P> {
    let (a, b) = (path.at(s - h), path.at(s + h));
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = dx.hypot(dy);
    (l > 1e-9).then(|| [dx / l, dy / l])
}

/// The free width across `path` at `s` on `grid`, up to `cap`.
fn width_at(grid: &Clearance, path: &Path, s: f64, cap: f64) -> f64 {
    let q = path.at(s);
    if grid.at(q) >= cap / 2.0 {
        return cap;
    }
    let Some(t) = direction(path, s, 2.0 * grid.resolution()) else {
        return cap;
    };
    let n = [-t[1], t[0]];
    let left = ray(grid, q, n, cap);
    let right = ray(grid, q, [-n[0], -n[1]], cap);
    (left + right).min(cap)
}

/// The narrow stretches of `path` on `grid` (module documentation): where
/// the free width across it is less than `need`, runs nearer than `join`
/// made one.
pub fn narrow(grid: &Clearance, path: &Path, need: f64, join: f64) -> Vec<Stretch> {
    let len = path.length();
    let step = grid.resolution() / 4.0;
    let mut runs: Vec<(f64, f64, f64)> = Vec::new();
    let mut s = 0.0;
    while s <= len {
        let w = width_at(grid, path, s, need);
        if w < need {
            match runs.last_mut() {
                Some(r) if s - r.1 <= join => {
                    r.1 = s;
                    r.2 = r.2.min(w);
                }
                _ => runs.push((s, s, w)),
            }
        }
        s += step;
    }
    runs.into_iter()
        .map(|(from, to, width)| {
            let h = (2.0 * grid.resolution()).max((to - from) / 2.0);
            let mid = (from + to) / 2.0;
            Stretch {
                from,
                to,
                mid: path.at(mid),
                dir: direction(path, mid, h).unwrap_or([1.0, 0.0]),
                width,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_route::Scene;

    /// A wall across y = 0 from x = -5 to 5 with a gap `door` wide at
    /// x = 0, and a corridor `corridor` wide along y from -5 to -1
    /// (walls at x = -corridor/2 and +corridor/2) below it.
    fn walls(door: f64, corridor: f64) -> Vec<[P; 2]> {
        vec![
            [[-5.0, 0.0], [-door / 2.0, 0.0]],
            [[door / 2.0, 0.0], [5.0, 0.0]],
            [[-corridor / 2.0, -5.0], [-corridor / 2.0, -1.0]],
            [[corridor / 2.0, -5.0], [corridor / 2.0, -1.0]],
        ]
    }

    #[test]
    fn a_door_on_the_route_is_a_narrow_stretch_and_a_wide_corridor_is_not() {
        let w = walls(1.2, 2.0);
        let grid = Clearance::build(&Scene {
            walls: &w,
            discs: &[],
            points: &[[0.0, -4.5], [0.0, 4.0]],
            resolution: 0.05,
            pad: 1.0,
        });
        // Up the corridor's middle, through the door, into the room.
        let path = Path::new(vec![[0.0, -4.5], [0.0, 4.0]]);
        let found = narrow(&grid, &path, need(0.6), 0.9);
        assert_eq!(found.len(), 1, "{found:?}");
        let st = found[0];
        // The door is at 4.5 m along the route; the stretch holds it and
        // not the corridor (which ends at 3.5 m).
        assert!(st.from > 3.6 && st.from <= 4.5, "{st:?}");
        assert!(st.to >= 4.5 && st.to < 5.4, "{st:?}");
        assert!((st.width - 1.2).abs() < 0.1, "{st:?}");
        assert!(st.mid[1].abs() < 0.3 && st.mid[0].abs() < 1e-9, "{st:?}");
        assert!((st.dir[1] - 1.0).abs() < 1e-9, "{st:?}");
        // A door as wide as the need is not narrow.
        let w = walls(1.9, 2.0);
        let grid = Clearance::build(&Scene {
            walls: &w,
            discs: &[],
            points: &[[0.0, -4.5], [0.0, 4.0]],
            resolution: 0.05,
            pad: 1.0,
        });
        assert!(narrow(&grid, &path, need(0.6), 0.9).is_empty());
        // A corridor narrower than the need is narrow along its length.
        let w = walls(1.9, 1.4);
        let grid = Clearance::build(&Scene {
            walls: &w,
            discs: &[],
            points: &[[0.0, -4.5], [0.0, 4.0]],
            resolution: 0.05,
            pad: 1.0,
        });
        let found = narrow(&grid, &path, need(0.6), 0.9);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].from < 0.1 && found[0].to > 3.4, "{found:?}");
    }

    #[test]
    fn each_agv_route_through_the_office_is_narrow_at_its_two_doors_only() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenarios/shapes/agv-swap.toml");
        let s = mrsim_scenario::load(&file).expect("the AGV scene").scenario;
        let scene = crate::route::RouteScene::of(&s);
        for spec in &s.robots {
            let (grid, path) = scene.route(spec).expect("a route");
            let body = spec.body_shape();
            let found = narrow(
                &grid,
                &path,
                need(2.0 * body.inradius()),
                2.0 * body.circumradius(),
            );
            // Out of its room through one door, along the corridor (2 m:
            // not narrow) and in through another: each stretch in a 1.2 m
            // door of the walls at y = +-1.1, doors at x = -9, -3, 3, 9.
            assert_eq!(found.len(), 2, "{}: {found:?}", spec.name);
            for st in &found {
                let door = (st.mid[0] / 3.0).round() * 3.0;
                assert!(
                    (st.mid[0] - door).abs() < 0.1
                        && (door / 3.0).rem_euclid(2.0) == 1.0
                        && (st.mid[1].abs() - 1.1).abs() < 0.1,
                    "{}: {st:?}",
                    spec.name
                );
                assert!((st.width - 1.2).abs() < 0.1, "{}: {st:?}", spec.name);
                assert!(st.dir[1].abs() > 0.99, "{}: {st:?}", spec.name);
            }
        }
    }
}
