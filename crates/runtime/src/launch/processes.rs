//! The run as processes: the world, the agents (one per robot or group)
//! and the ROS 2 agent started, supervised (restarts, forwarded signals)
//! and reaped.

use super::prepare::Prepared;
use super::zenoh::zenoh_sides;
use super::{Event, LaunchError, MAX_RESTARTS, ProcessSpec, Starter, Transport, describe};
use crate::agent::{AgentRequest, Misbehave, RECONNECT};
use crate::finish::{AgentFailure, Ending, Outcome, WorldFailure};
use crate::ros2::Ros2Request;
use crate::usage::AgentUsage;
use crate::world::WorldRequest;
use mrsim_ros2::node::NodeOptions;
use std::path::{Path, PathBuf};
use std::process::{Child, ExitStatus, Stdio};
use std::time::{Duration, Instant};

impl Prepared {
    pub(super) fn run_processes(
        self,
        starter: &dyn Starter,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> Result<Outcome, LaunchError> {
        // The world runs in its own process: this one's copy goes.
        let (source, scenario) = self.validated.into_scenario();
        let (dir, run_id) = (&self.dir, self.ns.run_id());
        // Hundreds of agent processes starting on two cores take a while to
        // join: the world and each agent wait a minute plus a second per
        // robot.
        let join = Duration::from_secs_f64(60.0 + scenario.robots.len() as f64);
        let transport = self.request.transport;
        // Over Zenoh the world listens where asked (a free loopback port by
        // default) and the agents, on this machine, connect there.
        let (world_net, agent_net) = match transport {
            Transport::Zenoh => {
                let (world, agent) = zenoh_sides(&self.request.zenoh)?;
                (Some(world), Some(agent))
            }
            _ => (None, None),
        };
        // An `external` robot's program is started by its user, whenever:
        // then the world waits for its agents without a limit (a signal
        // ends the wait).
        let external = scenario
            .robots
            .iter()
            .any(|r| r.planner == mrsim_planners::EXTERNAL);
        // Realtime under `[world.cpus]` the agents run on the cores' CPUs
        // (the world on all the run's, above them).
        let agent_cpus = self.cores.as_ref().map(|c| c.agent_cpus.clone());
        let start = |spec: ProcessSpec| -> std::io::Result<Child> {
            let mut cmd = starter.command(&spec)?;
            if let (ProcessSpec::Agent(_), Some(cpus)) = (&spec, &agent_cpus) {
                mrsim_sys::sched::pin_command(&mut cmd, cpus)?;
            }
            cmd.stdin(Stdio::null()).spawn()
        };
        let mut world = start(ProcessSpec::World {
            scenario: source,
            request: WorldRequest {
                run_id: run_id.to_string(),
                out: Some(dir.clone()),
                start_timeout: (!external).then_some(join),
                launched: true,
                zenoh: world_net,
            },
        })
        .map_err(LaunchError::SpawnWorld)?;
        // One process per group of `robots_per_agent` robots (the last
        // takes the rest), named after the group's first robot.
        // An `external` robot's agent is its user's program: none is started.
        let names: Vec<&str> = scenario
            .robots
            .iter()
            .filter(|r| r.planner != mrsim_planners::EXTERNAL && r.planner != mrsim_planners::ROS2)
            .map(|r| r.name.as_str())
            .collect();
        let k = (scenario.world.robots_per_agent as usize).max(1);
        let groups: Vec<&[&str]> = names.chunks(k).collect();
        let spawn = |group: &[&str]| -> Result<Child, LaunchError> {
            let first = group.first().copied().unwrap_or_default();
            start(ProcessSpec::Agent(AgentRequest {
                robots: group.iter().map(|r| r.to_string()).collect(),
                run_id: run_id.to_string(),
                timeout: join,
                misbehave: Misbehave::default(),
                usage_out: Some(usage_file(dir, first)),
                zenoh: agent_net.clone(),
                reconnect: RECONNECT,
            }))
            .map_err(|source| LaunchError::SpawnAgent {
                robot: group_name(group),
                source,
            })
        };
        let mut agents: Vec<(String, Child)> = Vec::with_capacity(groups.len());
        for g in &groups {
            agents.push((group_name(g), spawn(g)?));
        }
        // The robots with planner `ros2` share one ROS 2 agent (not
        // restarted: after `groups`, out of the restart loop's reach).
        let ros2: Vec<&str> = scenario
            .robots
            .iter()
            .filter(|r| r.planner == mrsim_planners::ROS2)
            .map(|r| r.name.as_str())
            .collect();
        let mut restarts = vec![0u32; agents.len()];
        if !ros2.is_empty() {
            // In lockstep the ROS 2 agent waits for a cmd_vel for less
            // than the world waits for it, so the world never loses it.
            let wait = (0.5 * scenario.world.stall_timeout).min(1.0);
            let child = start(ProcessSpec::Ros2(Ros2Request {
                robots: ros2.iter().map(|r| r.to_string()).collect(),
                run_id: run_id.to_string(),
                timeout: join,
                zenoh: agent_net.clone(),
                node: NodeOptions {
                    domain: self.request.ros2.domain,
                    connect: self.request.ros2.connect.clone(),
                    config_file: None,
                    name: String::new(),
                },
                prefix: String::new(),
                wait: Duration::from_secs_f64(wait),
                map: scenario.map.as_ref().map(|m| PathBuf::from(&m.file)),
                stats_out: Some(dir.join(crate::ros2::STATS_FILE)),
            }))
            .map_err(|source| LaunchError::SpawnAgent {
                robot: group_name(&ros2),
                source,
            })?;
            agents.push((format!("ros2 agent ({})", ros2.join(",")), child));
        }

        // Wait for the world; forward a signal to everything we started.
        let mut forwarded: Option<Instant> = None;
        let world_status = loop {
            if let Some(status) = world.try_wait().map_err(LaunchError::Wait)? {
                break status;
            }
            on_event(Event::Waiting);
            // Stop the world first: it writes what it has and tells the
            // agents the run is over, so they end by themselves (the ones
            // that do not are stopped below); a world that does not end in
            // 5 s is killed.
            if mrsim_sys::signal::received().is_some() && forwarded.is_none() {
                mrsim_sys::process::kill(world.id(), mrsim_sys::signal::SIGTERM);
                forwarded = Some(Instant::now());
            }
            if forwarded.is_some_and(|t| t.elapsed() > Duration::from_secs(5)) {
                mrsim_sys::process::kill(world.id(), mrsim_sys::signal::SIGKILL);
            }
            // One system call a round while no agent has ended (asking
            // each of hundreds would be as many, at the agents' priority).
            let ended = mrsim_sys::process::a_child_ended();
            for (((name, a), n), g) in agents.iter_mut().zip(restarts.iter_mut()).zip(&groups) {
                if !ended {
                    break;
                }
                let Ok(Some(status)) = a.try_wait() else {
                    continue;
                };
                if !self.request.restart_agents
                    || forwarded.is_some()
                    || status.success()
                    || *n >= MAX_RESTARTS
                {
                    continue;
                }
                *n += 1;
                on_event(Event::AgentRestarted {
                    robot: name,
                    pid: a.id(),
                    how: describe(status),
                    restart: *n,
                });
                // A group's robots rejoin together, in one new process.
                *a = spawn(g)?;
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        on_event(Event::WorldEnded);

        let agent_failures = alike(
            reap_agents(&mut agents, world_status)
                .iter()
                .map(|f| (f.robot.as_str(), f.what.clone())),
        );
        self.ns.remove_leftovers();
        // 130: the world was interrupted and wrote what it had (metrics.json).
        let interrupted = world_status.code() == Some(130);
        let world_failure = (!world_status.success() && !interrupted).then(|| WorldFailure {
            pid: world.id(),
            how: describe(world_status),
        });
        // A group's process used what its robots used together: each
        // robot is given an equal share of its CPU time.
        let usage: Vec<AgentUsage> = groups
            .iter()
            .filter_map(|g| {
                let f = usage_file(dir, g.first()?);
                let u = crate::usage::read_agent(&f);
                let _ = std::fs::remove_file(&f);
                u.map(|u| (g.len(), u))
            })
            .flat_map(|(len, u)| {
                let share = AgentUsage {
                    cpu_s: u.cpu_s / len as f64,
                    ..u
                };
                std::iter::repeat_n(share, len)
            })
            .collect();
        Ok(crate::finish::finish(Ending {
            dir,
            world_failure,
            agent_failures,
            usage: Some((transport.name(), &usage)),
            render: self.request.render,
            metrics: None,
        })?)
    }
}

/// Agents end on the world's last snapshot: gives them a moment, then stops
/// the ones left, all at once (SIGTERM, then SIGKILL a second later): a
/// thousand stragglers stopped one after another would take minutes.
/// Returns the ones that ended badly while the world did not.
fn reap_agents(agents: &mut [(String, Child)], world_status: ExitStatus) -> Vec<AgentFailure> {
    let mut ended: Vec<Option<ExitStatus>> = vec![None; agents.len()];
    wait_ended(agents, &mut ended, Instant::now() + Duration::from_secs(3));
    for (sig, wait) in [
        (mrsim_sys::signal::SIGTERM, Duration::from_secs(1)),
        (mrsim_sys::signal::SIGKILL, Duration::ZERO),
    ] {
        if ended.iter().all(Option::is_some) {
            break;
        }
        for ((_, a), _) in agents.iter().zip(&ended).filter(|(_, e)| e.is_none()) {
            mrsim_sys::process::kill(a.id(), sig);
        }
        wait_ended(agents, &mut ended, Instant::now() + wait);
    }
    let mut failures = Vec::new();
    for ((name, a), e) in agents.iter_mut().zip(ended) {
        let status = match e {
            Some(s) => s,
            None => a.wait().unwrap_or(world_status),
        };
        if !status.success() && world_status.success() {
            failures.push(AgentFailure {
                robot: name.clone(),
                what: describe(status),
            });
        }
    }
    failures
}

/// Records in `ended` the status of each agent that has ended, until all
/// have or `deadline` passes. The children are asked one by one only after
/// one of them has ended (one system call a round otherwise).
fn wait_ended(agents: &mut [(String, Child)], ended: &mut [Option<ExitStatus>], deadline: Instant) {
    loop {
        if mrsim_sys::process::a_child_ended() {
            for ((_, a), e) in agents.iter_mut().zip(ended.iter_mut()) {
                if e.is_none()
                    && let Ok(Some(s)) = a.try_wait()
                {
                    *e = Some(s);
                }
            }
        }
        if ended.iter().all(Option::is_some) || Instant::now() >= deadline {
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Failures of robots (or groups) that failed alike (every robot when the
/// world went, say) as one failure naming the first few: a run of 10,000
/// robots prints a line, not 10,000.
pub(super) fn alike<'a>(failures: impl Iterator<Item = (&'a str, String)>) -> Vec<AgentFailure> {
    let mut alike: Vec<(String, Vec<&str>)> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for (name, what) in failures {
        let k = *index.entry(what.clone()).or_insert_with(|| {
            alike.push((what, Vec::new()));
            alike.len() - 1
        });
        alike[k].1.push(name);
    }
    alike
        .into_iter()
        .map(|(what, names)| AgentFailure {
            robot: group_name(&names),
            what,
        })
        .collect()
}

/// A group's robots as messages name them: the first few and a count.
fn group_name(group: &[&str]) -> String {
    mrsim_world::names::first_few(group, 3)
}

/// Where the agent of `robot` (of the group it is first of) writes what
/// it used.
fn usage_file(dir: &Path, robot: &str) -> PathBuf {
    dir.join(mrsim_runfolder::agent_usage_file(robot))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robots_that_failed_alike_are_one_failure_naming_the_first_few() {
        let names: Vec<String> = (0..1000).map(|i| format!("g{i}")).collect();
        let failures = alike(
            names
                .iter()
                .map(|n| (n.as_str(), "failed: the world is gone".to_string()))
                .chain([("odd", "exited with status 1".to_string())]),
        );
        assert_eq!(failures.len(), 2);
        assert_eq!(
            failures[0].to_string(),
            "agent for g0, g1, g2 and 997 more failed: the world is gone"
        );
        assert_eq!(
            failures[1].to_string(),
            "agent for odd exited with status 1"
        );
    }
}
