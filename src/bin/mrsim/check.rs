//! `mrsim check`: validate a scenario without running it; for a scenario
//! with `[world.cpus]` or CPU robots, print its task set and the verdict
//! of the schedulability tests.

use crate::cli::ScenarioArgs;
use crate::exit::fail;
use anyhow::Result;
use mrsim_runtime::Validated;
use mrsim_scenario::schedulability;

/// Runs `mrsim check`; returns the exit status.
pub fn main(args: &ScenarioArgs) -> Result<i32> {
    let v = Validated::new(args.source()).map_err(fail)?;
    println!(
        "{}: ok ({} robots, {} obstacles)",
        v.origin(),
        v.scenario().robots.len(),
        v.scenario().obstacles.len()
    );
    // With [world.cpus] or CPU robots: the task set and its verdict.
    if let Some((set, verdict)) = schedulability::of_scenario(v.scenario()) {
        print!("{}", schedulability::render(&set, &verdict));
    }
    Ok(0)
}
