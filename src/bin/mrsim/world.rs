//! `mrsim world`: a world process, started by `mrsim run` or by hand.

use crate::cli::{Connect, LinkArgs, Listen, ScenarioArgs};
use crate::exit::{EXIT_INTERRUPTED, fail};
use anyhow::Result;
use clap::Args;
use mrsim_runtime::world::WorldRequest;
use mrsim_runtime::{ScenarioSource, Validated};
use mrsim_transport::zenoh::ZenohOptions;
use std::ffi::OsString;
use std::time::Duration;

/// `mrsim world` options.
#[derive(Debug, Clone, Args)]
pub struct WorldArgs {
    /// Scenario and overrides.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Run id agents use to find this world.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// Give up if not every agent has joined after this many seconds
    /// (default: wait forever).
    #[arg(long)]
    pub start_timeout: Option<f64>,
    /// Started by `mrsim run`: the launcher cleans up and prints.
    #[arg(long, hide = true)]
    pub launched: bool,
    /// The transport; over Zenoh where to listen.
    #[command(flatten)]
    pub link: LinkArgs<Listen>,
}

/// The runtime's request for a world from its options (the scenario
/// apart: [`ScenarioArgs::source`]).
pub(crate) fn request(args: &WorldArgs) -> WorldRequest {
    WorldRequest {
        run_id: args.run.clone(),
        out: args.scenario.out.clone(),
        start_timeout: args.start_timeout.map(Duration::from_secs_f64),
        launched: args.launched,
        zenoh: args.link.zenoh(),
    }
}

/// The arguments that ask `mrsim world` for `req` on `scenario`: what
/// [`request`] and [`ScenarioArgs::source`] make of them again.
pub fn spell(scenario: &ScenarioSource, req: &WorldRequest) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec!["world".into()];
    v.extend(ScenarioArgs::spell(scenario));
    v.extend(["--run".into(), req.run_id.clone().into()]);
    if let Some(t) = req.start_timeout {
        v.extend(["--start-timeout".into(), t.as_secs_f64().to_string().into()]);
    }
    if req.launched {
        v.push("--launched".into());
    }
    if let Some(out) = &req.out {
        v.extend(["--out".into(), out.into()]);
    }
    v.extend(LinkArgs::<Listen>::spell(req.zenoh.as_ref()));
    v
}

/// Runs `mrsim world`; returns the exit status.
pub fn main(args: &WorldArgs) -> Result<i32> {
    let validated = Validated::new(args.scenario.source()).map_err(fail)?;
    let req = request(args);
    // The agents' link: this world's endpoint (the config file is theirs).
    let agent_link = req.zenoh.as_ref().map(|z| ZenohOptions {
        endpoint: Some(
            z.endpoint
                .clone()
                .unwrap_or_else(|| mrsim_transport::zenoh::DEFAULT_ENDPOINT.to_string()),
        ),
        config_file: None,
    });
    let agent_flags: String = LinkArgs::<Connect>::spell(agent_link.as_ref())
        .iter()
        .map(|a| format!(" {}", a.to_string_lossy()))
        .collect();
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
        crate::outcome::print(finished, false, None);
    }
    Ok(if ended.interrupted {
        EXIT_INTERRUPTED
    } else {
        0
    })
}
