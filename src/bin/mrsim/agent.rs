//! `mrsim agent`: one robot's agent process.

use crate::cli::{Connect, LinkArgs};
use crate::exit::fail;
use anyhow::Result;
use clap::Args;
use mrsim_runtime::agent::{AgentRequest, Misbehave};
use std::ffi::OsString;
use std::path::PathBuf;
use std::time::Duration;

/// `mrsim agent` options.
#[derive(Debug, Clone, Args)]
pub struct AgentArgs {
    /// The robot's name in the scenario.
    #[arg(long, required_unless_present = "robots", conflicts_with = "robots")]
    pub robot: Option<String>,
    /// Drive several robots from this one process, comma-separated (each
    /// joins with its own token and plans on its own observation).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub robots: Vec<String>,
    /// The run id of the world.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// Seconds to wait for the world.
    #[arg(long, default_value_t = 30.0)]
    pub timeout: f64,
    /// Fault injection for tests: put this robot id in every command.
    #[arg(long, hide = true)]
    pub impersonate: Option<u32>,
    /// Fault injection for tests: nan, inf, huge, other-robot, past-tick,
    /// future-tick, double, sent-late, join-twice, hang-at-tick=N, die-at-tick=N, stop-at-tick=N,
    /// slow-ms=N.
    #[arg(long, hide = true)]
    pub fault: Option<mrsim_agents::fault::Fault>,
    /// For tests of strangers: announce this protocol version.
    #[arg(long, hide = true)]
    pub protocol_version: Option<u32>,
    /// Write CPU time and peak RSS here at the end (set by `mrsim run`).
    #[arg(long, hide = true)]
    pub usage_out: Option<PathBuf>,
    /// The transport; over Zenoh where the world is.
    #[command(flatten)]
    pub link: LinkArgs<Connect>,
    /// With --transport zenoh: seconds to keep trying to reach the world
    /// again after losing it (a cut link), rejoining with a new token; 0:
    /// end at once.
    #[arg(long, default_value_t = 30.0, value_name = "SECS")]
    pub reconnect: f64,
}

/// The runtime's request for an agent from its options.
pub(crate) fn request(args: &AgentArgs) -> Result<AgentRequest> {
    let robots = match &args.robot {
        Some(r) => vec![r.clone()],
        None => args.robots.clone(),
    };
    Ok(AgentRequest {
        robots,
        run_id: args.run.clone(),
        timeout: Duration::from_secs_f64(args.timeout),
        misbehave: Misbehave {
            impersonate: args.impersonate,
            fault: args.fault,
            protocol_version: args.protocol_version,
        },
        usage_out: args.usage_out.clone(),
        zenoh: args.link.zenoh(),
        reconnect: Duration::try_from_secs_f64(args.reconnect)
            .map_err(|e| crate::exit::invalid(format!("--reconnect {}: {e}", args.reconnect)))?,
    })
}

/// The arguments that ask `mrsim agent` for `req`: what [`request`] makes
/// of them again.
pub fn spell(req: &AgentRequest) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec!["agent".into()];
    match &req.robots[..] {
        [one] => v.extend(["--robot".into(), one.into()]),
        group => v.extend(["--robots".into(), group.join(",").into()]),
    }
    v.extend(["--run".into(), req.run_id.clone().into()]);
    if let Some(f) = &req.usage_out {
        v.extend(["--usage-out".into(), f.into()]);
    }
    v.extend([
        "--timeout".into(),
        req.timeout.as_secs_f64().to_string().into(),
    ]);
    v.extend([
        "--reconnect".into(),
        req.reconnect.as_secs_f64().to_string().into(),
    ]);
    let m = &req.misbehave;
    if let Some(id) = m.impersonate {
        v.extend(["--impersonate".into(), id.to_string().into()]);
    }
    if let Some(f) = m.fault {
        v.extend(["--fault".into(), f.to_string().into()]);
    }
    if let Some(p) = m.protocol_version {
        v.extend(["--protocol-version".into(), p.to_string().into()]);
    }
    v.extend(LinkArgs::<Connect>::spell(req.zenoh.as_ref()));
    v
}

/// Runs `mrsim agent`; returns the exit status.
pub fn main(args: &AgentArgs) -> Result<i32> {
    let req = request(args)?;
    let who = req.robots.join(",");
    let end = mrsim_runtime::agent::run(&req);
    if let (Some(e), Some(path)) = (&end.usage_error, &args.usage_out) {
        eprintln!("warning: agent {who}: cannot write {}: {e}", path.display());
    }
    end.result.map_err(fail)?;
    Ok(0)
}
