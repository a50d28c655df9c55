//! `mrsim ros2`: the ROS 2 agent of robots with `planner = "ros2"`.

use crate::cli::{LinkArg, Ros2Args};
use crate::exit::{fail, invalid};
use anyhow::Result;
use mrsim_ros2::node::NodeOptions;
use mrsim_runtime::ros2::Ros2Request;
use std::time::Duration;

/// Runs `mrsim ros2`; returns the exit status.
pub fn main(args: &Ros2Args) -> Result<i32> {
    let secs = |what: &str, v: f64| {
        Duration::try_from_secs_f64(v).map_err(|e| invalid(format!("{what} {v}: {e}")))
    };
    let stats = mrsim_runtime::ros2::run(&Ros2Request {
        robots: args.robots.clone(),
        run_id: args.run.clone(),
        timeout: secs("--timeout", args.timeout)?,
        zenoh: (args.transport == LinkArg::Zenoh).then(|| args.zenoh.options(args.connect.clone())),
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
    .map_err(fail)?;
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
