//! `mrsim rerun RUN_DIR [--out DIR] [--set KEY=VALUE]...`: a recorded run
//! again in lockstep with its recorded timing (`mrsim_runtime::rerun`).

use crate::cli::RerunArgs;
use anyhow::Result;
use mrsim_planners::Registry;
use mrsim_runtime::rerun::{Rerun, rerun};
use std::sync::Arc;

/// Runs `mrsim rerun`; returns the exit status.
pub fn main(args: &RerunArgs) -> Result<i32> {
    let req = Rerun {
        run: args.run.clone(),
        out: args.out.clone(),
        set: args.set.clone(),
        registry: Arc::new(Registry::builtin()),
        render: !args.no_report,
    };
    let done = rerun(&req).map_err(crate::exit::fail)?;
    for (robot, planner) in &done.not_deterministic {
        println!(
            "note: robot `{robot}`'s planner `{planner}` is not built in and may not be \
             deterministic: the rerun may differ from the record there"
        );
    }
    let what = if args.set.is_empty() {
        "rerun"
    } else {
        "counterfactual"
    };
    println!(
        "{what} of {} in {}: {} ticks",
        args.run.display(),
        done.result.dir.display(),
        done.result.metrics.ticks
    );
    Ok(0)
}
