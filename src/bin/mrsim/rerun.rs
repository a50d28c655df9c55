//! `mrsim rerun RUN_DIR [--out DIR] [--set KEY=VALUE]...`: a recorded run
//! again in lockstep with its recorded timing (`mrsim_runtime::rerun`).

use anyhow::Result;
use clap::Args;
use mrsim_planners::Registry;
use mrsim_runtime::rerun::{Rerun, rerun};
use std::path::PathBuf;
use std::sync::Arc;

/// What `mrsim rerun` was asked.
#[derive(Debug, Clone, Args)]
pub struct RerunArgs {
    /// The recorded run's folder (with timing.csv, source.json, scenario.json).
    pub run: PathBuf,
    /// Output folder (default: a fresh folder under runs/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A counterfactual: override a scenario value on top of the run's own
    /// overrides (KEY=VALUE as for `run --set`); the timing stays as recorded.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Skip plot.svg, plot.png and replay.html.
    #[arg(long)]
    pub no_report: bool,
}

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
    if !done.modelled.is_empty() {
        println!(
            "modelled counterfactual: the cores' model re-decides the timing of {} \
             (another [world.cpus]); the other robots replay their recorded times",
            mrsim_world::names::first_few(&done.modelled, 8)
        );
    }
    if let Some(cut) = &done.cut {
        println!(
            "note: {} was cut (its world killed before the end): rerun up to tick {}, its \
             trajectory's last whole tick",
            args.run.display(),
            cut.tick
        );
        for c in &cut.files {
            println!("note: {c}");
        }
    }
    let what = if args.set.is_empty() {
        "rerun (recorded times)"
    } else if done.modelled.is_empty() {
        "counterfactual (recorded times)"
    } else {
        "modelled counterfactual"
    };
    println!(
        "{what} of {} in {}: {} ticks",
        args.run.display(),
        done.result.dir.display(),
        done.result.metrics.ticks
    );
    Ok(0)
}
