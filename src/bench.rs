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
//! one agent. With
//! `--baseline`, the same fan-out with bare iceoryx2 (`mrsim
//! baseline-world`) per agent count.
//!
//! Outputs: a table on stdout, `bench.json` (`{"rows": [...]}`), `bench.csv`
//! and `bench.svg` (p99 round trip and miss rate against agent count).

use crate::launch::Transport;
use crate::sched::SchedArgs;
use anyhow::{Context, Result, anyhow};
use clap::Args;
use serde_json::{Value, json};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

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
    pub transport: Vec<Transport>,
    /// Planner of every robot.
    #[arg(long, default_value = "chung-1")]
    pub planner: String,
    /// Deadline as a fraction of the tick (the scenario's world.deadline).
    #[arg(long, default_value_t = 1.0)]
    pub deadline: f64,
    /// Also measure the bare iceoryx2 fan-out for each agent count.
    #[arg(long)]
    pub baseline: bool,
    /// Output folder (default: runs/bench-<time>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// CPUs to pin everything to (default: the first two, or all if fewer),
    /// and --rt for SCHED_FIFO.
    #[command(flatten)]
    pub sched: SchedArgs,
}

/// Robot radius, queue spacing and sensing range of the generated scene, m.
const ROBOT_RADIUS: f64 = 0.25;
const SENSING_RANGE: f64 = 3.0;
const HEAD_DISTANCE: f64 = 3.0;

/// The generated scene for `agents` robots: two crossing streams in a walled
/// arena large enough for both queues and their mirrored goals, realtime at
/// `rate` Hz for `duration` s, one physics substep per tick.
pub fn scene_toml(agents: usize, rate: f64, duration: f64, planner: &str, deadline: f64) -> String {
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

/// Percentiles of a metrics.json histogram; null where it has no samples.
fn pct(v: &Value, keys: &[&str]) -> Value {
    let empty = v["count"].as_u64().unwrap_or(0) == 0;
    keys.iter()
        .map(|k| {
            (
                k.to_string(),
                if empty { Value::Null } else { v[*k].clone() },
            )
        })
        .collect::<serde_json::Map<_, _>>()
        .into()
}

const ALL: &[&str] = &["p50", "p99", "p999", "max"];

/// One row of bench.json from a run folder's metrics.json and usage.json.
pub fn row_from_run(
    agents: usize,
    transport: Transport,
    rate: f64,
    metrics: &Value,
    usage: &Value,
) -> Value {
    let t = &metrics["timing"];
    let wall = t["wall_s"].as_f64().unwrap_or(0.0);
    let ticks = metrics["ticks"].as_u64().unwrap_or(0);
    let misses: u64 = metrics["robots"]
        .as_object()
        .map(|r| {
            r.values()
                .filter_map(|v| v["deadline_misses"].as_u64())
                .sum()
        })
        .unwrap_or(0);
    let slots = ticks * agents as u64;
    let process_cpu = t["process_cpu_s"].as_f64().unwrap_or(0.0);
    let agents_cpu = usage["agents_cpu_s"].as_f64().unwrap_or(0.0);
    // In-process, the world's process holds the agent threads too.
    let world_cpu = match transport {
        Transport::Shm => process_cpu,
        Transport::Inproc => (process_cpu - agents_cpu).max(0.0),
    };
    let pct_of_wall = |s: f64| if wall > 0.0 { 100.0 * s / wall } else { 0.0 };
    let steal = t["cpus_steal_s"].as_f64().map(pct_of_wall);
    let mb = |kb: Option<u64>| kb.map(|k| k as f64 / 1024.0);
    json!({
        "agents": agents,
        "transport": transport.name(),
        "rate_hz": rate,
        "roundtrip_us": pct(&t["latency_us"], ALL),
        "allin_us": pct(&t["allin_us"], &["p50", "p99"]),
        "miss_rate": if slots > 0 { misses as f64 / slots as f64 } else { 0.0 },
        "jitter_us_p99": pct(&t["jitter_us"], &["p99"])["p99"],
        "world_cpu_pct": pct_of_wall(world_cpu),
        "agents_cpu_pct": pct_of_wall(agents_cpu),
        "steal_pct": steal,
        "world_rss_mb": mb(t["process_maxrss_kb"].as_u64()),
        "agent_rss_mb": mb(usage["agent_maxrss_kb"].as_u64()),
        "wake_us": pct(&t["wake_us"], ALL),
        "compute_us": pct(&t["compute_us"], ALL),
        "world_tick_us": pct(&t["world_tick_us"], ALL),
        "physics_us": pct(&t["physics_us"], ALL),
        "ticks": ticks,
        "deadline_misses": misses,
        "wall_s": wall,
        // Simulated over wall time of the tick loop: below 1 the world could
        // not hold the rate (ticks started ever later, see the jitter), and
        // the miss rate alone understates how far it fell behind.
        "realtime_factor": metrics["realtime_factor"].as_f64().unwrap_or(0.0),
    })
}

struct Progress {
    total: usize,
    done: usize,
    tty: bool,
    start: Instant,
}

impl Progress {
    fn step(&mut self, what: &str) {
        let mut err = std::io::stderr();
        if self.tty {
            let width = 30;
            let filled = width * self.done / self.total.max(1);
            let _ = write!(
                err,
                "\r\x1b[2K[{}{}] {}/{} {:>5.0}s  {what}",
                "#".repeat(filled),
                "-".repeat(width - filled),
                self.done,
                self.total,
                self.start.elapsed().as_secs_f64()
            );
        } else {
            let _ = writeln!(err, "bench: [{}/{}] {what}", self.done + 1, self.total);
        }
        let _ = err.flush();
    }

    fn finish(&mut self) {
        if self.tty {
            self.step("done");
            eprintln!();
        } else {
            eprintln!("bench: done in {:.0} s", self.start.elapsed().as_secs_f64());
        }
    }
}

fn run_one(exe: &Path, scene: &Path, dir: &Path, transport: Transport) -> Result<(Value, Value)> {
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
        .context("cannot start `mrsim run`")?;
    if !out.status.success() {
        return Err(anyhow!(
            "`mrsim run {}` failed ({}): {}",
            scene.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let read = |f: &str| -> Result<Value> {
        let p = dir.join(f);
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
    };
    Ok((read("metrics.json")?, read("usage.json")?))
}

fn run_baseline(exe: &Path, dir: &Path, agents: usize, args: &BenchArgs) -> Result<Value> {
    let file = dir.join(format!("baseline-{agents}.json"));
    let run_id = mrsim_transport::Namespace::fresh_run_id();
    let out = Command::new(exe)
        .args(["baseline-world", "--run", &run_id, "--agents"])
        .arg(agents.to_string())
        .arg("--rate")
        .arg(args.rate.to_string())
        .arg("--duration")
        .arg(args.duration.to_string())
        .arg("--deadline")
        .arg(args.deadline.to_string())
        .arg("--out")
        .arg(&file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .context("cannot start `mrsim baseline-world`")?;
    if !out.status.success() {
        return Err(anyhow!(
            "baseline with {agents} agents failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let text =
        std::fs::read_to_string(&file).with_context(|| format!("reading {}", file.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", file.display()))
}

fn f(v: &Value, digits: usize) -> String {
    v.as_f64()
        .map(|x| format!("{x:.digits$}"))
        .unwrap_or_else(|| "-".to_string())
}

/// The table printed at the end: one row per combination.
pub fn table(rows: &[Value]) -> String {
    let header = [
        "agents",
        "transport",
        "rt p50",
        "rt p99",
        "rt p999",
        "rt max",
        "miss %",
        "realtime x",
        "jit p99",
        "allin p99",
        "base p99",
        "base rt p99",
        "world cpu%",
        "agents cpu%",
        "steal%",
        "world MB",
        "agent MB",
    ];
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r["agents"].to_string(),
                r["transport"].as_str().unwrap_or("-").to_string(),
                f(&r["roundtrip_us"]["p50"], 0),
                f(&r["roundtrip_us"]["p99"], 0),
                f(&r["roundtrip_us"]["p999"], 0),
                f(&r["roundtrip_us"]["max"], 0),
                r["miss_rate"]
                    .as_f64()
                    .map(|m| format!("{:.3}", 100.0 * m))
                    .unwrap_or_else(|| "-".into()),
                f(&r["realtime_factor"], 2),
                f(&r["jitter_us_p99"], 0),
                f(&r["allin_us"]["p99"], 0),
                f(&r["baseline_allin_us"]["p99"], 0),
                f(&r["baseline_roundtrip_us"]["p99"], 0),
                f(&r["world_cpu_pct"], 1),
                f(&r["agents_cpu_pct"], 1),
                f(&r["steal_pct"], 1),
                f(&r["world_rss_mb"], 1),
                f(&r["agent_rss_mb"], 1),
            ]
        })
        .collect();
    let widths: Vec<usize> = (0..header.len())
        .map(|i| {
            body.iter()
                .map(|r| r[i].len())
                .chain([header[i].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out =
        String::from("times in µs (rt = round trip, allin = published -> last command in)\n");
    let line = |cells: Vec<String>| {
        cells
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:>w$}"))
            .collect::<Vec<_>>()
            .join("  ")
    };
    out.push_str(&line(header.iter().map(|s| s.to_string()).collect()));
    out.push('\n');
    for r in body {
        out.push_str(&line(r));
        out.push('\n');
    }
    out
}

/// bench.csv: the rows flattened (nested percentiles as `field_p50` ...).
pub fn csv(rows: &[Value]) -> String {
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

/// `mrsim bench`.
pub fn main(args: &BenchArgs) -> Result<i32> {
    if args.agents.is_empty() || args.agents.contains(&0) {
        return Err(crate::launch::invalid(
            "--agents: give positive counts, e.g. 8,32,64",
        ));
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !positive(args.rate) || !positive(args.duration) {
        return Err(crate::launch::invalid(
            "--rate and --duration must be positive",
        ));
    }
    if args.transport.is_empty() {
        return Err(crate::launch::invalid(
            "--transport: give shm, inproc or both",
        ));
    }
    // Check the planner and the scene before anything runs.
    let first = scene_toml(
        args.agents[0],
        args.rate,
        args.duration,
        &args.planner,
        args.deadline,
    );
    let loaded = mrsim_scenario::parse(&first, "bench scene")
        .map_err(|e| crate::launch::invalid(e.to_string()))?;
    for r in loaded.scenario.robots.iter().take(1) {
        mrsim_agents::build_planner(r)
            .map_err(|e| crate::launch::invalid(format!("--planner: {e}")))?;
    }
    let mut sched = args.sched.clone();
    if sched.cpus.is_none() {
        let n = crate::sched::online_cpus().min(2);
        sched.cpus = Some(if n > 1 {
            format!("0-{}", n - 1)
        } else {
            "0".into()
        });
    }
    let applied = crate::sched::apply(&sched).map_err(crate::launch::invalid)?;

    let out = crate::launch::prepare_out(&args.out, "bench")?;
    std::fs::create_dir_all(out.join("runs"))
        .map_err(|e| crate::launch::invalid(format!("output folder {}: {e}", out.display())))?;
    let exe = std::env::current_exe().context("cannot find the mrsim executable")?;

    let mut agents = args.agents.clone();
    agents.sort_unstable();
    agents.dedup();
    let total = agents.len() * (args.transport.len() + usize::from(args.baseline));
    let mut progress = Progress {
        total,
        done: 0,
        tty: std::io::stderr().is_terminal(),
        start: Instant::now(),
    };
    let mut rows = Vec::new();
    for &n in &agents {
        let scene = out.join("runs").join(format!("crossing-{n}.toml"));
        std::fs::write(
            &scene,
            scene_toml(n, args.rate, args.duration, &args.planner, args.deadline),
        )
        .with_context(|| format!("writing {}", scene.display()))?;
        let mut batch = Vec::new();
        for &t in &args.transport {
            progress.step(&format!("{n} agents over {}", t.name()));
            let dir = out.join("runs").join(format!("{}-{n}", t.name()));
            let (metrics, usage) = run_one(&exe, &scene, &dir, t)?;
            let mut row = row_from_run(n, t, args.rate, &metrics, &usage);
            row["cpus"] = json!(applied.cpus);
            row["rt"] = json!(applied.rt);
            row["planner"] = json!(args.planner);
            row["run_dir"] = json!(dir);
            batch.push(row);
            progress.done += 1;
        }
        if args.baseline {
            progress.step(&format!("{n} agents, bare iceoryx2 baseline"));
            let b = run_baseline(&exe, &out, n, args)?;
            for row in &mut batch {
                row["baseline_allin_us"] = pct(&b["allin_us"], &["p50", "p99"]);
                row["baseline_roundtrip_us"] = pct(&b["roundtrip_us"], &["p50", "p99"]);
            }
            progress.done += 1;
        }
        rows.extend(batch);
    }
    progress.finish();

    let doc = json!({"rows": rows});
    std::fs::write(out.join("bench.json"), format!("{doc:#}\n"))
        .with_context(|| format!("writing {}", out.join("bench.json").display()))?;
    std::fs::write(out.join("bench.csv"), csv(&rows))
        .with_context(|| format!("writing {}", out.join("bench.csv").display()))?;
    let series: Vec<mrsim_report::bench_plot::Point> = rows
        .iter()
        .map(|r| mrsim_report::bench_plot::Point {
            series: r["transport"].as_str().unwrap_or("?").to_string(),
            agents: r["agents"].as_u64().unwrap_or(0) as f64,
            roundtrip_p99_ms: r["roundtrip_us"]["p99"].as_f64().unwrap_or(0.0) / 1000.0,
            miss_pct: 100.0 * r["miss_rate"].as_f64().unwrap_or(0.0),
        })
        .collect();
    if let Err(e) = mrsim_report::bench_plot::write(&series, &out.join("bench.svg")) {
        eprintln!("warning: cannot draw bench.svg: {e}");
    }
    print!("{}", table(&rows));
    println!(
        "pinned to CPUs {:?}{}; wrote {}/bench.json, bench.csv, bench.svg",
        applied.cpus,
        if applied.rt { ", SCHED_FIFO" } else { "" },
        out.display()
    );
    Ok(0)
}
