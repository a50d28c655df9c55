//! The real cores of a realtime run under `[world.cpus]`, claimed before
//! anything starts: the CPUs the agents are pinned to (the first `count`
//! of the run's `--cpus`, or of the machine's), and each agent's policy
//! (`mrsim_agents::cores`), asked of the kernel at once by a probe so that
//! a policy it refuses is refused now, with its reason, rather than by an
//! agent in the middle of a run.
//!
//! Policies per robot need one robot per agent process on this machine:
//! the in-process transport (every robot a worker's turn), agent groups
//! (`robots_per_agent` > 1) and robots whose program is their own
//! (`external`, `ros2`) are refused.

use crate::error::Invalid;
use crate::launch::Transport;
use mrsim_scenario::Scenario;
use mrsim_sys::policy::{Policy, PolicyError, admission_share, admit, probe};

/// What the run claimed of the real cores.
#[derive(Debug, Clone, PartialEq)]
pub struct Cores {
    /// The CPUs every agent process is pinned to.
    pub agent_cpus: Vec<usize>,
    /// Each robot's policy, in the scenario's order (the agents take them
    /// themselves; listed for the run's messages).
    pub policies: Vec<(String, Policy)>,
}

/// The real cores of a run of `scenario` (named `origin` in messages)
/// over `transport`, whose processes may run on `run_cpus` (empty: not
/// pinned). `None` unless the run is realtime under `[world.cpus]`. A
/// layout that cannot give each robot its own policy, a `count` beyond the
/// CPUs, or a policy the kernel refuses (probed) is refused.
pub fn claim(
    scenario: &Scenario,
    origin: &str,
    transport: Transport,
    run_cpus: &[usize],
) -> Result<Option<Cores>, Invalid> {
    let Some(cpus) = scenario
        .world
        .cpus
        .filter(|_| mrsim_agents::cores::real(&scenario.world))
    else {
        return Ok(None);
    };
    let scheduler = cpus.scheduler.name();
    let refuse = |why: String| {
        Invalid(format!(
            "{origin}: [world.cpus] scheduler = \"{scheduler}\" in realtime: {why}"
        ))
    };
    if transport == Transport::Inproc {
        return Err(refuse(
            "each robot's agent takes its own scheduling policy, which needs an agent \
             process per robot; --transport inproc drives every robot from a few worker \
             threads (run it over shared memory, or in lockstep for the cores' model)"
                .to_string(),
        ));
    }
    if scenario.world.robots_per_agent > 1 {
        return Err(refuse(format!(
            "each robot's agent takes its own scheduling policy, which needs an agent \
             process per robot; [world] robots_per_agent = {} puts several in one",
            scenario.world.robots_per_agent
        )));
    }
    let own: Vec<String> = scenario
        .robots
        .iter()
        .filter(|r| r.planner == mrsim_planners::EXTERNAL || r.planner == mrsim_planners::ROS2)
        .map(|r| format!("`{}`", r.name))
        .collect();
    if !own.is_empty() {
        return Err(refuse(format!(
            "robot {} is driven by a program of its own (planner \"external\" or \"ros2\"), \
             whose scheduling this run cannot set",
            mrsim_world::names::first_few(&own, 5)
        )));
    }
    let available: Vec<usize> = if run_cpus.is_empty() {
        mrsim_sys::sched::affinity()
            .unwrap_or_else(|| (0..mrsim_sys::sched::online_cpus()).collect())
    } else {
        run_cpus.to_vec()
    };
    let count = cpus.count as usize;
    if count > available.len() {
        return Err(refuse(format!(
            "count = {count}, but the run may use only {} CPU{} ({})",
            available.len(),
            if available.len() == 1 { "" } else { "s" },
            cpu_list(&available)
        )));
    }
    let agent_cpus = available[..count].to_vec();
    let robots: Vec<(&str, Option<&mrsim_scenario::timing::Timing>)> = scenario
        .robots
        .iter()
        .map(|r| (r.name.as_str(), r.timing.as_ref()))
        .collect();
    let policies = mrsim_agents::cores::policies(cpus.scheduler, &robots);
    let bandwidths: Vec<f64> = policies.iter().map(Policy::bandwidth).collect();
    if let Some(share) = admission_share().filter(|_| bandwidths.iter().any(|&b| b > 0.0)) {
        let cores = mrsim_sys::sched::online_cpus();
        admit(&bandwidths, share, cores).map_err(|e| {
            refuse(format!(
                "the kernel would refuse the reservations (EBUSY): {e}; give them \
                 less runtime or longer periods"
            ))
        })?;
    }
    // The world's own policy is asked for too: it ticks above the agents.
    let mut asked = policies.clone();
    asked.push(mrsim_agents::cores::world_policy());
    probe(&asked, &agent_cpus).map_err(|(i, e)| {
        let whose = match robots.get(i) {
            Some((name, _)) => format!("robot `{name}`'s agent"),
            None => "the world".to_string(),
        };
        refuse(format!(
            "{whose} on CPUs {}: {e}{}",
            cpu_list(&agent_cpus),
            hint(&e)
        ))
    })?;
    Ok(Some(Cores {
        agent_cpus,
        policies: robots
            .iter()
            .map(|(n, _)| n.to_string())
            .zip(policies)
            .collect(),
    }))
}

/// What to do about a refusal.
fn hint(e: &PolicyError) -> &'static str {
    match e {
        PolicyError::NotPermitted { .. } => {
            "; run as root (or with CAP_SYS_NICE), with count covering every CPU of the \
             machine for scheduler = \"deadline\""
        }
        PolicyError::OverAdmission { .. } => {
            "; give the reservations less runtime or longer periods"
        }
        _ => "",
    }
}

/// `0,1`.
fn cpu_list(cpus: &[usize]) -> String {
    cpus.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(",")
}
