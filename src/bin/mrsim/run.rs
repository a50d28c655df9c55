//! `mrsim run`: a whole run, with its progress on stderr and its summary
//! on stdout.

use crate::cli::{ScenarioArgs, SchedArgs, TransportArg, ZenohArgs};
use crate::exit::fail;
use crate::watch::RunWatch;
use anyhow::Result;
use clap::Args;
use mrsim_runtime::Validated;
use mrsim_runtime::{Event, MAX_RESTARTS, RunRequest};

/// `mrsim run` options.
#[derive(Debug, Clone, Default, Args)]
pub struct RunArgs {
    /// Scenario and overrides.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Run id (iceoryx2 namespace); default: a fresh one.
    #[arg(long)]
    pub run: Option<String>,
    /// Print only the output folder, not the table.
    #[arg(long)]
    pub quiet: bool,
    /// Restart an agent process that dies while the world runs (same
    /// command line); it rejoins and drives its robot from where it is.
    #[arg(long)]
    pub restart_agents: bool,
    /// Robots each agent process drives (shm; the scenario's
    /// `[world] robots_per_agent`, default 1).
    #[arg(long, value_name = "K")]
    pub robots_per_agent: Option<u32>,
    /// World and agents as processes over iceoryx2 (shm), as threads
    /// of one process over crossbeam channels (inproc), or as processes
    /// over Zenoh on loopback (zenoh).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: TransportArg,
    /// With --transport zenoh: where the world listens (default: a free
    /// loopback port), e.g. tcp/127.0.0.1:7447.
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Option<String>,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
    /// Robots with planner = "ros2": the Zenoh router of the ROS 2 side
    /// (default tcp/localhost:7447), where `mrsim ros2` connects.
    #[arg(long, value_name = "ENDPOINT")]
    pub ros2_connect: Option<String>,
    /// Robots with planner = "ros2": the ROS domain id.
    #[arg(long, value_name = "ID")]
    pub ros2_domain: Option<u32>,
    /// Scheduling: --cpus LIST, --rt.
    #[command(flatten)]
    pub sched: SchedArgs,
    /// Do not draw plot.svg/png and replay.html.
    #[arg(long, hide = true)]
    pub no_report: bool,
    /// Show the run in a browser while it ticks: serve the live page on
    /// ADDR (default 127.0.0.1 on a free port; the URL is printed). Another
    /// address than loopback exposes the page, which has no
    /// authentication, to the network.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:0")]
    pub live: Option<String>,
}

/// Runs `mrsim run`; returns the exit status.
pub fn main(args: &RunArgs) -> Result<i32> {
    let mut source = args.scenario.source();
    if let Some(k) = args.robots_per_agent {
        // An override like any other: the world, the launcher and
        // scenario.json all see the same group size.
        source.set.push(format!("world.robots_per_agent={k}"));
    }
    let validated = Validated::new(source).map_err(fail)?;
    // The live page starts before the run, so its address is printed
    // before anything else happens.
    let feed = args.live.as_ref().map(|_| mrsim_live::Feed::new());
    let server = match (&args.live, &feed) {
        (Some(addr), Some(feed)) => Some(crate::view::serve(addr, feed.clone())?),
        _ => None,
    };
    let max_ticks = validated.scenario().max_ticks();
    // With [world.cpus] or CPU robots: the task set and the verdict of the
    // schedulability tests, printed as the run starts and set beside the
    // measured misses after it.
    let verdict = mrsim_scenario::schedulability::of_scenario(validated.scenario());
    let periods: Vec<(String, u32)> = validated
        .scenario()
        .robots
        .iter()
        .map(|r| {
            (
                r.name.clone(),
                r.timing.as_ref().map_or(1, |t| t.period_ticks.max(1)),
            )
        })
        .collect();
    let prepared = mrsim_runtime::prepare(
        validated,
        RunRequest {
            run_id: args.run.clone(),
            out: args.scenario.out.clone(),
            transport: args.transport.into(),
            sched: (&args.sched).into(),
            render: !args.no_report,
            restart_agents: args.restart_agents,
            zenoh: args.zenoh.options(args.listen.clone()),
            plan_timeout: None,
            ros2: mrsim_runtime::Ros2Side {
                connect: args.ros2_connect.clone(),
                domain: args.ros2_domain.unwrap_or(0),
            },
        },
    )
    .map_err(fail)?;
    if let Some(why) = &prepared.applied().rt_refused {
        eprintln!("warning: {why}");
    }
    if let (Some((set, v)), false) = (&verdict, args.quiet) {
        print!("{}", mrsim_scenario::schedulability::render(set, v));
    }
    let ns = prepared.namespace().clone();
    let zenoh = prepared.zenoh_observer();
    let external = prepared.validated().external_robots();
    if !external.is_empty() {
        eprintln!(
            "run `{}`: waiting for your own agent for {} (planner = \"external\"): a program \
             that joins with mrsim::LiveAgent, run id `{}`",
            ns.run_id(),
            external.join(", "),
            ns.run_id()
        );
    }
    let mut watch = None;
    let outcome = prepared
        .start(&crate::start::ThisExe, &mut |event| match event {
            Event::Waiting => watch
                .get_or_insert_with(|| RunWatch::new(&ns, max_ticks, zenoh.clone(), feed.clone()))
                .update(),
            Event::WaitingInproc(obs) => watch
                .get_or_insert_with(|| RunWatch::new(&ns, max_ticks, zenoh.clone(), feed.clone()))
                .update_from(obs.0),
            Event::WorldEnded => {
                if let Some(w) = watch.take() {
                    w.finish();
                }
            }
            Event::AgentRestarted {
                robot,
                pid,
                how,
                restart,
            } => eprintln!(
                "launcher: the agent for {robot} (pid {pid}) {how}; restarting it ({restart} of at most {MAX_RESTARTS})"
            ),
        })
        .map_err(fail)?;
    let beside = match (&verdict, &outcome.metrics, args.quiet) {
        (Some((_, v)), Some(m), false) => {
            Some(crate::table::predicted_and_measured(v, m, &periods))
        }
        _ => None,
    };
    let status = crate::outcome::print(&outcome, args.quiet, beside.as_deref());
    if let (Some(server), Some(feed)) = (server, feed) {
        // The world is gone: if the pump did not see the end, say so, and
        // serve a moment longer so that every open page shows it.
        if !feed.ended() {
            feed.end(if outcome.interrupted() {
                "the run was interrupted"
            } else {
                "finished"
            });
        }
        std::thread::sleep(crate::view::LINGER);
        drop(server);
    }
    Ok(status)
}
