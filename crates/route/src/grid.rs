//! The clearance grid (crate documentation, "The clearance").

use crate::P;

/// What routes go around: wall segments and static discs, and the points
/// that must lie inside the grid.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// Wall segments.
    pub walls: &'a [[P; 2]],
    /// Static discs: centre and radius.
    pub discs: &'a [(P, f64)],
    /// Points the grid must cover (robots' starts and goals).
    pub points: &'a [P],
    /// Cell size (for a map, its resolution), > 0.
    pub resolution: f64,
    /// Extra room around everything, so that a route may go round a wall's
    /// free end; at least the largest robot's radius plus margin.
    pub pad: f64,
}

/// Cells at most, the resolution coarsened until the grid fits.
const MAX_CELLS: f64 = 16.0e6;

/// Distance from each cell's centre to the nearest wall or disc rim.
#[derive(Debug, Clone)]
pub struct Clearance {
    /// Lower-left corner of cell (0, 0).
    pub(crate) origin: P,
    /// Cell size.
    pub(crate) res: f64,
    /// Cells across.
    pub(crate) w: usize,
    /// Cells up.
    pub(crate) h: usize,
    /// Clearance a cell, row by row from the bottom (+inf: nothing at all).
    pub(crate) c: Vec<f64>,
}

impl Clearance {
    /// Builds the grid over `scene`.
    pub fn build(scene: &Scene) -> Self {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let mut cover = |p: P, r: f64| {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k] - r);
                hi[k] = hi[k].max(p[k] + r);
            }
        };
        for w in scene.walls {
            cover(w[0], 0.0);
            cover(w[1], 0.0);
        }
        for &(p, r) in scene.discs {
            cover(p, r);
        }
        for &p in scene.points {
            cover(p, 0.0);
        }
        if !lo[0].is_finite() {
            lo = [0.0; 2];
            hi = [0.0; 2];
        }
        let mut res = scene.resolution;
        let pad = scene.pad.max(0.0) + 2.0 * res;
        let size = |res: f64| {
            (
                ((hi[0] - lo[0] + 2.0 * pad) / res).ceil().max(1.0),
                ((hi[1] - lo[1] + 2.0 * pad) / res).ceil().max(1.0),
            )
        };
        while {
            let (w, h) = size(res);
            w * h > MAX_CELLS
        } {
            res *= 1.5;
        }
        let (w, h) = size(res);
        let (w, h) = (w as usize, h as usize);
        let origin = [lo[0] - pad, lo[1] - pad];
        let mut g = Self {
            origin,
            res,
            w,
            h,
            c: Vec::new(),
        };
        g.c = g.propagate(scene);
        g
    }

    /// The cell of `p`, if inside.
    pub(crate) fn cell(&self, p: P) -> Option<(usize, usize)> {
        let i = ((p[0] - self.origin[0]) / self.res).floor();
        let j = ((p[1] - self.origin[1]) / self.res).floor();
        (i >= 0.0 && j >= 0.0 && i < self.w as f64 && j < self.h as f64)
            .then_some((i as usize, j as usize))
    }

    /// The centre of cell `(i, j)`.
    pub(crate) fn centre(&self, i: usize, j: usize) -> P {
        [
            self.origin[0] + (i as f64 + 0.5) * self.res,
            self.origin[1] + (j as f64 + 0.5) * self.res,
        ]
    }

    /// Clearance at the centre of the cell holding `p` (0 outside).
    pub fn at(&self, p: P) -> f64 {
        self.cell(p).map_or(0.0, |(i, j)| self.c[j * self.w + i])
    }

    /// Cell size actually used.
    pub fn resolution(&self) -> f64 {
        self.res
    }

    /// Seeds each cell with the nearest sample of the scene in it, then
    /// sweeps forwards and backwards (Danielsson's vector propagation).
    fn propagate(&self, scene: &Scene) -> Vec<f64> {
        let (w, h) = (self.w, self.h);
        let none = [f64::NAN; 2];
        let mut site = vec![none; w * h];
        let step = self.res / 2.0;
        let mut seed = |q: P| {
            if let Some((i, j)) = self.cell(q) {
                let k = j * w + i;
                let c = self.centre(i, j);
                if site[k][0].is_nan() || crate::dist(c, q) < crate::dist(c, site[k]) {
                    site[k] = q;
                }
            }
        };
        for s in scene.walls {
            let len = crate::dist(s[0], s[1]);
            let n = (len / step).ceil().max(1.0) as usize;
            for k in 0..=n {
                let t = k as f64 / n as f64;
                seed([
                    s[0][0] + (s[1][0] - s[0][0]) * t,
                    s[0][1] + (s[1][1] - s[0][1]) * t,
                ]);
            }
        }
        for &(p, r) in scene.discs {
            let n = ((std::f64::consts::TAU * r / step).ceil() as usize).max(8);
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                seed([p[0] + r * a.cos(), p[1] + r * a.sin()]);
            }
            seed(p);
        }
        let d = |k: usize, s: P| {
            if s[0].is_nan() {
                f64::INFINITY
            } else {
                crate::dist(self.centre(k % w, k / w), s)
            }
        };
        let best = |site: &mut Vec<P>, k: usize, from: usize| {
            let s = site[from];
            if !s[0].is_nan() && d(k, s) < d(k, site[k]) {
                site[k] = s;
            }
        };
        for j in 0..h {
            for i in 0..w {
                let k = j * w + i;
                if j > 0 {
                    best(&mut site, k, k - w);
                    if i > 0 {
                        best(&mut site, k, k - w - 1);
                    }
                    if i + 1 < w {
                        best(&mut site, k, k - w + 1);
                    }
                }
                if i > 0 {
                    best(&mut site, k, k - 1);
                }
            }
            for i in (0..w.saturating_sub(1)).rev() {
                let k = j * w + i;
                best(&mut site, k, k + 1);
            }
        }
        for j in (0..h).rev() {
            for i in (0..w).rev() {
                let k = j * w + i;
                if j + 1 < h {
                    best(&mut site, k, k + w);
                    if i + 1 < w {
                        best(&mut site, k, k + w + 1);
                    }
                    if i > 0 {
                        best(&mut site, k, k + w - 1);
                    }
                }
                if i + 1 < w {
                    best(&mut site, k, k + 1);
                }
            }
            for i in 1..w {
                let k = j * w + i;
                best(&mut site, k, k - 1);
            }
        }
        (0..w * h).map(|k| d(k, site[k])).collect()
    }
}

#[cfg(test)]
impl Clearance {
    /// The tests' grid: `walls` alone, cells of 0.05, padded by 0.5.
    pub(crate) fn of_walls(walls: &[[P; 2]]) -> Self {
        Self::build(&Scene {
            walls,
            discs: &[],
            points: &[],
            resolution: 0.05,
            pad: 0.5,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clearance_is_the_distance_to_the_nearest_wall_within_a_tenth_of_a_cell() {
        let walls = [[[0.0, 0.0], [10.0, 0.0]], [[0.0, 0.0], [0.0, 10.0]]];
        let g = Clearance::build(&Scene {
            walls: &walls,
            discs: &[(([6.0, 6.0]), 1.0)],
            points: &[],
            resolution: 0.1,
            pad: 1.0,
        });
        for (p, want) in [
            ([3.05, 1.05], 1.05),
            ([1.05, 4.05], 1.05),
            ([2.05, 2.55], 2.05),
            ([6.05, 3.55], 1.45),
            ([-0.55, -0.55], 0.55 * 2f64.sqrt()),
        ] {
            let got = g.at(p);
            assert!((got - want).abs() < 0.01, "{p:?}: {got} vs {want}");
        }
    }
}
