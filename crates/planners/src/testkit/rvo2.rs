//! RVO2's own examples (snape/RVO2, `examples/Circle.cc` and
//! `examples/Blocks.cc`) as testkit scenes, for orca's tests and for
//! reproducing BENCHMARKS.md's comparison with RVO2 (`cargo run --release
//! -p mrsim-planners --features testkit --example rvo2_blocks`).

use super::Sim;
use crate::orca::Orca;
use crate::{Segment, Vec2};

/// RVO2's Circle example with `n` agents on a circle of `radius`, each
/// start moved by up to `jitter` in x and y (a fixed-seed generator:
/// real robots are never placed with perfect symmetry).
pub fn circle(n: usize, radius: f64, jitter: f64, max_neighbors: usize) -> (Sim, Vec<Vec2>) {
    let mut state: u64 = 12345;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut sim = Sim::new(0.25, 1);
    let mut goals = Vec::new();
    for i in 0..n {
        let a = i as f64 * std::f64::consts::TAU / n as f64;
        let on_circle = Vec2::new(a.cos(), a.sin()) * radius;
        goals.push(-on_circle);
        let start = on_circle + Vec2::new(uniform(), uniform()) * jitter;
        let mut planner = Orca::default();
        planner.max_neighbors = max_neighbors;
        sim.add_robot(
            Box::new(planner),
            start,
            -on_circle,
            1.5,
            1.0,
            0.0,
            2.0,
            1e12,
        );
    }
    (sim, goals)
}

/// ORCA with RVO2's Blocks parameters and perturbation, `seed` drawn.
pub fn blocks_orca(seed: u64) -> Orca {
    let mut orca = Orca::new(15.0, 10, 5.0, 5.0, 1.0);
    orca.perturb = 1e-4;
    orca.seed = seed;
    orca
}

/// RVO2's Blocks example: 100 agents, in Blocks.cc's order (per cell of a
/// 5 x 5 grid, one agent of each corner group), each heading for the
/// opposite corner, with RVO2's four squares as four walls each and
/// [`blocks_orca`]'s parameters and perturbation `seed`.
pub fn blocks(seed: u64) -> (Sim, Vec<Vec2>) {
    let polygons = [
        [(-10.0, 40.0), (-40.0, 40.0), (-40.0, 10.0), (-10.0, 10.0)],
        [(10.0, 40.0), (10.0, 10.0), (40.0, 10.0), (40.0, 40.0)],
        [(10.0, -40.0), (40.0, -40.0), (40.0, -10.0), (10.0, -10.0)],
        [
            (-10.0, -40.0),
            (-10.0, -10.0),
            (-40.0, -10.0),
            (-40.0, -40.0),
        ],
    ];
    let seg = |a: (f64, f64), b: (f64, f64)| Segment {
        a: Vec2::new(a.0, a.1),
        b: Vec2::new(b.0, b.1),
    };
    let mut sim = Sim::new(0.25, 1);
    for p in polygons {
        sim.walls.extend((0..4).map(|k| seg(p[k], p[(k + 1) % 4])));
    }
    let mut goals = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let (x, y) = (55.0 + 10.0 * i as f64, 55.0 + 10.0 * j as f64);
            for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                let goal = Vec2::new(-75.0 * sx, -75.0 * sy);
                goals.push(goal);
                let start = Vec2::new(x * sx, y * sy);
                let orca = Box::new(blocks_orca(seed));
                sim.add_robot(orca, start, goal, 2.0, 1.0, 0.0, 2.0, 1e12);
            }
        }
    }
    (sim, goals)
}

/// The agents of a [`blocks`] scene not yet within 20 of their goals
/// (Blocks.cc's `reachedGoal` holds when there are none).
pub fn blocks_not_in(sim: &Sim, goals: &[Vec2]) -> Vec<usize> {
    sim.robots
        .iter()
        .zip(goals)
        .enumerate()
        .filter(|(_, (r, g))| (r.state.position - *g).norm_squared() > 400.0)
        .map(|(i, _)| i)
        .collect()
}
