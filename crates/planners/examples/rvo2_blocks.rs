//! RVO2's Blocks example in the testkit, one line per perturbation seed:
//! the makespan in steps, the smallest gap between two agents, and the
//! agents not in when it stops at step 20,000 (BENCHMARKS.md, "ORCA vs
//! RVO2", the 100-seed table). Seeds 1 to 10 are also a unit test
//! (`rvo2_blocks_takes_the_published_number_of_steps_for_each_of_ten_seeds`).
//!
//! ```text
//! cargo run --release -p mrsim-planners --features testkit --example rvo2_blocks -- 1-100
//! ```

use mrsim_planners::testkit::{Sim, rvo2};

/// Parses `A-B` or `A` (default 1-10).
fn seeds(arg: Option<String>) -> Result<(u64, u64), String> {
    let Some(s) = arg else {
        return Ok((1, 10));
    };
    let (a, b) = s.split_once('-').unwrap_or((&s, &s));
    let parse = |x: &str| {
        x.trim()
            .parse::<u64>()
            .map_err(|e| format!("seed range `{s}`: `{x}` is not a seed ({e}); expected A-B or A"))
    };
    Ok((parse(a)?, parse(b)?))
}

fn gap(sim: &Sim, i: usize, j: usize) -> f64 {
    let (a, b) = (&sim.robots[i].state, &sim.robots[j].state);
    (a.position - b.position).norm() - a.radius - b.radius
}

fn main() {
    let (first, last) = match seeds(std::env::args().nth(1)) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("rvo2_blocks: {e}");
            std::process::exit(2);
        }
    };
    for seed in first..=last {
        let (mut sim, goals) = rvo2::blocks(seed);
        let (mut min_gap, mut steps) = (f64::INFINITY, 0);
        while steps < 20_000 && !rvo2::blocks_not_in(&sim, &goals).is_empty() {
            sim.step();
            steps += 1;
            for i in 0..sim.robots.len() {
                for j in i + 1..sim.robots.len() {
                    min_gap = min_gap.min(gap(&sim, i, j));
                }
            }
        }
        let out: Vec<String> = rvo2::blocks_not_in(&sim, &goals)
            .into_iter()
            .map(|i| {
                let p = sim.robots[i].state.position;
                format!("a{i} at ({:.2}, {:.2})", p.x, p.y)
            })
            .collect();
        println!(
            "blocks seed {seed}: {} steps, min gap {min_gap:.4}{}",
            if out.is_empty() {
                steps.to_string()
            } else {
                format!("> {steps}")
            },
            if out.is_empty() {
                String::new()
            } else {
                format!(", not in: {}", out.join(", "))
            }
        );
    }
}
