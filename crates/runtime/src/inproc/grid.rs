//! The bodies of one snapshot on a grid, for the in-process pool's
//! observations.

use mrsim_agents::Driver;

/// The bodies of one snapshot bucketed in square cells at least as wide as
/// any of a worker's robots can sense (plus the largest body radius), so
/// each robot's observation looks at the 3 x 3 cells around it instead of
/// every body: at 1000 robots the full scans were half of all CPU time.
/// The candidates are handed over in ascending index order, the order of a
/// full scan, so the observation and everything after it are the same.
#[derive(Default)]
pub(super) struct Grid {
    cell: f64,
    /// (cell key, body index), sorted.
    keyed: Vec<(i64, u32)>,
}

impl Grid {
    /// Buckets `bodies` for robots sensing up to `reach`; false (no grid)
    /// when no robot has a finite reach, or a position is not finite.
    pub(super) fn build(&mut self, bodies: &[mrsim_proto::BodyState], reach: Option<f64>) -> bool {
        self.keyed.clear();
        let Some(reach) = reach else {
            return false;
        };
        let rmax = bodies.iter().map(|b| b.radius).fold(0.0f64, f64::max);
        self.cell = (reach + rmax) * (1.0 + 1e-9) + 1e-9;
        if !self.cell.is_finite() || self.cell <= 0.0 {
            return false;
        }
        for (i, b) in bodies.iter().enumerate() {
            match self.key(b.position) {
                Some(k) => self.keyed.push((k, i as u32)),
                None => {
                    self.keyed.clear();
                    return false;
                }
            }
        }
        self.keyed.sort_unstable();
        true
    }

    fn cell_of(&self, p: [f64; 2]) -> Option<(i64, i64)> {
        let (x, y) = (p[0] / self.cell, p[1] / self.cell);
        // Far outside any arena (or not finite): no grid for this snapshot.
        let ok = |v: f64| v.is_finite() && v.abs() < 1e9;
        (ok(x) && ok(y)).then(|| (x.floor() as i64, y.floor() as i64))
    }

    fn key(&self, p: [f64; 2]) -> Option<i64> {
        self.cell_of(p).map(|(cx, cy)| Self::pack(cx, cy))
    }

    fn pack(cx: i64, cy: i64) -> i64 {
        (cx << 32) ^ (cy & 0xffff_ffff)
    }

    /// Fills `out` with the indices of the bodies in the 3 x 3 cells
    /// around `d`'s robot, ascending; false if `d` needs a full scan (its
    /// reach is unlimited or wider than a cell, or its position unknown).
    pub(super) fn near(
        &self,
        d: &Driver,
        bodies: &[mrsim_proto::BodyState],
        out: &mut Vec<u32>,
    ) -> bool {
        out.clear();
        let (Some(reach), Some(p)) = (d.reach(), d.position(bodies)) else {
            return false;
        };
        self.near_point(reach, p, out)
    }

    /// [`Self::near`] for a robot at `p` sensing up to `reach`.
    fn near_point(&self, reach: f64, p: [f64; 2], out: &mut Vec<u32>) -> bool {
        out.clear();
        if reach > self.cell {
            return false;
        }
        let Some((cx, cy)) = self.cell_of(p) else {
            return false;
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                let k = Self::pack(cx + dx, cy + dy);
                let from = self.keyed.partition_point(|&(key, _)| key < k);
                out.extend(
                    self.keyed[from..]
                        .iter()
                        .take_while(|&&(key, _)| key == k)
                        .map(|&(_, i)| i),
                );
            }
        }
        out.sort_unstable();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::BodyState;

    #[test]
    fn grid_candidates_hold_every_body_within_reach_in_index_order() {
        let mut x = 7u64;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let bodies: Vec<BodyState> = (0..400)
            .map(|i| BodyState {
                id: i,
                position: [next() * 40.0 - 20.0, next() * 40.0 - 20.0],
                radius: 0.1 + 0.4 * next(),
                ..Default::default()
            })
            .collect();
        let mut grid = Grid::default();
        let reach = 3.0;
        assert!(grid.build(&bodies, Some(reach)));
        let mut out = Vec::new();
        for me in &bodies {
            assert!(grid.near_point(reach, me.position, &mut out));
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending");
            for b in &bodies {
                let (dx, dy) = (
                    b.position[0] - me.position[0],
                    b.position[1] - me.position[1],
                );
                if (dx * dx + dy * dy).sqrt() - b.radius <= reach {
                    assert!(out.contains(&b.id), "body {} missed", b.id);
                }
            }
        }
        // No grid without a finite reach or with a position that is not finite.
        assert!(!grid.build(&bodies, None));
        let mut bad = bodies.clone();
        bad[3].position[0] = f64::NAN;
        assert!(!grid.build(&bad, Some(reach)));
    }
}
