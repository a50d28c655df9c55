//! `mrsim sweep`: runs every combination of values with each seed (see
//! `mrsim_runtime::sweep`) and tabulates the metrics.
//!
//! Outputs: `DIR/sweep.csv`, one row per run (the varied values, the mode,
//! the seed, the run's metrics, its folder relative to DIR; `collided` is 1
//! if the run had any collision, so its mean is the collision rate);
//! `DIR/summary.csv` and a table on stdout with, per combination and mode,
//! the mean of each metric and the half-width of its 95 % confidence
//! interval (Student's t, n - 1 degrees of freedom); `DIR/sweep.svg` and
//! `sweep.png`, every metric against a swept number. In lockstep nothing in
//! sweep.csv depends on the wall clock, so the same command gives the same
//! file byte for byte.
//!
//! `--allowable KEY` (a swept numeric key, e.g. `robot.*.max_speed`) also
//! reports, per combination of the other keys, the mean over seeds of the
//! largest value of KEY at which the run had no collision (0 if none;
//! `allowable.csv`): our reading of Zhu & Loh's "average allowable maximum
//! speed" when KEY is the robot's speed limit.

use crate::exit::fail;
use anyhow::{Result, anyhow};
use clap::{Args, ValueEnum};
use mrsim_runfolder::{ALLOWABLE_FILE, SUMMARY_FILE, SWEEP_FILE};
use mrsim_runtime::sweep::{
    Job, JobDone, JobResult, METRICS, SweepPlan, largest_allowable, mean_ci,
};
use std::io::IsTerminal;
use std::path::PathBuf;

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
    /// The realtime runs' scheduling: --cpus LIST, --rt (as for `run`;
    /// lockstep runs are not pinned).
    #[command(flatten)]
    pub sched: crate::cli::SchedArgs,
    /// Keep every run whose folder under --out already holds it whole
    /// (the same scenario file, overrides and mode, its metrics.json
    /// written): a sweep cut short goes on where it stopped
    #[arg(long, requires = "out")]
    pub resume: bool,
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

use mrsim_runfolder::sweep::{number as fmt_opt, write_table};

/// Runs `mrsim sweep`; returns the exit status.
pub fn main(args: &SweepArgs) -> Result<i32> {
    let sweep = mrsim_runtime::sweep::prepare(&SweepPlan {
        scenario: args.scenario.clone(),
        set: args.set.clone(),
        seeds: args.seeds,
        out: args.out.clone(),
        jobs: args.jobs,
        allowable: args.allowable.clone(),
        mode: args.mode.into(),
        x: args.x.clone(),
        metrics: args.metrics.clone(),
        sched: (&args.sched).into(),
        resume: args.resume,
    })
    .map_err(fail)?;
    let (axes, combos, jobs, dir) = (&sweep.axes, &sweep.combos, &sweep.jobs, &sweep.dir);
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(jobs.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {pos}/{len} runs {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        Some(b)
    } else {
        None
    };
    let at_once = match args.mode {
        SweepModeArg::Lockstep => format!("{} at once", sweep.workers),
        SweepModeArg::Realtime => "one at a time".to_string(),
        SweepModeArg::Both => format!(
            "lockstep {} at once, then realtime one at a time",
            sweep.workers
        ),
    };
    eprintln!(
        "sweep: {} combinations x {} seeds = {} runs, {at_once}, into {}",
        combos.len(),
        args.seeds,
        jobs.len(),
        dir.display()
    );
    let kept_runs = std::sync::atomic::AtomicUsize::new(0);
    let results = sweep
        .run(&|d: JobDone<'_>| {
            if d.kept {
                kept_runs.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            if let Some(e) = d.error {
                let msg = format!("{}: {e}", d.job.folder);
                match &bar {
                    Some(b) => b.println(msg),
                    None => eprintln!("{msg}"),
                }
            }
            let kept = if d.kept { " (kept)" } else { "" };
            match &bar {
                Some(b) => b.set_position(d.done as u64),
                None => eprintln!("sweep: {}/{} {}{kept}", d.done, jobs.len(), d.job.folder),
            }
        })
        .map_err(fail)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let kept_runs = kept_runs.into_inner();
    if kept_runs > 0 {
        eprintln!(
            "sweep: kept {kept_runs} of {} runs that {} already held (--resume)",
            jobs.len(),
            dir.display()
        );
    }
    if mrsim_runtime::sweep::seeds_change_nothing(jobs, &results) {
        eprintln!(
            "warning: {}: every seed gave the same run: seeds change nothing here; \
             add `jitter` or noise",
            args.scenario.display()
        );
    }

    // sweep.csv
    let mut header: Vec<String> = axes.iter().map(|(k, _)| k.clone()).collect();
    header.push("mode".into());
    header.push("seed".into());
    header.extend(METRICS.iter().map(|(n, _)| n.to_string()));
    header.push("run".into());
    let mut rows = Vec::with_capacity(jobs.len());
    let mut failed = 0;
    for (job, r) in jobs.iter().zip(&results) {
        let mut row: Vec<String> = combos[job.combo].clone();
        row.push(job.mode.to_string());
        row.push(job.seed.to_string());
        match r {
            Ok(m) => row.extend(METRICS.iter().map(|(_, f)| fmt_opt(f(m)))),
            _ => {
                failed += 1;
                row.extend(METRICS.iter().map(|_| String::new()));
            }
        }
        row.push(job.folder.clone());
        rows.push(row);
    }
    write_table(dir, SWEEP_FILE, &header, &rows)?;

    // Summary: per combination, mean and 95 % half-width of each metric.
    let mut summary = Vec::new();
    let mut sheader: Vec<String> = axes.iter().map(|(k, _)| k.clone()).collect();
    sheader.push("mode".into());
    sheader.push("runs".into());
    for (n, _) in METRICS {
        sheader.push(format!("{n}_mean"));
        sheader.push(format!("{n}_ci95"));
    }
    // The miss rate joins the table when some run missed a deadline (a
    // timing model, contended cores, a realtime run that fell behind).
    let missed = results.iter().any(|r| {
        r.as_ref()
            .is_ok_and(|m| m.miss_rate.is_some_and(|x| x > 0.0))
    });
    let shown: Vec<&str> = [
        "success_rate",
        "collided",
        "collisions_total",
        "makespan",
        "path_length_ratio",
        "min_clearance",
    ]
    .into_iter()
    .chain(missed.then_some("miss_rate"))
    .collect();
    let mut table: Vec<Vec<String>> = Vec::new();
    let mut theader: Vec<String> = axes.iter().map(|(k, _)| k.clone()).collect();
    theader.push("mode".into());
    theader.push("runs".into());
    // In METRICS order, as the rows are filled.
    theader.extend(
        METRICS
            .iter()
            .filter(|(n, _)| shown.contains(n))
            .map(|(n, _)| n.to_string()),
    );
    table.push(theader);
    let summaries = sweep.summarize(&results);
    for sum in &summaries {
        let combo = &combos[sum.combo];
        let mut srow: Vec<String> = combo.clone();
        srow.push(sum.mode.to_string());
        srow.push(sum.runs.to_string());
        let mut trow: Vec<String> = combo.clone();
        trow.push(sum.mode.to_string());
        trow.push(sum.runs.to_string());
        for ((n, _), &(mean, hw)) in METRICS.iter().zip(&sum.stats) {
            srow.push(fmt_opt(mean));
            srow.push(fmt_opt(hw));
            if shown.contains(n) {
                trow.push(match (mean, hw) {
                    (Some(m), Some(h)) => format!("{m:.3} ± {h:.3}"),
                    (Some(m), None) => format!("{m:.3}"),
                    _ => "-".into(),
                });
            }
        }
        summary.push(srow);
        table.push(trow);
    }
    write_table(dir, SUMMARY_FILE, &sheader, &summary)?;
    let widths: Vec<usize> = (0..table[0].len())
        .map(|c| {
            table
                .iter()
                .map(|r| r[c].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    for (i, r) in table.iter().enumerate() {
        let cells: Vec<String> = r
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect();
        println!("{}", cells.join("  ").trim_end());
        if i == 0 {
            println!(
                "{}",
                widths
                    .iter()
                    .map(|w| "-".repeat(*w))
                    .collect::<Vec<_>>()
                    .join("  ")
            );
        }
    }
    println!(
        "(mean ± half-width of the 95 % interval, Student's t, over seeds 1..={})",
        args.seeds
    );
    let drawn = match sweep.draw(&summaries) {
        Ok(true) => ", sweep.svg, sweep.png",
        Ok(false) => {
            eprintln!("note: no swept key is a number, so there is no sweep.svg to draw");
            ""
        }
        Err(e) => {
            eprintln!("warning: cannot draw sweep.svg: {e}");
            ""
        }
    };
    if let Some(key) = &args.allowable {
        let (header, rows, text) = allowable(key, axes, combos, jobs, &results)?;
        write_table(dir, ALLOWABLE_FILE, &header, &rows)?;
        print!("{text}");
    }
    println!(
        "sweep folder: {} (sweep.csv, summary.csv{drawn}, runs/)",
        dir.display()
    );
    if failed > 0 {
        eprintln!("error: {failed} of {} runs failed (see above)", jobs.len());
        return Ok(crate::exit::EXIT_FAILED);
    }
    Ok(0)
}

/// `--allowable KEY`: per combination of the other keys, the mean over
/// seeds of the largest allowable value of KEY (allowable.csv, and a table).
fn allowable(
    key: &str,
    axes: &[(String, Vec<String>)],
    combos: &[Vec<String>],
    jobs: &[Job],
    results: &[JobResult],
) -> Result<(Vec<String>, Vec<Vec<String>>, String)> {
    let k = axes
        .iter()
        .position(|(a, _)| a == key)
        .ok_or_else(|| anyhow!("--allowable {key}: not a swept key"))?;
    // The mode counts as one more of the other keys.
    let mode_key = "mode".to_string();
    let others: Vec<&String> = axes
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, (a, _))| a)
        .chain([&mode_key])
        .collect();
    // Group runs by (the other values, seed).
    // (the other values, seed, [(value of key, collided)])
    type Group = (Vec<String>, u64, Vec<(f64, bool)>);
    let mut groups: Vec<Group> = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        let Ok(m) = r else { continue };
        let combo = &combos[job.combo];
        let rest: Vec<String> = combo
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(_, v)| v.clone())
            .chain([job.mode.to_string()])
            .collect();
        let v: f64 = combo[k].parse().unwrap_or(f64::NAN);
        let run = (v, m.collisions_total > 0.0);
        match groups
            .iter_mut()
            .find(|(o, s, _)| *o == rest && *s == job.seed)
        {
            Some(g) => g.2.push(run),
            None => groups.push((rest, job.seed, vec![run])),
        }
    }
    let mut header: Vec<String> = others.iter().map(|o| o.to_string()).collect();
    header.push("seeds".into());
    header.push(format!("{key}_allowable_mean"));
    header.push(format!("{key}_allowable_ci95"));
    let mut csv = Vec::new();
    let mut table =
        format!("\nlargest collision-free {key}, mean over seeds (0: every value collided):\n");
    let mut keys: Vec<Vec<String>> = Vec::new();
    for (rest, _, _) in &groups {
        if !keys.contains(rest) {
            keys.push(rest.clone());
        }
    }
    for rest in &keys {
        let xs: Vec<f64> = groups
            .iter()
            .filter(|(o, _, _)| o == rest)
            .map(|(_, _, runs)| largest_allowable(runs))
            .collect();
        let (mean, hw) = mean_ci(&xs);
        let mut row: Vec<String> = rest.clone();
        row.push(xs.len().to_string());
        row.push(fmt_opt(mean));
        row.push(fmt_opt(hw));
        csv.push(row);
        let what: Vec<String> = others
            .iter()
            .zip(rest)
            .map(|(o, v)| format!("{o}={v}"))
            .collect();
        table.push_str(&format!(
            "  {}  {} ± {}  ({} seeds)\n",
            if what.is_empty() {
                "all".to_string()
            } else {
                what.join(" ")
            },
            mean.map_or("-".into(), |m| format!("{m:.3}")),
            hw.map_or("-".into(), |h| format!("{h:.3}")),
            xs.len()
        ));
    }
    Ok((header, csv, table))
}
