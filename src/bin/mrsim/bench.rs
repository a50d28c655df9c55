//! `mrsim bench`: timing under true concurrency (see
//! `mrsim_runtime::bench` for what is measured); progress on stderr, the
//! table on stdout.

use crate::cli::BenchArgs;
use crate::exit::fail;
use crate::table::{num, text};
use anyhow::Result;
use mrsim_runfolder::bench::{BenchRow, Overhead};
use mrsim_runtime::bench::{BenchPlan, BenchStep};
use std::io::{IsTerminal, Write};
use std::time::Instant;

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
