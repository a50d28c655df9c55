//! The command line: the subcommands, and the options several of them
//! share, with their conversion into the runtime's plain request types.
//! Each subcommand's own options are in its file, beside what it does with
//! them; clap types never leave the executable.

use clap::{Args, Parser, Subcommand, ValueEnum};
use mrsim_runtime::ScenarioSource;
use mrsim_runtime::Sched;
use mrsim_runtime::Transport;
use mrsim_transport::zenoh::ZenohOptions;
use std::ffi::OsString;
use std::path::PathBuf;

/// mrsim: many robots, one world, one agent process per robot.
#[derive(Debug, Parser)]
#[command(name = "mrsim", version, about, long_about = None)]
pub struct Cli {
    /// What to do (default: run the built-in demo).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Time mode override.
#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum ModeArg {
    /// Wait for every agent each tick (deterministic).
    Lockstep,
    /// Tick on the wall clock; late commands are deadline misses.
    Realtime,
}

/// Options shared by `run` and `world`: which scenario and how.
#[derive(Debug, Clone, Default, Args)]
pub struct ScenarioArgs {
    /// Scenario file (TOML). Without one, the built-in demo.
    pub scenario: Option<PathBuf>,
    /// Override the scenario's time mode.
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Override a scenario value: KEY=VALUE, KEY a dotted path
    /// (world.dt, robot.r0.max_speed, robot.*.params.alpha, planner).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Output folder (default: a fresh folder under runs/).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

impl ScenarioArgs {
    /// The scenario file and overrides, for the runtime.
    pub fn source(&self) -> ScenarioSource {
        ScenarioSource {
            path: self.scenario.clone(),
            mode: self.mode.map(|m| match m {
                ModeArg::Lockstep => mrsim_scenario::Mode::Lockstep,
                ModeArg::Realtime => mrsim_scenario::Mode::Realtime,
            }),
            set: self.set.clone(),
        }
    }
}

impl ScenarioArgs {
    /// The arguments that give another process `source`: what
    /// [`ScenarioArgs::source`] makes of them again.
    pub fn spell(source: &ScenarioSource) -> Vec<OsString> {
        let mut v: Vec<OsString> = Vec::new();
        if let Some(p) = &source.path {
            v.push(p.clone().into());
        }
        for s in &source.set {
            v.push("--set".into());
            v.push(s.into());
        }
        if let Some(m) = source.mode {
            v.push("--mode".into());
            v.push(mrsim_runtime::mode_name(m).into());
        }
        v
    }
}

/// The transport between the world and its agents.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum TransportArg {
    /// iceoryx2 shared memory, one process per agent.
    #[default]
    Shm,
    /// crossbeam channels, one thread per agent in one process.
    Inproc,
    /// Zenoh over TCP, one process per agent (see --listen, --zenoh-config).
    Zenoh,
}

/// The transport of a process started by hand (`world`, `agent`, `top`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum LinkArg {
    /// iceoryx2 shared memory: everything on this machine.
    #[default]
    Shm,
    /// Zenoh over TCP (or TLS): the world listens, agents connect, from
    /// this machine or others.
    Zenoh,
}

/// The Zenoh config file of a run or of a process started by hand.
#[derive(Debug, Clone, Default, Args)]
pub struct ZenohArgs {
    /// A Zenoh JSON5 config file (TLS, user/password auth, routers, lease);
    /// --listen/--connect given as well override its endpoints.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
}

impl ZenohArgs {
    /// The runtime's Zenoh options with `endpoint`.
    pub fn options(&self, endpoint: Option<String>) -> ZenohOptions {
        ZenohOptions {
            endpoint,
            config_file: self.zenoh_config.clone(),
        }
    }
}

/// The side of a Zenoh link a process is on: the world listens
/// ([`Listen`]), the processes that reach it connect ([`Connect`]).
pub trait Side: Args + Clone + std::fmt::Debug {
    /// The option that gives the endpoint (`--listen` or `--connect`).
    const FLAG: &'static str;
    /// The endpoint given, if any.
    fn endpoint(&self) -> Option<String>;
}

/// `--listen`: where a world started by hand listens.
#[derive(Debug, Clone, Default, Args)]
pub struct Listen {
    /// With --transport zenoh: where to listen (default: loopback only,
    /// tcp/127.0.0.1:7447; tcp/0.0.0.0:7447 for every interface).
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Option<String>,
}

impl Side for Listen {
    const FLAG: &'static str = "--listen";
    fn endpoint(&self) -> Option<String> {
        self.listen.clone()
    }
}

/// `--connect`: where an agent, the ROS 2 agent or a watcher finds the
/// world.
#[derive(Debug, Clone, Default, Args)]
pub struct Connect {
    /// With --transport zenoh: the world's address (default
    /// tcp/127.0.0.1:7447).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<String>,
}

impl Side for Connect {
    const FLAG: &'static str = "--connect";
    fn endpoint(&self) -> Option<String> {
        self.connect.clone()
    }
}

/// How a process started by hand (`world`, `agent`, `ros2`, `top`,
/// `view`) reaches the others of its run: the transport, and over Zenoh
/// the endpoint of its side and the config file. The one place these
/// options are declared, read and spelled.
#[derive(Debug, Clone, Args)]
pub struct LinkArgs<E: Side> {
    /// shm (iceoryx2: every process on this machine) or zenoh (over TCP or
    /// TLS: the world listens, the others connect, from this machine or
    /// others).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: LinkArg,
    /// With --transport zenoh: the endpoint.
    #[command(flatten)]
    pub endpoint: E,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
}

impl<E: Side> LinkArgs<E> {
    /// The runtime's Zenoh options when the link is Zenoh; `None`: shared
    /// memory.
    pub fn zenoh(&self) -> Option<ZenohOptions> {
        (self.transport == LinkArg::Zenoh).then(|| self.zenoh.options(self.endpoint.endpoint()))
    }

    /// The arguments that give another process the link `zenoh` (`None`:
    /// shared memory, the default, spelled as nothing): what
    /// [`LinkArgs::zenoh`] makes of them again.
    pub fn spell(zenoh: Option<&ZenohOptions>) -> Vec<OsString> {
        let Some(z) = zenoh else {
            return Vec::new();
        };
        let mut v: Vec<OsString> = vec!["--transport".into(), "zenoh".into()];
        if let Some(e) = &z.endpoint {
            v.extend([E::FLAG.into(), e.into()]);
        }
        if let Some(f) = &z.config_file {
            v.extend(["--zenoh-config".into(), f.into()]);
        }
        v
    }
}

impl From<TransportArg> for Transport {
    fn from(t: TransportArg) -> Self {
        match t {
            TransportArg::Shm => Transport::Shm,
            TransportArg::Inproc => Transport::Inproc,
            TransportArg::Zenoh => Transport::Zenoh,
        }
    }
}

/// `--cpus` and `--rt`.
#[derive(Debug, Clone, Default, Args)]
pub struct SchedArgs {
    /// Pin every process of the run to these CPUs (e.g. `0,1` or `0-3`).
    #[arg(long, value_name = "LIST")]
    pub cpus: Option<String>,
    /// Run the world and the agents under SCHED_FIFO where permitted (a
    /// warning and normal scheduling where not).
    #[arg(long)]
    pub rt: bool,
}

impl From<&SchedArgs> for Sched {
    fn from(a: &SchedArgs) -> Self {
        Sched {
            cpus: a.cpus.clone(),
            rt: a.rt,
        }
    }
}

/// Which running world to watch and how to reach it (`top`, `view`).
#[derive(Debug, Clone, Args)]
pub struct WatchArgs {
    /// The run id of the world.
    #[arg(long, default_value = "default")]
    pub run: String,
    /// Seconds to wait for the world.
    #[arg(long, default_value_t = 10.0)]
    pub timeout: f64,
    /// How to reach the world.
    #[command(flatten)]
    pub link: LinkArgs<Connect>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scenario: start the world and one agent process per robot,
    /// wait for the end, write the outputs, print a summary.
    Run(crate::run::RunArgs),
    /// Measure timing under true concurrency: realtime runs of generated
    /// crossing scenes for each agent count and transport (see BENCHMARKS.md).
    Bench(crate::bench::BenchArgs),
    /// Start a world by hand; agents join with `mrsim agent --robot NAME --run ID`.
    World(crate::world::WorldArgs),
    /// Drive one robot of a running world.
    Agent(crate::agent::AgentArgs),
    /// Drive robots of a running world from ROS 2 over rmw_zenoh: cmd_vel
    /// in; odom, scan, tf, clock and map out (see docs/ros2.md).
    Ros2(crate::ros2::Ros2Args),
    /// Watch a running world: a live dashboard of its bodies and agents
    /// (read-only; never slows the world or counts as an agent).
    Top(WatchArgs),
    /// Watch a running world in a browser: the live page, served on
    /// loopback (read-only; never slows the world or counts as an agent).
    View {
        /// The run and how to reach its world.
        #[command(flatten)]
        watch: WatchArgs,
        /// Where the page is served (default 127.0.0.1 on a free port).
        /// Another address than loopback exposes the page, which has no
        /// authentication, to the network.
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:0")]
        live: String,
    },
    /// Regenerate plot.svg, plot.png and replay.html of a run folder.
    Report {
        /// The run folder.
        dir: PathBuf,
    },
    /// Write a run folder in another format: `--mcap` writes run.mcap
    /// (Foxglove's schemas, simulated time) into the folder.
    Export {
        /// The run folder.
        dir: PathBuf,
        /// Write run.mcap, for Foxglove or Lichtblick.
        #[arg(long)]
        mcap: bool,
    },
    /// List the planners.
    Planners,
    /// Run every combination of values (x seeds 1..N) and tabulate and
    /// draw the metrics: sweep.csv, summary.csv, a table of means with
    /// 95 % intervals, sweep.svg and sweep.png.
    Sweep(crate::sweep::SweepArgs),
    /// A CPU-bound load of `bench --stress`; exits when process PARENT is
    /// no longer its parent.
    #[command(hide = true)]
    Spin {
        /// The bench's pid.
        #[arg(long)]
        parent: u32,
    },
    /// Run a recorded run again in lockstep with the timing it recorded
    /// (timing.csv): the same trajectory byte for byte, or with --set a
    /// counterfactual under the same timing.
    Rerun(crate::rerun::RerunArgs),
    /// Check a scenario file without running it.
    Check {
        /// Scenario and overrides.
        #[command(flatten)]
        scenario: ScenarioArgs,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn another_process_gets_the_same_scenario_from_the_arguments() {
        let s = ScenarioSource {
            path: Some("a.toml".into()),
            mode: Some(mrsim_scenario::Mode::Realtime),
            set: vec!["world.dt=0.1".into()],
        };
        let args: Vec<String> = ScenarioArgs::spell(&s)
            .into_iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            args,
            ["a.toml", "--set", "world.dt=0.1", "--mode", "realtime"]
        );
    }
}
