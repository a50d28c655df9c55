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

mod output;
mod rows;
mod scene;
#[cfg(test)]
mod tests;

use crate::error::{Invalid, Refusal};
use crate::sched::{Applied, Sched};
use crate::transport::Transport;
use mrsim_runfolder::bench::{BenchDoc, BenchRow, Overhead};
use mrsim_runfolder::usage::Usage;
use mrsim_runfolder::{
    BENCH_CSV_FILE, BENCH_FILE, BENCH_SVG_FILE, FileError, Percentiles, RunMetrics,
    STRESS_PNG_FILE, STRESS_SVG_FILE,
};
use output::{csv, stress_figure};
use rows::{median_p99, overhead, row_from_run};
use scene::scene_toml;
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

/// What the baseline program writes: its all-in time and round trip.
#[derive(Debug, Clone, Default, serde::Deserialize)]
#[serde(default)]
struct BaselineResult {
    /// Tick published -> last reply in, µs.
    allin_us: Percentiles,
    /// Tick published -> one reply in, µs.
    roundtrip_us: Percentiles,
}
