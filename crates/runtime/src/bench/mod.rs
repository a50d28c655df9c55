//! `mrsim bench`: timing under true concurrency.
//!
//! For each agent count and transport, a realtime run of a generated
//! crossing scene (two streams of robots crossing at right angles in a
//! walled arena, `[generate] kind = "crossing"`), every process pinned to
//! the given CPUs (the bench pins itself; children and threads inherit the
//! mask, and SCHED_FIFO with `--rt`). Each run is a plain
//! `mrsim run SCENE --transport T` in its own folder under `OUT/runs/`, so
//! any row can be reproduced or inspected on its own. From each run's
//! metrics.json (`timing`, per-robot misses) and usage.json the bench takes:
//! round trip (snapshot published -> command received by the world), wake-up
//! latency, planner compute, deadline misses, tick jitter, all-in time
//! (published -> last command in), CPU of the world and of the agents while
//! the run ticked, the time the hypervisor stole from the run's CPUs (a
//! virtual machine's own interference), and peak RSS of the world and of
//! one agent. With a baseline, the same fan-out with bare iceoryx2 (the
//! `mrsim-baseline` program next to this one, `benches/baseline`) per agent
//! count.
//!
//! Under load (`stress`: that many CPU-bound processes on the same CPUs,
//! [`Stress`], started before and killed after each level's runs) every
//! measurement is made at each level, and `stress.svg`/`stress.png` draw
//! round trip and misses against the load. With `repeat` > 1 each run and
//! its baseline are made that many times, interleaved (mrsim, then the bare
//! fan-out, then mrsim again ...), and bench.json's `overhead` gives the
//! median of the pairs' ratios with its spread: each side alone moves from
//! run to run on a shared machine, the ratio of neighbours much less.
//!
//! Outputs: `bench.json` (`{"rows": [...], "overhead": [...]}`), `bench.csv`
//! and `bench.svg` (p99 round trip and miss rate against agent count); the
//! caller prints the table.

use crate::error::{Invalid, Refusal};
use crate::launch::Transport;
use crate::sched::{Applied, Sched};
use mrsim_report::sweep_plot::{Figure, Panel, Point, Series};
use mrsim_runfolder::bench::{BenchDoc, BenchRow, MedianP99, Overhead, Quantiles};
use mrsim_runfolder::usage::Usage;
use mrsim_runfolder::{
    BENCH_CSV_FILE, BENCH_FILE, BENCH_SVG_FILE, FileError, Percentiles, RunMetrics,
    STRESS_PNG_FILE, STRESS_SVG_FILE,
};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// What to measure.
#[derive(Debug, Clone)]
pub struct BenchPlan {
    /// Agent counts.
    pub agents: Vec<usize>,
    /// Tick rate, Hz.
    pub rate: f64,
    /// Seconds of each run.
    pub duration: f64,
    /// Transports, each run for every agent count.
    pub transports: Vec<Transport>,
    /// Planner of every robot.
    pub planner: String,
    /// Deadline as a fraction of the tick.
    pub deadline: f64,
    /// Also measure the bare iceoryx2 fan-out for each agent count.
    pub baseline: bool,
    /// Output folder (`None`: runs/bench-<time>).
    pub out: Option<PathBuf>,
    /// CPUs (`None`: the first two, or all if fewer) and SCHED_FIFO.
    pub sched: Sched,
    /// Loads: numbers of CPU-bound processes beside each measurement
    /// (empty: none).
    pub stress: Vec<usize>,
    /// Measurements of each run (and its baseline), interleaved.
    pub repeat: usize,
}

/// The baseline's program, next to this executable.
pub const BASELINE_PROGRAM: &str = "mrsim-baseline";

/// Why a bench failed.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// Refused before anything ran: the counts, rate, duration, transports,
    /// planner, CPUs or output folder.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The running executable is not known.
    #[error("cannot find the mrsim executable")]
    Exe(#[source] std::io::Error),
    /// A file could not be written.
    #[error("writing {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be read.
    #[error("reading {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file is not JSON.
    #[error("parsing {}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// A program could not be started.
    #[error("cannot start `{what}`")]
    Start {
        /// The command.
        what: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The baseline's program is not built.
    #[error(
        "the raw iceoryx2 baseline is its own program and {} does not exist: build it with `cargo build --release --workspace`",
        path.display()
    )]
    NoBaseline {
        /// Where it was looked for.
        path: PathBuf,
    },
    /// One run failed.
    #[error("`mrsim run {}` failed ({status}): {stderr}", scene.display())]
    Run {
        /// Its scene.
        scene: PathBuf,
        /// How it ended.
        status: std::process::ExitStatus,
        /// What it said.
        stderr: String,
    },
    /// One baseline failed.
    #[error("baseline with {agents} agents failed ({status}): {stderr}")]
    Baseline {
        /// Its agent count.
        agents: usize,
        /// How it ended.
        status: std::process::ExitStatus,
        /// What it said.
        stderr: String,
    },
}

impl Refusal for BenchError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            BenchError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// Robot radius, queue spacing and sensing range of the generated scene, m.
const ROBOT_RADIUS: f64 = 0.25;
const SENSING_RANGE: f64 = 3.0;
const HEAD_DISTANCE: f64 = 3.0;

/// The generated scene for `agents` robots: two crossing streams in a walled
/// arena large enough for both queues and their mirrored goals, realtime at
/// `rate` Hz for `duration` s, one physics substep per tick.
fn scene_toml(agents: usize, rate: f64, duration: f64, planner: &str, deadline: f64) -> String {
    // Queue spacing of [generate] crossing: three robot radii.
    let queue = agents.div_ceil(2) as f64 * 3.0 * ROBOT_RADIUS;
    let half = (HEAD_DISTANCE + queue + 2.0).ceil();
    format!(
        r#"name = "bench-crossing-{agents}"
description = "mrsim bench: {agents} robots in two streams crossing at right angles, realtime at {rate} Hz, {planner}"
length_unit = "m"

[world]
dt = {dt}
substeps = 1
duration = {duration}
mode = "realtime"
on_deadline_miss = "hold"
deadline = {deadline}
seed = 1
arena = {{ min = [-{half}, -{half}], max = [{half}, {half}] }}

[defaults]
radius = {ROBOT_RADIUS}
max_speed = 1.0
max_accel = 2.0
sensing_range = {SENSING_RANGE}
goal_tolerance = 0.1

[generate]
kind = "crossing"
count = {agents}
radius = {HEAD_DISTANCE}
planner = "{planner}"
"#,
        dt = 1.0 / rate,
    )
}

/// Percentiles of a metrics.json histogram; none where it has no samples.
fn quantiles(p: &Percentiles) -> Quantiles {
    let has = p.count > 0;
    Quantiles {
        p50: has.then_some(p.p50),
        p99: has.then_some(p.p99),
        p999: has.then_some(p.p999),
        max: has.then_some(p.max),
    }
}

/// Median and 99th percentile of a metrics.json histogram; none where it
/// has no samples.
fn median_p99(p: &Percentiles) -> MedianP99 {
    let q = quantiles(p);
    MedianP99 {
        p50: q.p50,
        p99: q.p99,
    }
}

/// One row of bench.json from a run folder's metrics.json and usage.json
/// (the bench's own fields, `cpus`, `rt`, `planner`, `run_dir`, left
/// empty).
fn row_from_run(
    agents: usize,
    transport: Transport,
    rate: f64,
    metrics: &RunMetrics,
    usage: &Usage,
) -> BenchRow {
    let t = &metrics.timing;
    let wall = t.wall_s;
    let ticks = metrics.ticks;
    let misses: u64 = metrics.robots.values().map(|r| r.deadline_misses).sum();
    let slots = ticks * agents as u64;
    let agents_cpu = usage.agents_cpu_s;
    // In-process, the world's process holds the agent threads too.
    let world_cpu = match transport {
        Transport::Shm | Transport::Zenoh => t.process_cpu_s,
        Transport::Inproc => (t.process_cpu_s - agents_cpu).max(0.0),
    };
    let pct_of_wall = |s: f64| if wall > 0.0 { 100.0 * s / wall } else { 0.0 };
    let mb = |kb: u64| kb as f64 / 1024.0;
    BenchRow {
        agents,
        transport: transport.name().to_string(),
        rate_hz: rate,
        roundtrip_us: quantiles(&t.latency_us),
        allin_us: median_p99(&t.allin_us),
        miss_rate: if slots > 0 {
            misses as f64 / slots as f64
        } else {
            0.0
        },
        jitter_us_p99: quantiles(&t.jitter_us).p99,
        world_cpu_pct: pct_of_wall(world_cpu),
        agents_cpu_pct: pct_of_wall(agents_cpu),
        steal_pct: t.cpus_steal_s.map(pct_of_wall),
        world_rss_mb: Some(mb(t.process_maxrss_kb)),
        agent_rss_mb: usage.agent_maxrss_kb.map(mb),
        wake_us: quantiles(&t.wake_us),
        compute_us: quantiles(&t.compute_us),
        world_tick_us: quantiles(&t.world_tick_us),
        physics_us: quantiles(&t.physics_us),
        ticks,
        deadline_misses: misses,
        wall_s: wall,
        // Simulated over wall time of the tick loop: below 1 the world could
        // not hold the rate (ticks started ever later, see the jitter), and
        // the miss rate alone understates how far it fell behind.
        realtime_factor: metrics.realtime_factor,
        ..Default::default()
    }
}

/// A bench ready to start: checked, pinned, its folder made.
#[derive(Debug)]
pub struct PreparedBench {
    plan: BenchPlan,
    applied: Applied,
    out: PathBuf,
    exe: PathBuf,
    agents: Vec<usize>,
    stress: Vec<usize>,
}

/// The most CPU-bound processes `--stress` starts.
pub const MAX_STRESS: usize = 64;

/// CPU-bound processes (`mrsim spin`, [`mrsim_sys::sched::spin_while_child_of`])
/// on the bench's CPUs, which they inherit with its affinity mask, at
/// normal scheduling. Dropping it kills and reaps them; each also exits by
/// itself once the bench is gone, so none outlives an interrupted bench.
#[derive(Debug)]
pub struct Stress {
    children: Vec<std::process::Child>,
}

impl Stress {
    /// Starts `n` load processes of `exe`.
    pub fn start(exe: &Path, n: usize) -> Result<Self, BenchError> {
        let mut stress = Stress {
            children: Vec::new(),
        };
        for _ in 0..n {
            let child = Command::new(exe)
                .args(["spin", "--parent"])
                .arg(std::process::id().to_string())
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .map_err(|source| BenchError::Start {
                    what: "mrsim spin".into(),
                    source,
                })?;
            stress.children.push(child);
        }
        Ok(stress)
    }

    /// The load processes' pids.
    pub fn pids(&self) -> Vec<u32> {
        self.children.iter().map(|c| c.id()).collect()
    }
}

impl Drop for Stress {
    fn drop(&mut self) {
        for c in &mut self.children {
            let _ = c.kill();
        }
        for c in &mut self.children {
            let _ = c.wait();
        }
    }
}

/// What happens while a bench goes on.
#[derive(Debug)]
pub enum BenchStep {
    /// A measurement starts (`8 agents over shm`).
    Starting(String),
    /// It is done.
    Done,
}

/// What a bench gave.
#[derive(Debug)]
pub struct BenchOutcome {
    /// bench.json's rows, one per load, agent count, transport and
    /// repetition.
    pub rows: Vec<BenchRow>,
    /// bench.json's overhead figures (with a baseline).
    pub overhead: Vec<Overhead>,
    /// The output folder.
    pub out: PathBuf,
    /// bench.svg could not be drawn.
    pub svg_error: Option<String>,
}

/// Checks the plan (the planner and the scene before anything runs), pins
/// this process (and so every run) and makes the output folder.
pub fn prepare(plan: &BenchPlan) -> Result<PreparedBench, BenchError> {
    if plan.agents.is_empty() || plan.agents.contains(&0) {
        return Err(Invalid::new("--agents: give positive counts, e.g. 8,32,64").into());
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !positive(plan.rate) || !positive(plan.duration) {
        return Err(Invalid::new("--rate and --duration must be positive").into());
    }
    if plan.repeat == 0 {
        return Err(Invalid::new("--repeat must be at least 1").into());
    }
    if plan.stress.iter().any(|&k| k > MAX_STRESS) {
        return Err(Invalid(format!(
            "--stress: at most {MAX_STRESS} processes (each takes a whole CPU while it runs)"
        ))
        .into());
    }
    if plan.transports.is_empty() {
        return Err(Invalid::new("--transport: give one or more of shm, inproc, zenoh").into());
    }
    let first = scene_toml(
        plan.agents[0],
        plan.rate,
        plan.duration,
        &plan.planner,
        plan.deadline,
    );
    let loaded =
        mrsim_scenario::parse(&first, "bench scene").map_err(|e| Invalid(e.to_string()))?;
    for r in loaded.scenario.robots.iter().take(1) {
        mrsim_agents::build_planner(r).map_err(|e| Invalid(format!("--planner: {e}")))?;
    }
    let mut sched = plan.sched.clone();
    if sched.cpus.is_none() {
        let n = mrsim_sys::sched::online_cpus().min(2);
        sched.cpus = Some(if n > 1 {
            format!("0-{}", n - 1)
        } else {
            "0".into()
        });
    }
    let applied = crate::sched::apply(&sched)?;
    let out = crate::out::prepare(plan.out.as_deref(), "bench")?;
    std::fs::create_dir_all(out.join("runs"))
        .map_err(|e| Invalid(format!("output folder {}: {e}", out.display())))?;
    let exe = std::env::current_exe().map_err(BenchError::Exe)?;
    let mut agents = plan.agents.clone();
    agents.sort_unstable();
    agents.dedup();
    let mut stress = plan.stress.clone();
    stress.sort_unstable();
    stress.dedup();
    if stress.is_empty() {
        stress.push(0);
    }
    Ok(PreparedBench {
        plan: plan.clone(),
        applied,
        out,
        exe,
        agents,
        stress,
    })
}

impl PreparedBench {
    /// What the scheduling request gave.
    pub fn applied(&self) -> &Applied {
        &self.applied
    }

    /// How many measurements [`Self::run`] makes.
    pub fn steps(&self) -> usize {
        self.stress.len()
            * self.agents.len()
            * self.plan.repeat
            * (self.plan.transports.len() + usize::from(self.plan.baseline))
    }

    /// Runs every measurement and writes bench.json, bench.csv and
    /// bench.svg.
    pub fn run(self, on_step: &mut dyn FnMut(BenchStep)) -> Result<BenchOutcome, BenchError> {
        let (plan, out) = (&self.plan, &self.out);
        let baseline = if plan.baseline {
            let p = self.exe.with_file_name(BASELINE_PROGRAM);
            if !p.is_file() {
                return Err(BenchError::NoBaseline { path: p });
            }
            Some(p)
        } else {
            None
        };
        let mut rows = Vec::new();
        for &n in &self.agents {
            let scene = out.join("runs").join(format!("crossing-{n}.toml"));
            let text = scene_toml(n, plan.rate, plan.duration, &plan.planner, plan.deadline);
            std::fs::write(&scene, text).map_err(|source| BenchError::Write {
                path: scene.clone(),
                source,
            })?;
        }
        for &k in &self.stress {
            let _load = Stress::start(&self.exe, k)?;
            let load = if k > 0 {
                format!(", {k} CPU-bound beside")
            } else {
                String::new()
            };
            for &n in &self.agents {
                let scene = out.join("runs").join(format!("crossing-{n}.toml"));
                for r in 1..=plan.repeat {
                    let mut suffix = String::new();
                    if k > 0 {
                        suffix.push_str(&format!("-stress{k}"));
                    }
                    if plan.repeat > 1 {
                        suffix.push_str(&format!("-r{r}"));
                    }
                    let of = if plan.repeat > 1 {
                        format!(" ({r}/{})", plan.repeat)
                    } else {
                        String::new()
                    };
                    let mut batch = Vec::new();
                    for &t in &plan.transports {
                        on_step(BenchStep::Starting(format!(
                            "{n} agents over {}{load}{of}",
                            t.name()
                        )));
                        let dir = out.join("runs").join(format!("{}-{n}{suffix}", t.name()));
                        let (metrics, usage) = run_one(&self.exe, &scene, &dir, t)?;
                        let mut row = row_from_run(n, t, plan.rate, &metrics, &usage);
                        row.cpus = self.applied.cpus.clone();
                        row.rt = self.applied.rt;
                        row.planner = plan.planner.clone();
                        row.run_dir = dir.to_string_lossy().into_owned();
                        row.stress = k;
                        row.repeat = r;
                        batch.push(row);
                        on_step(BenchStep::Done);
                    }
                    if let Some(program) = &baseline {
                        on_step(BenchStep::Starting(format!(
                            "{n} agents, bare iceoryx2 baseline{load}{of}"
                        )));
                        let name = format!("baseline-{n}{suffix}.json");
                        let b = run_baseline(program, out, &name, n, plan)?;
                        for row in &mut batch {
                            row.baseline_allin_us = Some(median_p99(&b.allin_us));
                            row.baseline_roundtrip_us = Some(median_p99(&b.roundtrip_us));
                        }
                        on_step(BenchStep::Done);
                    }
                    rows.extend(batch);
                }
            }
        }
        let write = |name: &str, text: String| {
            let path = out.join(name);
            std::fs::write(&path, text).map_err(|source| BenchError::Write { path, source })
        };
        let doc = BenchDoc {
            overhead: overhead(&rows),
            rows,
        };
        let text = serde_json::to_string_pretty(&doc).map_err(|e| BenchError::Write {
            path: out.join(BENCH_FILE),
            source: e.into(),
        })?;
        write(BENCH_FILE, format!("{text}\n"))?;
        let rows = doc.rows;
        let flat: Vec<Value> = rows
            .iter()
            .map(|r| serde_json::to_value(r).unwrap_or_default())
            .collect();
        write(BENCH_CSV_FILE, csv(&flat))?;
        // The first repetition's rows; a line per transport and load.
        let series: Vec<mrsim_report::bench_plot::Point> = rows
            .iter()
            .filter(|r| r.repeat == 1)
            .map(|r| mrsim_report::bench_plot::Point {
                series: if self.stress.len() > 1 {
                    format!("{}, {} CPU-bound beside", r.transport, r.stress)
                } else {
                    r.transport.clone()
                },
                agents: r.agents as f64,
                roundtrip_p99_ms: r.roundtrip_us.p99.unwrap_or(0.0) / 1000.0,
                miss_pct: 100.0 * r.miss_rate,
            })
            .collect();
        let mut svg_error = mrsim_report::bench_plot::write(&series, &out.join(BENCH_SVG_FILE))
            .err()
            .map(|e| e.to_string());
        if self.stress.len() > 1 {
            let drawn = mrsim_report::sweep_plot::write_figure(
                &stress_figure(&rows, &self.stress),
                &out.join(STRESS_SVG_FILE),
                &out.join(STRESS_PNG_FILE),
            );
            if let Err(e) = drawn {
                svg_error = Some(e.to_string());
            }
        }
        Ok(BenchOutcome {
            rows,
            overhead: doc.overhead,
            out: self.out,
            svg_error,
        })
    }
}

fn read_json<T: serde::de::DeserializeOwned>(dir: &Path, name: &str) -> Result<T, BenchError> {
    mrsim_runfolder::read_json(dir, name).map_err(|e| match e {
        FileError::Io { path, source } => BenchError::Read { path, source },
        FileError::Json { path, source } => BenchError::Parse { path, source },
    })
}

fn run_one(
    exe: &Path,
    scene: &Path,
    dir: &Path,
    transport: Transport,
) -> Result<(RunMetrics, Usage), BenchError> {
    let out = Command::new(exe)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(dir)
        .args(["--quiet", "--no-report", "--transport", transport.name()])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|source| BenchError::Start {
            what: "mrsim run".into(),
            source,
        })?;
    if !out.status.success() {
        return Err(BenchError::Run {
            scene: scene.to_path_buf(),
            status: out.status,
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok((
        read_json(dir, mrsim_runfolder::METRICS_FILE)?,
        read_json(dir, mrsim_runfolder::USAGE_FILE)?,
    ))
}

fn run_baseline(
    program: &Path,
    dir: &Path,
    name: &str,
    agents: usize,
    plan: &BenchPlan,
) -> Result<BaselineResult, BenchError> {
    let file = dir.join(name);
    let run_id = mrsim_transport::Namespace::fresh_run_id();
    let out = Command::new(program)
        .args(["world", "--run", &run_id, "--agents"])
        .arg(agents.to_string())
        .arg("--rate")
        .arg(plan.rate.to_string())
        .arg("--duration")
        .arg(plan.duration.to_string())
        .arg("--deadline")
        .arg(plan.deadline.to_string())
        .arg("--out")
        .arg(&file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|source| BenchError::Start {
            what: format!("{BASELINE_PROGRAM} world"),
            source,
        })?;
    if !out.status.success() {
        return Err(BenchError::Baseline {
            agents,
            status: out.status,
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    read_json(dir, name)
}

/// The value at fraction `q` of sorted `xs`, interpolated linearly between
/// neighbours (as numpy's default).
fn quantile(xs: &[f64], q: f64) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    let pos = q * (xs.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    xs[lo] + (xs[hi] - xs[lo]) * (pos - lo as f64)
}

/// Per agent count, transport and load: the ratio of mrsim's all-in
/// median to the bare fan-out's measured right after it, over the
/// repetitions, with its median, quartiles and range.
fn overhead(rows: &[BenchRow]) -> Vec<Overhead> {
    let mut out: Vec<Overhead> = Vec::new();
    for r in rows {
        let ratio = match (r.allin_us.p50, r.baseline_allin_us.and_then(|b| b.p50)) {
            (Some(a), Some(b)) if b > 0.0 => a / b,
            _ => continue,
        };
        match out
            .iter_mut()
            .find(|o| o.agents == r.agents && o.transport == r.transport && o.stress == r.stress)
        {
            Some(o) => o.ratios.push(ratio),
            None => out.push(Overhead {
                agents: r.agents,
                transport: r.transport.clone(),
                stress: r.stress,
                ratios: vec![ratio],
                ..Default::default()
            }),
        }
    }
    for o in &mut out {
        let mut xs = o.ratios.clone();
        xs.sort_by(f64::total_cmp);
        o.pairs = xs.len();
        o.median = quantile(&xs, 0.5);
        o.q1 = quantile(&xs, 0.25);
        o.q3 = quantile(&xs, 0.75);
        o.min = xs[0];
        o.max = xs[xs.len() - 1];
    }
    out
}

/// `stress.svg`: round trip and misses against the number of CPU-bound
/// processes, one line per transport and agent count, each point the mean
/// over the repetitions with its 95 % interval.
fn stress_figure(rows: &[BenchRow], levels: &[usize]) -> Figure {
    let mut lines: Vec<(String, usize)> = Vec::new();
    for r in rows {
        let key = (r.transport.clone(), r.agents);
        if !lines.contains(&key) {
            lines.push(key);
        }
    }
    type Metric = (&'static str, &'static str, fn(&BenchRow) -> Option<f64>);
    let metrics: [Metric; 4] = [
        ("round trip p50", "us", |r| r.roundtrip_us.p50),
        ("round trip p99", "us", |r| r.roundtrip_us.p99),
        ("all-in p99", "us (published -> last command in)", |r| {
            r.allin_us.p99
        }),
        ("deadline misses", "% of agent-ticks", |r| {
            Some(100.0 * r.miss_rate)
        }),
    ];
    let panels = metrics
        .iter()
        .map(|(title, unit, value)| Panel {
            title: title.to_string(),
            y_label: unit.to_string(),
            fraction: false,
            lines: lines
                .iter()
                .map(|(t, n)| {
                    levels
                        .iter()
                        .filter_map(|&k| {
                            let xs: Vec<f64> = rows
                                .iter()
                                .filter(|r| r.transport == *t && r.agents == *n && r.stress == k)
                                .filter_map(value)
                                .collect();
                            let (mean, half_width) = crate::sweep::mean_ci(&xs);
                            Some(Point {
                                x: k as f64,
                                mean: mean?,
                                half_width,
                            })
                        })
                        .collect()
                })
                .collect(),
        })
        .collect();
    Figure {
        title: "mrsim bench --stress: timing against CPU-bound load on the run's CPUs".into(),
        x_label: "CPU-bound processes beside the run".into(),
        series: lines
            .iter()
            .enumerate()
            .map(|(i, (t, n))| Series {
                label: format!("{t}, {n} agents"),
                colour: i,
                measured: false,
            })
            .collect(),
        panels,
    }
}

/// What the baseline program writes: its all-in time and round trip.
#[derive(Debug, Clone, Default, serde::Deserialize)]
#[serde(default)]
struct BaselineResult {
    /// Tick published -> last reply in, µs.
    allin_us: Percentiles,
    /// Tick published -> one reply in, µs.
    roundtrip_us: Percentiles,
}

/// bench.csv: the rows flattened (nested percentiles as `field_p50` ...).
fn csv(rows: &[Value]) -> String {
    let mut cols: Vec<String> = Vec::new();
    let flat: Vec<Vec<(String, String)>> = rows
        .iter()
        .map(|r| {
            let mut cells = Vec::new();
            if let Some(o) = r.as_object() {
                for (k, v) in o {
                    match v {
                        Value::Object(inner) => {
                            for (ik, iv) in inner {
                                cells.push((format!("{k}_{ik}"), cell(iv)));
                            }
                        }
                        other => cells.push((k.clone(), cell(other))),
                    }
                }
            }
            cells
        })
        .collect();
    for r in &flat {
        for (k, _) in r {
            if !cols.contains(k) {
                cols.push(k.clone());
            }
        }
    }
    let mut out = cols.join(",");
    out.push('\n');
    for r in &flat {
        let line: Vec<String> = cols
            .iter()
            .map(|c| {
                r.iter()
                    .find(|(k, _)| k == c)
                    .map(|(_, v)| v.clone())
                    .unwrap_or_default()
            })
            .collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

fn cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        Value::Array(a) => a.iter().map(cell).collect::<Vec<_>>().join(" "),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(transport: &str) -> (RunMetrics, Usage) {
        let metrics: RunMetrics = serde_json::from_value(serde_json::json!({
            "ticks": 10,
            "realtime_factor": 0.9,
            "robots": {"a": {"deadline_misses": 3}, "b": {"deadline_misses": 1}},
            "timing": {
                "wall_s": 2.0, "process_cpu_s": 1.0, "process_maxrss_kb": 2048,
                "latency_us": {"p50": 10.0, "p99": 20.0, "p999": 30.0, "max": 40.0, "count": 5},
                "allin_us": {"count": 0}
            }
        }))
        .expect("metrics.json");
        let usage = Usage {
            transport: transport.into(),
            agents_reported: 2,
            agents_cpu_s: 0.4,
            agent_maxrss_kb: (transport == "shm").then_some(1024),
        };
        (metrics, usage)
    }

    #[test]
    fn a_row_counts_misses_per_slot_and_leaves_empty_histograms_null() {
        let (m, u) = run("shm");
        let row = row_from_run(2, Transport::Shm, 5.0, &m, &u);
        assert_eq!(row.miss_rate, 4.0 / 20.0);
        assert_eq!(row.roundtrip_us.p99, Some(20.0));
        assert_eq!(row.allin_us, MedianP99::default(), "no sample: null");
        assert_eq!((row.world_rss_mb, row.agent_rss_mb), (Some(2.0), Some(1.0)));
        assert_eq!(row.world_cpu_pct, 50.0);
    }

    fn pair(agents: usize, stress: usize, mrsim: f64, bare: f64) -> BenchRow {
        BenchRow {
            agents,
            stress,
            transport: "shm".into(),
            allin_us: MedianP99 {
                p50: Some(mrsim),
                p99: None,
            },
            baseline_allin_us: Some(MedianP99 {
                p50: Some(bare),
                p99: None,
            }),
            ..Default::default()
        }
    }

    #[test]
    fn the_overhead_is_the_median_of_the_pairs_ratios_with_quartiles_and_range() {
        let rows = [
            pair(64, 0, 120.0, 100.0),
            pair(64, 0, 150.0, 100.0),
            pair(64, 0, 100.0, 100.0),
            pair(64, 0, 260.0, 200.0),
            pair(64, 0, 140.0, 100.0),
            pair(64, 1, 300.0, 100.0),
            // No baseline median: not a pair.
            BenchRow {
                agents: 64,
                stress: 1,
                transport: "shm".into(),
                ..Default::default()
            },
        ];
        let o = overhead(&rows);
        assert_eq!(o.len(), 2);
        assert_eq!(o[0].ratios, [1.2, 1.5, 1.0, 1.3, 1.4]);
        assert_eq!(o[0].pairs, 5);
        assert!((o[0].median - 1.3).abs() < 1e-12);
        // Sorted 1.0 1.2 1.3 1.4 1.5: quartiles at positions 1 and 3.
        assert!((o[0].q1 - 1.2).abs() < 1e-12 && (o[0].q3 - 1.4).abs() < 1e-12);
        assert_eq!((o[0].min, o[0].max), (1.0, 1.5));
        assert_eq!((o[1].stress, o[1].pairs, o[1].median), (1, 1, 3.0));
    }

    #[test]
    fn quantiles_interpolate_between_neighbours() {
        assert_eq!(quantile(&[1.0, 2.0], 0.5), 1.5);
        assert_eq!(quantile(&[1.0, 2.0, 4.0, 8.0], 0.25), 1.75);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn in_process_the_agents_cpu_is_taken_out_of_the_worlds() {
        let (m, u) = run("inproc");
        let row = row_from_run(2, Transport::Inproc, 5.0, &m, &u);
        assert!(
            (row.world_cpu_pct - 30.0).abs() < 1e-9,
            "{}",
            row.world_cpu_pct
        );
        assert!((row.agents_cpu_pct - 20.0).abs() < 1e-9);
        assert_eq!(row.agent_rss_mb, None);
    }
}
