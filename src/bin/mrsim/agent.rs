//! `mrsim agent`: one robot's agent process.

use crate::cli::{AgentArgs, LinkArg};
use crate::exit::fail;
use anyhow::Result;
use mrsim_runtime::agent::{AgentRequest, Misbehave};
use std::time::Duration;

/// Runs `mrsim agent`; returns the exit status.
pub fn main(args: &AgentArgs) -> Result<i32> {
    let robots = match &args.robot {
        Some(r) => vec![r.clone()],
        None => args.robots.clone(),
    };
    let who = robots.join(",");
    let end = mrsim_runtime::agent::run(&AgentRequest {
        robots,
        run_id: args.run.clone(),
        timeout: Duration::from_secs_f64(args.timeout),
        misbehave: Misbehave {
            impersonate: args.impersonate,
            fault: args.fault,
            protocol_version: args.protocol_version,
        },
        usage_out: args.usage_out.clone(),
        zenoh: (args.transport == LinkArg::Zenoh).then(|| args.zenoh.options(args.connect.clone())),
        reconnect: Duration::try_from_secs_f64(args.reconnect)
            .map_err(|e| crate::exit::invalid(format!("--reconnect {}: {e}", args.reconnect)))?,
    });
    if let (Some(e), Some(path)) = (&end.usage_error, &args.usage_out) {
        eprintln!("warning: agent {who}: cannot write {}: {e}", path.display());
    }
    end.result.map_err(fail)?;
    Ok(0)
}
