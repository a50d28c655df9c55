//! `mrsim bench`: timing under true concurrency (see
//! `mrsim_runtime::bench` for what is measured); progress on stderr, the
//! table on stdout.

use crate::cli::{SchedArgs, TransportArg};
use crate::exit::fail;
use crate::table::{num, text};
use anyhow::Result;
use clap::Args;
use mrsim_runfolder::bench::{BenchRow, Overhead};
use mrsim_runtime::bench::{BenchPlan, BenchStep};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
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

/// The table printed at the end: one row per combination.
pub fn table(rows: &[BenchRow]) -> String {
    let header = [
        "stress",
        "rep",
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
                r.stress.to_string(),
                r.repeat.to_string(),
                r.agents.to_string(),
                text(&r.transport),
                num(r.roundtrip_us.p50, 0),
                num(r.roundtrip_us.p99, 0),
                num(r.roundtrip_us.p999, 0),
                num(r.roundtrip_us.max, 0),
                format!("{:.3}", 100.0 * r.miss_rate),
                num(Some(r.realtime_factor), 2),
                num(r.jitter_us_p99, 0),
                num(r.allin_us.p99, 0),
                num(r.baseline_allin_us.and_then(|b| b.p99), 0),
                num(r.baseline_roundtrip_us.and_then(|b| b.p99), 0),
                num(Some(r.world_cpu_pct), 1),
                num(Some(r.agents_cpu_pct), 1),
                num(r.steal_pct, 1),
                num(r.world_rss_mb, 1),
                num(r.agent_rss_mb, 1),
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

/// The overhead over the bare fan-out: the median of the interleaved pairs'
/// ratios with its quartiles and range.
pub fn overhead_table(rows: &[Overhead]) -> String {
    let mut out =
        String::from("\nmrsim over bare iceoryx2, all-in p50 ratio of interleaved pairs:\n");
    out.push_str(&format!(
        "{:>6}  {:>6}  {:>9}  {:>5}  {:>6}  {:>13}  {:>13}\n",
        "stress", "agents", "transport", "pairs", "median", "IQR", "min-max"
    ));
    for o in rows {
        out.push_str(&format!(
            "{:>6}  {:>6}  {:>9}  {:>5}  {:>6.2}  {:>13}  {:>13}\n",
            o.stress,
            o.agents,
            o.transport,
            o.pairs,
            o.median,
            format!("{:.2}-{:.2}", o.q1, o.q3),
            format!("{:.2}-{:.2}", o.min, o.max),
        ));
    }
    out
}

/// Runs `mrsim bench`; returns the exit status.
pub fn main(args: &BenchArgs) -> Result<i32> {
    let plan = BenchPlan {
        agents: args.agents.clone(),
        rate: args.rate,
        duration: args.duration,
        transports: args.transport.iter().map(|&t| t.into()).collect(),
        planner: args.planner.clone(),
        deadline: args.deadline,
        baseline: args.baseline,
        out: args.out.clone(),
        sched: (&args.sched).into(),
        stress: args.stress.clone(),
        repeat: args.repeat,
    };
    let prepared = mrsim_runtime::bench::prepare(&plan).map_err(fail)?;
    let applied = prepared.applied().clone();
    if let Some(why) = &applied.rt_refused {
        eprintln!("warning: {why}");
    }
    let mut progress = Progress {
        total: prepared.steps(),
        done: 0,
        tty: std::io::stderr().is_terminal(),
        start: Instant::now(),
    };
    let outcome = prepared
        .run(&mut |step| match step {
            BenchStep::Starting(what) => progress.step(&what),
            BenchStep::Done => progress.done += 1,
        })
        .map_err(fail)?;
    progress.finish();
    if let Some(e) = &outcome.svg_error {
        eprintln!("warning: cannot draw bench.svg: {e}");
    }
    print!("{}", table(&outcome.rows));
    if !outcome.overhead.is_empty() {
        print!("{}", overhead_table(&outcome.overhead));
    }
    println!(
        "pinned to CPUs {:?}{}; wrote {}/bench.json, bench.csv, bench.svg{}",
        applied.cpus,
        if applied.rt { ", SCHED_FIFO" } else { "" },
        outcome.out.display(),
        if args
            .stress
            .iter()
            .collect::<std::collections::BTreeSet<_>>()
            .len()
            > 1
        {
            ", stress.svg, stress.png"
        } else {
            ""
        }
    );
    Ok(0)
}
