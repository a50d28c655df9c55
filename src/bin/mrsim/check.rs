//! `mrsim check`: validate a scenario without running it.

use crate::cli::ScenarioArgs;
use crate::exit::fail;
use anyhow::Result;
use mrsim_runtime::Validated;

/// Runs `mrsim check`; returns the exit status.
pub fn main(args: &ScenarioArgs) -> Result<i32> {
    let v = Validated::new(args.source()).map_err(fail)?;
    println!(
        "{}: ok ({} robots, {} obstacles)",
        v.origin(),
        v.scenario().robots.len(),
        v.scenario().obstacles.len()
    );
    Ok(0)
}
