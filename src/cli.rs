//! Command-line interface.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Exit status for a refused scenario or command line.
pub const EXIT_INVALID: i32 = 2;
/// Exit status for a run that failed.
pub const EXIT_FAILED: i32 = 1;

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
#[derive(Debug, Clone, Args)]
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

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scenario: start the world and one agent process per robot,
    /// wait for the end, write the outputs, print a summary.
    Run {
        /// Scenario and overrides.
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// Run id (iceoryx2 namespace); default: a fresh one.
        #[arg(long)]
        run: Option<String>,
        /// Print only the output folder, not the table.
        #[arg(long)]
        quiet: bool,
        /// Restart an agent process that dies while the world runs (same
        /// command line); it rejoins and drives its robot from where it is.
        #[arg(long)]
        restart_agents: bool,
        /// World and agents as processes over iceoryx2 (shm) or as threads
        /// of one process over crossbeam channels (inproc).
        #[arg(long, value_enum, default_value = "shm")]
        transport: crate::launch::Transport,
        /// Scheduling: --cpus LIST, --rt.
        #[command(flatten)]
        sched: crate::sched::SchedArgs,
        /// Do not draw plot.svg/png and replay.html.
        #[arg(long, hide = true)]
        no_report: bool,
    },
    /// Measure timing under true concurrency: realtime runs of generated
    /// crossing scenes for each agent count and transport (see BENCHMARKS.md).
    Bench(crate::bench::BenchArgs),
    /// Raw iceoryx2 fan-out baseline, world side (started by `bench --baseline`).
    #[command(hide = true)]
    BaselineWorld(crate::baseline::WorldArgs),
    /// Raw iceoryx2 fan-out baseline, agent side (started by `baseline-world`).
    #[command(hide = true)]
    BaselineAgent(crate::baseline::AgentArgs),
    /// Start a world by hand; agents join with `mrsim agent --robot NAME --run ID`.
    World {
        /// Scenario and overrides.
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// Run id agents use to find this world.
        #[arg(long, default_value = "default")]
        run: String,
        /// Give up if not every agent has joined after this many seconds
        /// (default: wait forever).
        #[arg(long)]
        start_timeout: Option<f64>,
        /// Started by `mrsim run`: the launcher cleans up and prints.
        #[arg(long, hide = true)]
        launched: bool,
    },
    /// Drive one robot of a running world.
    Agent {
        /// The robot's name in the scenario.
        #[arg(long)]
        robot: String,
        /// The run id of the world.
        #[arg(long, default_value = "default")]
        run: String,
        /// Seconds to wait for the world.
        #[arg(long, default_value_t = 30.0)]
        timeout: f64,
        /// Fault injection for tests: put this robot id in every command.
        #[arg(long, hide = true)]
        impersonate: Option<u32>,
        /// Fault injection for tests: nan, inf, huge, other-robot, past-tick,
        /// future-tick, double, sent-late, join-twice, hang-at-tick=N, die-at-tick=N, stop-at-tick=N,
        /// slow-ms=N.
        #[arg(long, hide = true)]
        fault: Option<mrsim_agents::fault::Fault>,
        /// For tests of strangers: announce this protocol version.
        #[arg(long, hide = true)]
        protocol_version: Option<u32>,
        /// Write CPU time and peak RSS here at the end (set by `mrsim run`).
        #[arg(long, hide = true)]
        usage_out: Option<PathBuf>,
    },
    /// Watch a running world: a live dashboard of its bodies and agents
    /// (read-only; never slows the world or counts as an agent).
    Top {
        /// The run id of the world.
        #[arg(long, default_value = "default")]
        run: String,
        /// Seconds to wait for the world.
        #[arg(long, default_value_t = 10.0)]
        timeout: f64,
    },
    /// Regenerate plot.svg, plot.png and replay.html of a run folder.
    Report {
        /// The run folder.
        dir: PathBuf,
    },
    /// List the planners.
    Planners,
    /// Run every combination of values (x seeds 1..N) in lockstep and
    /// tabulate the metrics: sweep.csv, summary.csv, a table of means with
    /// 95 % intervals.
    Sweep(crate::sweep::SweepArgs),
    /// Check a scenario file without running it.
    Check {
        /// Scenario and overrides.
        #[command(flatten)]
        scenario: ScenarioArgs,
    },
}

/// Runs the parsed command line; returns the process exit status.
pub fn main(cli: Cli) -> i32 {
    let command = cli.command.unwrap_or(Command::Run {
        scenario: ScenarioArgs {
            scenario: None,
            mode: None,
            set: Vec::new(),
            out: None,
        },
        run: None,
        quiet: false,
        restart_agents: false,
        transport: crate::launch::Transport::Shm,
        sched: crate::sched::SchedArgs::default(),
        no_report: false,
    });
    let result = match command {
        Command::Run {
            scenario,
            run,
            quiet,
            restart_agents,
            transport,
            sched,
            no_report,
        } => crate::launch::run(
            &scenario,
            run,
            quiet,
            &crate::launch::RunHow {
                transport,
                sched,
                no_report,
                restart_agents,
            },
        ),
        Command::Bench(args) => crate::bench::main(&args),
        Command::BaselineWorld(args) => crate::baseline::world(&args),
        Command::BaselineAgent(args) => crate::baseline::agent(&args),
        Command::World {
            scenario,
            run,
            start_timeout,
            launched,
        } => crate::launch::world(&scenario, &run, start_timeout, launched),
        Command::Agent {
            robot,
            run,
            timeout,
            impersonate,
            fault,
            protocol_version,
            usage_out,
        } => crate::launch::agent(
            &robot,
            &run,
            timeout,
            crate::launch::Misbehave {
                impersonate,
                fault,
                protocol_version,
            },
            usage_out.as_deref(),
        ),
        Command::Top { run, timeout } => crate::top::run(&run, timeout),
        Command::Report { dir } => crate::report_cmd::run(&dir),
        Command::Sweep(args) => crate::sweep::sweep(&args),
        Command::Planners => {
            for p in mrsim_planners::PLANNERS {
                println!("{:<20} {}", p.name, p.summary);
            }
            Ok(0)
        }
        Command::Check { scenario } => crate::launch::load(&scenario).map(|l| {
            println!(
                "{}: ok ({} robots, {} obstacles)",
                l.origin(),
                l.scenario.robots.len(),
                l.scenario.obstacles.len()
            );
            0
        }),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            if let Some(invalid) = e.downcast_ref::<crate::launch::Invalid>() {
                eprintln!("error: {invalid}");
                return EXIT_INVALID;
            }
            eprintln!("error: {e:#}");
            EXIT_FAILED
        }
    }
}
