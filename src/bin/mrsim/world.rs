//! `mrsim world`: a world process, started by `mrsim run` or by hand.

use crate::cli::{LinkArg, WorldArgs};
use crate::exit::{EXIT_INTERRUPTED, fail};
use anyhow::Result;
use mrsim_runtime::Validated;
use mrsim_runtime::world::WorldRequest;
use std::time::Duration;

/// Runs `mrsim world`; returns the exit status.
pub fn main(args: &WorldArgs) -> Result<i32> {
    let validated = Validated::new(args.scenario.source()).map_err(fail)?;
    let req = WorldRequest {
        run_id: args.run.clone(),
        out: args.scenario.out.clone(),
        start_timeout: args.start_timeout.map(Duration::from_secs_f64),
        launched: args.launched,
        zenoh: (args.transport == LinkArg::Zenoh).then(|| args.zenoh.options(args.listen.clone())),
    };
    let agent_flags = match &req.zenoh {
        None => String::new(),
        Some(z) => format!(
            " --transport zenoh --connect {}",
            z.endpoint
                .as_deref()
                .unwrap_or(mrsim_transport::zenoh::DEFAULT_ENDPOINT)
        ),
    };
    let ended = mrsim_runtime::world::serve(validated, &req, &mut |run_id, scenario| {
        eprintln!(
            "world: run `{run_id}`, {} robots; start each agent with\n  mrsim agent --run {run_id} --robot NAME{agent_flags}\nfor NAME in: {}",
            scenario.robots.len(),
            scenario
                .robots
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    })
    .map_err(fail)?;
    if let Some(finished) = &ended.finished {
        crate::outcome::print(finished, false);
    }
    Ok(if ended.interrupted {
        EXIT_INTERRUPTED
    } else {
        0
    })
}
