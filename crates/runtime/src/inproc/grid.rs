//! The bodies of one snapshot on `mrsim-spatial`'s neighbour grid, for the
//! in-process pool's observations: at 1000 robots full scans were half of
//! all CPU time. The candidates come in ascending index order, the order of
//! a full scan, so the observation and everything after it are the same.

use mrsim_agents::Driver;
use mrsim_proto::BodyState;
use mrsim_spatial::NeighbourGrid;

/// A snapshot's bodies on a grid whose cells are as wide as the pool's
/// largest finite sensing reach plus the largest body radius.
#[derive(Debug, Default)]
pub(super) struct Grid(NeighbourGrid);

impl Grid {
    /// Buckets `bodies` for robots sensing up to `reach`; false (no grid)
    /// when no robot has a finite reach, or a position is not finite.
    pub(super) fn build(&mut self, bodies: &[BodyState], reach: Option<f64>) -> bool {
        let Some(reach) = reach else {
            return false;
        };
        self.0.build(
            bodies
                .iter()
                .map(|b| [b.position[0], b.position[1], b.radius]),
            reach,
        )
    }

    /// Fills `out` with the indices of the bodies that may be within `d`'s
    /// robot's reach, ascending; false if `d` needs a full scan (its reach
    /// is unlimited or wider than a cell, or its position unknown).
    pub(super) fn near(&self, d: &Driver, bodies: &[BodyState], out: &mut Vec<u32>) -> bool {
        out.clear();
        let (Some(reach), Some(p)) = (d.reach(), d.position(bodies)) else {
            return false;
        };
        self.0.near(p, reach, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            assert!(grid.0.near(me.position, reach, &mut out));
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
