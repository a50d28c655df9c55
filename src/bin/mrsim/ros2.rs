//! `mrsim ros2`: the ROS 2 agent of robots with `planner = "ros2"`.

use crate::cli::{Connect, LinkArgs};
use crate::exit::{fail, invalid};
use anyhow::Result;
use clap::Args;
use mrsim_ros2::node::NodeOptions;
use mrsim_runtime::ros2::Ros2Request;
use std::ffi::OsString;
use std::path::PathBuf;
use std::time::Duration;

/// `mrsim ros2` options.
#[derive(Debug, Clone, Args)]
pub struct Ros2Args {
    /// The robots (planner = "ros2"), comma-separated.
    #[arg(long, value_delimiter = ',', value_name = "NAMES", required = true)]
    pub robots: Vec<String>,
    /// The run id of the world.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// ROS domain id (ROS_DOMAIN_ID of the ROS 2 nodes).
    #[arg(long, default_value_t = 0)]
    pub domain: u32,
    /// The Zenoh router (or peer) the ROS 2 nodes use, e.g.
    /// tcp/HOST:7447 (default tcp/localhost:7447, where `ros2 run
    /// rmw_zenoh_cpp rmw_zenohd` listens).
    #[arg(long = "ros2-connect", alias = "ros-connect", value_name = "ENDPOINT")]
    pub ros2_connect: Option<String>,
    /// A Zenoh JSON5 config file for the ROS 2 side (as
    /// ZENOH_SESSION_CONFIG_URI is for rmw_zenoh).
    #[arg(long, value_name = "FILE")]
    pub ros2_config: Option<PathBuf>,
    /// Put the robots' topics under this prefix (`sim` gives
    /// /sim/a0/cmd_vel).
    #[arg(long, default_value = "", value_name = "PREFIX")]
    pub namespace_prefix: String,
    /// Lockstep: seconds to wait for a robot's cmd_vel after each /clock
    /// before it brakes for the tick (keep it below the scenario's
    /// stall_timeout).
    #[arg(long, default_value_t = 1.0, value_name = "SECS")]
    pub wait: f64,
    /// Publish this map (a ROS map_server YAML) on /map.
    #[arg(long, value_name = "YAML")]
    pub map: Option<PathBuf>,
    /// Write the counts of what came in on cmd_vel (JSON) here at the end.
    #[arg(long, value_name = "FILE")]
    pub stats_out: Option<PathBuf>,
    /// Seconds to wait for the world.
    #[arg(long, default_value_t = 30.0)]
    pub timeout: f64,
    /// The transport; over Zenoh where the world is.
    #[command(flatten)]
    pub link: LinkArgs<Connect>,
}

/// The runtime's request for the ROS 2 agent from its options.
pub(crate) fn request(args: &Ros2Args) -> Result<Ros2Request> {
    let secs = |what: &str, v: f64| {
        Duration::try_from_secs_f64(v).map_err(|e| invalid(format!("{what} {v}: {e}")))
    };
    Ok(Ros2Request {
        robots: args.robots.clone(),
        run_id: args.run.clone(),
        timeout: secs("--timeout", args.timeout)?,
        zenoh: args.link.zenoh(),
        node: NodeOptions {
            domain: args.domain,
            connect: args.ros2_connect.clone(),
            config_file: args.ros2_config.clone(),
            name: String::new(),
        },
        prefix: args.namespace_prefix.clone(),
        wait: secs("--wait", args.wait)?,
        map: args.map.clone(),
        stats_out: args.stats_out.clone(),
    })
}

/// The arguments that ask `mrsim ros2` for `req`: what [`request`] makes
/// of them again (the node's name is the agent's own).
pub fn spell(req: &Ros2Request) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec![
        "ros2".into(),
        "--robots".into(),
        req.robots.join(",").into(),
    ];
    v.extend(["--run".into(), req.run_id.clone().into()]);
    v.extend([
        "--timeout".into(),
        req.timeout.as_secs_f64().to_string().into(),
    ]);
    v.extend(["--domain".into(), req.node.domain.to_string().into()]);
    v.extend(["--wait".into(), req.wait.as_secs_f64().to_string().into()]);
    if let Some(f) = &req.stats_out {
        v.extend(["--stats-out".into(), f.into()]);
    }
    if let Some(c) = &req.node.connect {
        v.extend(["--ros2-connect".into(), c.into()]);
    }
    if let Some(f) = &req.node.config_file {
        v.extend(["--ros2-config".into(), f.into()]);
    }
    if !req.prefix.is_empty() {
        v.extend(["--namespace-prefix".into(), req.prefix.clone().into()]);
    }
    if let Some(m) = &req.map {
        v.extend(["--map".into(), m.into()]);
    }
    v.extend(LinkArgs::<Connect>::spell(req.zenoh.as_ref()));
    v
}

/// Runs `mrsim ros2`; returns the exit status.
pub fn main(args: &Ros2Args) -> Result<i32> {
    let stats = mrsim_runtime::ros2::run(&request(args)?).map_err(fail)?;
    for (robot, c) in &stats.robots {
        let bad = c.undecodable + c.non_finite + c.absurd + c.wrong_type + c.flooded;
        if bad + c.missed + c.stale + c.bad_attachment > 0 {
            eprintln!(
                "ros2 agent: {robot}: {} cmd_vel taken; refused {bad} (undecodable {}, \
                 non-finite {}, absurd {}, other type {}, flood {}); {} without attachment; \
                 braked for {} missed and {} stale ticks",
                c.accepted,
                c.undecodable,
                c.non_finite,
                c.absurd,
                c.wrong_type,
                c.flooded,
                c.bad_attachment,
                c.missed,
                c.stale
            );
        }
    }
    Ok(0)
}
