//! How `mrsim run` starts the processes of a run: this executable, asked
//! for each process's spec by the subcommand that runs it (`world`,
//! `agent`, `ros2`), which spells its own options.

use mrsim_runtime::{ProcessSpec, Starter};
use std::ffi::OsString;
use std::process::Command;

/// Starts each process as this same executable.
pub struct ThisExe;

/// The arguments of this executable that start `spec`.
pub fn args(spec: &ProcessSpec) -> Vec<OsString> {
    match spec {
        ProcessSpec::World { scenario, request } => crate::world::spell(scenario, request),
        ProcessSpec::Agent(request) => crate::agent::spell(request),
        ProcessSpec::Ros2(request) => crate::ros2::spell(request),
    }
}

impl Starter for ThisExe {
    fn command(&self, spec: &ProcessSpec) -> std::io::Result<Command> {
        let mut cmd = Command::new(std::env::current_exe()?);
        cmd.args(args(spec));
        Ok(cmd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command as Sub};
    use clap::Parser;
    use mrsim_ros2::node::NodeOptions;
    use mrsim_runtime::ScenarioSource;
    use mrsim_runtime::agent::{AgentRequest, Misbehave};
    use mrsim_runtime::ros2::Ros2Request;
    use mrsim_runtime::world::WorldRequest;
    use mrsim_transport::zenoh::ZenohOptions;
    use std::time::Duration;

    /// `spec` spelled and parsed back by this executable's command line.
    fn parsed(spec: &ProcessSpec) -> Sub {
        let argv = std::iter::once(OsString::from("mrsim")).chain(args(spec));
        Cli::try_parse_from(argv)
            .expect("the spelled arguments parse")
            .command
            .expect("a subcommand")
    }

    fn zenoh(endpoint: &str) -> Option<ZenohOptions> {
        Some(ZenohOptions {
            endpoint: Some(endpoint.into()),
            config_file: Some("z.json5".into()),
        })
    }

    #[test]
    fn a_world_parses_back_to_its_spec() {
        for (start_timeout, net) in [
            (Some(Duration::from_secs_f64(61.0)), None),
            (None, zenoh("tcp/127.0.0.1:7447")),
        ] {
            let scenario = ScenarioSource {
                path: Some("scenarios/crossing.toml".into()),
                mode: Some(mrsim_scenario::Mode::Realtime),
                set: vec!["world.dt=0.05".into(), "robot.*.max_speed=1".into()],
            };
            let request = WorldRequest {
                run_id: "r1".into(),
                out: Some("runs/x".into()),
                start_timeout,
                launched: true,
                zenoh: net,
            };
            let Sub::World(w) = parsed(&ProcessSpec::World {
                scenario: scenario.clone(),
                request: request.clone(),
            }) else {
                panic!("not `mrsim world`");
            };
            assert_eq!(w.scenario.source(), scenario);
            assert_eq!(
                format!("{:?}", crate::world::request(&w)),
                format!("{request:?}")
            );
        }
    }

    #[test]
    fn an_agent_or_a_group_parses_back_to_its_spec() {
        for (robots, net) in [
            (vec!["a".to_string()], None),
            (vec!["a".into(), "b".into()], zenoh("tcp/127.0.0.1:9")),
        ] {
            let request = AgentRequest {
                robots,
                run_id: "r1".into(),
                timeout: Duration::from_secs_f64(62.5),
                misbehave: Misbehave {
                    impersonate: Some(3),
                    fault: Some(mrsim_agents::fault::Fault::HangAt(7)),
                    protocol_version: Some(1),
                },
                usage_out: Some("runs/x/usage-a.json".into()),
                zenoh: net,
                reconnect: Duration::from_secs(30),
            };
            let Sub::Agent(a) = parsed(&ProcessSpec::Agent(request.clone())) else {
                panic!("not `mrsim agent`");
            };
            let back = crate::agent::request(&a).expect("a valid request");
            assert_eq!(format!("{back:?}"), format!("{request:?}"));
        }
    }

    #[test]
    fn the_ros2_agent_parses_back_to_its_spec() {
        let request = Ros2Request {
            robots: vec!["a0".into(), "a1".into()],
            run_id: "r1".into(),
            timeout: Duration::from_secs_f64(62.0),
            zenoh: zenoh("tcp/127.0.0.1:9"),
            node: NodeOptions {
                domain: 4,
                connect: Some("tcp/localhost:7447".into()),
                config_file: Some("ros.json5".into()),
                name: String::new(),
            },
            prefix: "sim".into(),
            wait: Duration::from_secs_f64(0.25),
            map: Some("maps/lab.yaml".into()),
            stats_out: Some("runs/x/ros2.json".into()),
        };
        let Sub::Ros2(r) = parsed(&ProcessSpec::Ros2(request.clone())) else {
            panic!("not `mrsim ros2`");
        };
        let back = crate::ros2::request(&r).expect("a valid request");
        assert_eq!(format!("{back:?}"), format!("{request:?}"));
    }
}
