//! The command line: every clap type of `mrsim`, and their conversion into
//! the runtime's plain request types (clap types never leave `src/`).

use clap::{Args, Parser, Subcommand, ValueEnum};
use mrsim_runtime::ScenarioSource;
use mrsim_runtime::launch::Transport;
use mrsim_runtime::sched::Sched;
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

/// Where a Zenoh world listens or its agents connect, and the config.
#[derive(Debug, Clone, Default, Args)]
pub struct ZenohArgs {
    /// A Zenoh JSON5 config file (TLS, user/password auth, routers, lease);
    /// --listen/--connect given as well override its endpoints.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
}

impl ZenohArgs {
    /// The runtime's Zenoh options with `endpoint`.
    pub fn options(&self, endpoint: Option<String>) -> mrsim_transport::zenoh::ZenohOptions {
        mrsim_transport::zenoh::ZenohOptions {
            endpoint,
            config_file: self.zenoh_config.clone(),
        }
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
    /// shm (this machine only) or zenoh (agents may be elsewhere).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: LinkArg,
    /// With --transport zenoh: where to listen (default: loopback only,
    /// tcp/127.0.0.1:7447; tcp/0.0.0.0:7447 for every interface).
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Option<String>,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
}

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
    /// shm (the world on this machine) or zenoh (the world at --connect).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: LinkArg,
    /// With --transport zenoh: the world's address (default
    /// tcp/127.0.0.1:7447).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<String>,
    /// With --transport zenoh: seconds to keep trying to reach the world
    /// again after losing it (a cut link), rejoining with a new token; 0:
    /// end at once.
    #[arg(long, default_value_t = 30.0, value_name = "SECS")]
    pub reconnect: f64,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
}

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
    /// shm (the world on this machine) or zenoh (the world at --connect).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: LinkArg,
    /// With --transport zenoh: the world's address (default
    /// tcp/127.0.0.1:7447).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<String>,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
}

/// `mrsim bench` options.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Agent counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "8,32,64,128,256")]
    pub agents: Vec<usize>,
    /// Tick rate, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Seconds of each run.
    #[arg(long, default_value_t = 10.0)]
    pub duration: f64,
    /// Transports, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "shm,inproc")]
    pub transport: Vec<TransportArg>,
    /// Planner of every robot.
    #[arg(long, default_value = "chung-1")]
    pub planner: String,
    /// Deadline as a fraction of the tick (the scenario's world.deadline).
    #[arg(long, default_value_t = 1.0)]
    pub deadline: f64,
    /// Also measure the bare iceoryx2 fan-out for each agent count (the
    /// `mrsim-baseline` program next to this one).
    #[arg(long)]
    pub baseline: bool,
    /// Output folder (default: runs/bench-<time>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// CPUs to pin everything to (default: the first two, or all if fewer),
    /// and --rt for SCHED_FIFO.
    #[command(flatten)]
    pub sched: SchedArgs,
    /// Loads, comma-separated: measure everything beside that many
    /// CPU-bound processes on the same CPUs (e.g. 0,1,2), one table and
    /// stress.svg/png.
    #[arg(long, value_delimiter = ',', value_name = "N,N,...")]
    pub stress: Vec<usize>,
    /// Make each measurement N times, interleaved with its baseline: with
    /// --baseline, the median overhead ratio and its spread.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub repeat: usize,
}

/// What `mrsim sweep` was asked.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Values to sweep: KEY=V1,V2,... (KEY as for `run --set`; values
    /// split at commas outside brackets, braces and quotes).
    #[arg(long = "set", value_name = "KEY=V1,V2,...")]
    pub set: Vec<String>,
    /// Repeat each combination with world.seed = 1..=N.
    #[arg(long, default_value_t = 1)]
    pub seeds: u64,
    /// Output folder (default: a fresh folder under runs/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Runs at once (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Also report, per seed and other combination, the largest value of
    /// this swept key whose run had no collision.
    #[arg(long, value_name = "KEY")]
    pub allowable: Option<String>,
    /// lockstep (the modelled curve, runs in parallel), realtime (the
    /// measured curve, one run at a time) or both (lockstep, then realtime,
    /// on one figure).
    #[arg(long, value_enum, default_value = "lockstep")]
    pub mode: SweepModeArg,
    /// The swept key on sweep.svg's x axis (default: the first swept key
    /// of more than one value whose values are all numbers).
    #[arg(long, value_name = "KEY")]
    pub x: Option<String>,
    /// The metrics sweep.svg draws, in this order (default: every one of
    /// sweep.csv's)
    #[arg(long, value_name = "METRIC,...", value_delimiter = ',')]
    pub metrics: Vec<String>,
}

/// How a sweep's runs keep time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum SweepModeArg {
    /// Lockstep, several runs at once.
    #[default]
    Lockstep,
    /// Realtime, one run at a time.
    Realtime,
    /// Lockstep, then realtime.
    Both,
}

impl From<SweepModeArg> for mrsim_runtime::sweep::SweepMode {
    fn from(m: SweepModeArg) -> Self {
        use mrsim_runtime::sweep::SweepMode;
        match m {
            SweepModeArg::Lockstep => SweepMode::Lockstep,
            SweepModeArg::Realtime => SweepMode::Realtime,
            SweepModeArg::Both => SweepMode::Both,
        }
    }
}

/// What `mrsim rerun` was asked.
#[derive(Debug, Clone, Args)]
pub struct RerunArgs {
    /// The recorded run's folder (with timing.csv, source.json, scenario.json).
    pub run: PathBuf,
    /// Output folder (default: a fresh folder under runs/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A counterfactual: override a scenario value on top of the run's own
    /// overrides (KEY=VALUE as for `run --set`); the timing stays as recorded.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Skip plot.svg, plot.png and replay.html.
    #[arg(long)]
    pub no_report: bool,
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
    /// shm (the world on this machine) or zenoh (the world at --connect).
    #[arg(long, value_enum, default_value = "shm")]
    pub transport: LinkArg,
    /// With --transport zenoh: the world's address (default
    /// tcp/127.0.0.1:7447).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<String>,
    /// With --transport zenoh: the config file.
    #[command(flatten)]
    pub zenoh: ZenohArgs,
}

impl WatchArgs {
    /// The Zenoh options when the world is reached over Zenoh.
    pub fn zenoh(&self) -> Option<mrsim_transport::zenoh::ZenohOptions> {
        (self.transport == LinkArg::Zenoh).then(|| self.zenoh.options(self.connect.clone()))
    }
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scenario: start the world and one agent process per robot,
    /// wait for the end, write the outputs, print a summary.
    Run(RunArgs),
    /// Measure timing under true concurrency: realtime runs of generated
    /// crossing scenes for each agent count and transport (see BENCHMARKS.md).
    Bench(BenchArgs),
    /// Start a world by hand; agents join with `mrsim agent --robot NAME --run ID`.
    World(WorldArgs),
    /// Drive one robot of a running world.
    Agent(AgentArgs),
    /// Drive robots of a running world from ROS 2 over rmw_zenoh: cmd_vel
    /// in; odom, scan, tf, clock and map out (see docs/ros2.md).
    Ros2(Ros2Args),
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
    Sweep(SweepArgs),
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
    Rerun(RerunArgs),
    /// Check a scenario file without running it.
    Check {
        /// Scenario and overrides.
        #[command(flatten)]
        scenario: ScenarioArgs,
    },
}
