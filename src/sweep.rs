//! `mrsim sweep`: a general experiment runner.
//!
//! `mrsim sweep SCENARIO --set KEY=V1,V2,... [--set ...] --seeds N --out DIR`
//! runs every combination of the values (the cartesian product, the first
//! `--set` varying slowest) with each seed 1..=N (`world.seed`). Each run is
//! an ordinary `mrsim run` child process, forced to lockstep, with its own
//! run folder `DIR/runs/<combination>-s<seed>/`; up to `--jobs` (default:
//! the core count) run at once. Every combination is validated before any
//! run starts.
//!
//! Outputs: `DIR/sweep.csv`, one row per run (the varied values, the seed,
//! the run's metrics, its folder relative to DIR; `collided` is 1 if the run
//! had any collision, so its mean is the collision rate); `DIR/summary.csv` and a
//! table on stdout with, per combination, the mean of each metric and the
//! half-width of its 95 % confidence interval (Student's t, n - 1 degrees of
//! freedom). Nothing in sweep.csv depends on the wall clock, so the same
//! command gives the same file byte for byte.
//!
//! Values are split at commas outside brackets, braces and quotes, so
//! `--set 'obstacle.*.motion={ model = "static" },{ model = "random", ... }'`
//! and `--set 'robot.r0.goal=[1, 2],[3, 4]'` give two values each; a comma
//! inside a plain value cannot be written (none of the scenario format's
//! plain values needs one).
//!
//! `--allowable KEY` (a swept numeric key, e.g. `robot.*.max_speed`) also
//! reports, per combination of the other keys, the mean over seeds of the
//! largest value of KEY at which the run had no collision (0 if none;
//! `allowable.csv`): our reading of Zhu & Loh's "average allowable maximum
//! speed" when KEY is the robot's speed limit.

use crate::cli::{ModeArg, ScenarioArgs};
use crate::launch::{Invalid, load};
use anyhow::{Context, Result, anyhow};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

fn invalid(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Invalid(msg.into()))
}

/// What `mrsim sweep` was asked.
#[derive(Debug, Clone, clap::Args)]
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
}

/// Splits `text` at commas outside brackets, braces and quotes.
pub fn split_values(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut quote: Option<char> = None;
    let mut cur = String::new();
    for c in text.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// The varied keys and their values, parsed from the `--set` options.
pub fn parse_axes(set: &[String]) -> Result<Vec<(String, Vec<String>)>> {
    let mut axes: Vec<(String, Vec<String>)> = Vec::new();
    for s in set {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| invalid(format!("--set {s}: expected KEY=V1,V2,...")))?;
        let k = k.trim().to_string();
        if k == "world.seed" {
            return Err(invalid(format!(
                "--set {s}: the seed is varied by --seeds (runs use seeds 1..=N)"
            )));
        }
        if axes.iter().any(|(a, _)| *a == k) {
            return Err(invalid(format!("--set {s}: `{k}` is set twice")));
        }
        let values = split_values(v);
        if let Some(i) = values.iter().position(|v| v.is_empty()) {
            return Err(invalid(format!(
                "--set {s}: value {} of `{k}` is empty",
                i + 1
            )));
        }
        axes.push((k, values));
    }
    Ok(axes)
}

/// Every combination of the axes' values, first axis slowest.
pub fn combinations(axes: &[(String, Vec<String>)]) -> Vec<Vec<String>> {
    let mut out = vec![Vec::new()];
    for (_, values) in axes {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                values.iter().map(move |v| {
                    let mut c = prefix.clone();
                    c.push(v.clone());
                    c
                })
            })
            .collect();
    }
    out
}

/// A folder-name-safe label of a combination: its index (which makes it
/// unique), then `key=value` pairs (last part of each key, values cleaned
/// and cut to 24 characters).
fn label(index: usize, axes: &[(String, Vec<String>)], combo: &[String]) -> String {
    let clean = |s: &str| {
        let mut out = String::new();
        for c in s.chars() {
            let c = if c.is_ascii_alphanumeric() || matches!(c, '.' | '-') {
                c
            } else {
                '_'
            };
            if !(c == '_' && (out.is_empty() || out.ends_with('_'))) {
                out.push(c);
            }
        }
        out.truncate(24);
        out.trim_end_matches('_').to_string()
    };
    let mut s = format!("{index:03}");
    for ((k, _), v) in axes.iter().zip(combo) {
        let short = k.rsplit('.').next().unwrap_or(k);
        s.push('-');
        s.push_str(&clean(short));
        s.push('=');
        s.push_str(&clean(v));
    }
    s
}

/// One run's metrics, as sweep.csv reports them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunMetrics {
    /// Fraction of robots that reached their goals.
    pub success_rate: f64,
    /// Contacts started, all robots.
    pub collisions_total: f64,
    /// Max time_to_goal if every robot arrived, else the run's duration.
    pub makespan: f64,
    /// Mean over robots of path_length / straight start-goal distance.
    pub path_ratio: Option<f64>,
    /// Min over robots of min_clearance.
    pub min_clearance: Option<f64>,
    /// Mean time_to_goal of the robots that arrived.
    pub time_to_goal: Option<f64>,
    /// Agents lost during the run.
    pub agents_lost: f64,
    /// Ticks run.
    pub ticks: f64,
}

/// How a metric column is read from a run's metrics.
type Column = (&'static str, fn(&RunMetrics) -> Option<f64>);

/// The metric columns of sweep.csv, in order, with how to get each.
const METRICS: [Column; 9] = [
    ("success_rate", |m| Some(m.success_rate)),
    ("collisions_total", |m| Some(m.collisions_total)),
    // 1 if the run had any collision: its mean is the collision rate.
    ("collided", |m| {
        Some(f64::from(u8::from(m.collisions_total > 0.0)))
    }),
    ("makespan", |m| Some(m.makespan)),
    ("path_length_ratio", |m| m.path_ratio),
    ("min_clearance", |m| m.min_clearance),
    ("time_to_goal", |m| m.time_to_goal),
    ("agents_lost", |m| Some(m.agents_lost)),
    ("ticks", |m| Some(m.ticks)),
];

/// Reads a run folder's metrics.json and scenario.json (with the report
/// crate's reader of metrics.json and the scenario's own type).
pub fn read_run(dir: &Path) -> Result<RunMetrics> {
    let read = |f: &str| -> Result<(PathBuf, String)> {
        let p = dir.join(f);
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        Ok((p, text))
    };
    let (p, text) = read("metrics.json")?;
    let m: mrsim_report::Metrics =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    let (p, text) = read("scenario.json")?;
    let sc: mrsim_scenario::Scenario =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
    let ticks = m.ticks as f64;
    let mut arrived = Vec::new();
    let mut ratios = Vec::new();
    let mut clearance: Option<f64> = None;
    let mut all_arrived = true;
    let none = Default::default();
    for r in &sc.robots {
        let rm = m.robots.get(&r.name).unwrap_or(&none);
        match rm.time_to_goal {
            Some(t) if rm.reached_goal => arrived.push(t),
            _ => all_arrived = false,
        }
        let straight = (r.goal[0] - r.start[0]).hypot(r.goal[1] - r.start[1]);
        if straight > 0.0 {
            ratios.push(rm.path_length / straight);
        }
        if let Some(c) = rm.min_clearance {
            clearance = Some(clearance.map_or(c, |m: f64| m.min(c)));
        }
    }
    let mean = |xs: &[f64]| (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64);
    let makespan = if all_arrived && !arrived.is_empty() {
        arrived.iter().copied().fold(f64::MIN, f64::max)
    } else {
        ticks * sc.world.dt
    };
    Ok(RunMetrics {
        success_rate: m.success_rate,
        collisions_total: m.collisions_total as f64,
        makespan,
        path_ratio: mean(&ratios),
        min_clearance: clearance,
        time_to_goal: mean(&arrived),
        agents_lost: m.agents_lost as f64,
        ticks,
    })
}

/// The 0.975 quantile of Student's t with `df` degrees of freedom (exact
/// to 3 decimals from a table up to 30, Cornish-Fisher expansion beyond).
pub fn t975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::NAN,
        1..=30 => TABLE[df - 1],
        _ => {
            let z: f64 = 1.959_964;
            let n = df as f64;
            z + (z.powi(3) + z) / (4.0 * n)
                + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * n * n)
        }
    }
}

/// Mean and the half-width of its 95 % interval (None with fewer than two
/// values for the interval, or none at all for the mean).
pub fn mean_ci(xs: &[f64]) -> (Option<f64>, Option<f64>) {
    if xs.is_empty() {
        return (None, None);
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    if xs.len() < 2 {
        return (Some(mean), None);
    }
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (Some(mean), Some(t975(xs.len() - 1) * (var / n).sqrt()))
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

struct Job {
    combo: usize,
    seed: u64,
    folder: String,
}

/// `mrsim sweep`.
pub fn sweep(args: &SweepArgs) -> Result<i32> {
    if args.seeds == 0 {
        return Err(invalid("--seeds must be at least 1"));
    }
    if args.jobs == Some(0) {
        return Err(invalid("--jobs must be at least 1"));
    }
    let axes = parse_axes(&args.set)?;
    if let Some(key) = &args.allowable {
        match axes.iter().find(|(k, _)| k == key) {
            None => {
                return Err(invalid(format!(
                    "--allowable {key}: not a swept key (give it --set {key}=V1,V2,...)"
                )));
            }
            Some((_, vs)) if vs.iter().any(|v| v.parse::<f64>().is_err()) => {
                return Err(invalid(format!(
                    "--allowable {key}: its values must be numbers"
                )));
            }
            _ => {}
        }
    }
    let combos = combinations(&axes);
    let sets = |combo: &[String], seed: u64| -> Vec<String> {
        let mut s: Vec<String> = axes
            .iter()
            .zip(combo)
            .map(|((k, _), v)| format!("{k}={v}"))
            .collect();
        s.push(format!("world.seed={seed}"));
        s
    };
    // Validate every combination before anything runs.
    let mut name = String::new();
    for combo in &combos {
        let loaded = load(&ScenarioArgs {
            scenario: Some(args.scenario.clone()),
            mode: Some(ModeArg::Lockstep),
            set: sets(combo, 1),
            out: None,
        })
        .map_err(|e| {
            let what: Vec<String> = axes
                .iter()
                .zip(combo)
                .map(|((k, _), v)| format!("{k}={v}"))
                .collect();
            invalid(format!("combination {}: {e}", what.join(" ")))
        })?;
        name = loaded.scenario.name.clone();
    }
    let dir = crate::launch::prepare_out(&args.out, &format!("sweep-{name}"))?;
    std::fs::create_dir_all(dir.join("runs")).map_err(|e| {
        invalid(format!(
            "output folder {}: cannot create runs/ in it: {e}",
            dir.display()
        ))
    })?;

    let jobs: Vec<Job> = combos
        .iter()
        .enumerate()
        .flat_map(|(i, c)| {
            let l = label(i, &axes, c);
            (1..=args.seeds).map(move |seed| Job {
                combo: i,
                seed,
                folder: format!("runs/{l}-s{seed}"),
            })
        })
        .collect();
    let workers = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(jobs.len())
        .max(1);
    let exe = std::env::current_exe().context("cannot find the mrsim executable")?;

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
    eprintln!(
        "sweep: {} combinations x {} seeds = {} runs, {} at once, into {}",
        combos.len(),
        args.seeds,
        jobs.len(),
        workers,
        dir.display()
    );

    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<RunMetrics, String>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(job) = jobs.get(i) else { break };
                    let out = dir.join(&job.folder);
                    let mut cmd = Command::new(&exe);
                    cmd.arg("run")
                        .arg(&args.scenario)
                        .args(["--mode", "lockstep", "--quiet", "--out"])
                        .arg(&out);
                    for s in sets(&combos[job.combo], job.seed) {
                        cmd.arg("--set").arg(s);
                    }
                    let r = cmd
                        .stdin(Stdio::null())
                        .output()
                        .map_err(|e| format!("cannot start mrsim run: {e}"))
                        .and_then(|o| {
                            if o.status.success() {
                                read_run(&out).map_err(|e| format!("{e:#}"))
                            } else {
                                let log = out.join("sweep-run.log");
                                let _ = std::fs::write(&log, [o.stdout, o.stderr].concat());
                                Err(format!(
                                    "mrsim run failed ({}); its output is in {}",
                                    o.status,
                                    log.display()
                                ))
                            }
                        });
                    if let Err(e) = &r {
                        let msg = format!("{}: {e}", job.folder);
                        match &bar {
                            Some(b) => b.println(msg),
                            None => eprintln!("{msg}"),
                        }
                    }
                    if let Ok(mut res) = results.lock() {
                        res[i] = Some(r);
                    }
                    let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                    match &bar {
                        Some(b) => b.set_position(n as u64),
                        None => eprintln!("sweep: {n}/{} {}", jobs.len(), job.folder),
                    }
                }
            });
        }
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let results = results
        .into_inner()
        .map_err(|_| anyhow!("a sweep worker panicked"))?;

    // sweep.csv
    let mut csv = String::new();
    let mut header: Vec<String> = axes.iter().map(|(k, _)| csv_field(k)).collect();
    header.push("seed".into());
    header.extend(METRICS.iter().map(|(n, _)| n.to_string()));
    header.push("run".into());
    csv.push_str(&header.join(","));
    csv.push('\n');
    let mut failed = 0;
    for (job, r) in jobs.iter().zip(&results) {
        let mut row: Vec<String> = combos[job.combo].iter().map(|v| csv_field(v)).collect();
        row.push(job.seed.to_string());
        match r {
            Some(Ok(m)) => row.extend(METRICS.iter().map(|(_, f)| fmt_opt(f(m)))),
            _ => {
                failed += 1;
                row.extend(METRICS.iter().map(|_| String::new()));
            }
        }
        row.push(csv_field(&job.folder));
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    std::fs::write(dir.join("sweep.csv"), &csv)
        .with_context(|| format!("writing {}", dir.join("sweep.csv").display()))?;

    // Summary: per combination, mean and 95 % half-width of each metric.
    let mut summary = String::new();
    let mut sheader: Vec<String> = axes.iter().map(|(k, _)| csv_field(k)).collect();
    sheader.push("runs".into());
    for (n, _) in METRICS {
        sheader.push(format!("{n}_mean"));
        sheader.push(format!("{n}_ci95"));
    }
    summary.push_str(&sheader.join(","));
    summary.push('\n');
    let shown = [
        "success_rate",
        "collided",
        "collisions_total",
        "makespan",
        "path_length_ratio",
        "min_clearance",
    ];
    let mut table: Vec<Vec<String>> = Vec::new();
    let mut theader: Vec<String> = axes.iter().map(|(k, _)| k.clone()).collect();
    theader.push("runs".into());
    // In METRICS order, as the rows are filled.
    theader.extend(
        METRICS
            .iter()
            .filter(|(n, _)| shown.contains(n))
            .map(|(n, _)| n.to_string()),
    );
    table.push(theader);
    for (ci, combo) in combos.iter().enumerate() {
        let runs: Vec<&RunMetrics> = jobs
            .iter()
            .zip(&results)
            .filter(|(j, _)| j.combo == ci)
            .filter_map(|(_, r)| match r {
                Some(Ok(m)) => Some(m),
                _ => None,
            })
            .collect();
        let mut srow: Vec<String> = combo.iter().map(|v| csv_field(v)).collect();
        srow.push(runs.len().to_string());
        let mut trow: Vec<String> = combo.clone();
        trow.push(runs.len().to_string());
        for (n, f) in METRICS {
            let xs: Vec<f64> = runs.iter().filter_map(|m| f(m)).collect();
            let (mean, hw) = mean_ci(&xs);
            srow.push(fmt_opt(mean));
            srow.push(fmt_opt(hw));
            if shown.contains(&n) {
                trow.push(match (mean, hw) {
                    (Some(m), Some(h)) => format!("{m:.3} ± {h:.3}"),
                    (Some(m), None) => format!("{m:.3}"),
                    _ => "-".into(),
                });
            }
        }
        summary.push_str(&srow.join(","));
        summary.push('\n');
        table.push(trow);
    }
    std::fs::write(dir.join("summary.csv"), &summary)
        .with_context(|| format!("writing {}", dir.join("summary.csv").display()))?;
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
    if let Some(key) = &args.allowable {
        let text = allowable(key, &axes, &combos, &jobs, &results)?;
        std::fs::write(dir.join("allowable.csv"), &text.0)
            .with_context(|| format!("writing {}", dir.join("allowable.csv").display()))?;
        print!("{}", text.1);
    }
    println!(
        "sweep folder: {} (sweep.csv, summary.csv, runs/)",
        dir.display()
    );
    if failed > 0 {
        eprintln!("error: {failed} of {} runs failed (see above)", jobs.len());
        return Ok(crate::cli::EXIT_FAILED);
    }
    Ok(0)
}

/// The largest value of `key` that is allowable for one seed: the largest
/// tested value whose run had no collision (0 if every value collided).
pub fn largest_allowable(runs: &[(f64, bool)]) -> f64 {
    runs.iter()
        .filter(|(_, collided)| !collided)
        .map(|(v, _)| *v)
        .fold(0.0, f64::max)
}

/// `--allowable KEY`: per combination of the other keys, the mean over
/// seeds of the largest allowable value of KEY (allowable.csv, and a table).
fn allowable(
    key: &str,
    axes: &[(String, Vec<String>)],
    combos: &[Vec<String>],
    jobs: &[Job],
    results: &[Option<Result<RunMetrics, String>>],
) -> Result<(String, String)> {
    let k = axes
        .iter()
        .position(|(a, _)| a == key)
        .ok_or_else(|| anyhow!("--allowable {key}: not a swept key"))?;
    let others: Vec<&String> = axes
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, (a, _))| a)
        .collect();
    // Group runs by (the other values, seed).
    // (the other values, seed, [(value of key, collided)])
    type Group = (Vec<String>, u64, Vec<(f64, bool)>);
    let mut groups: Vec<Group> = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        let Some(Ok(m)) = r else { continue };
        let combo = &combos[job.combo];
        let rest: Vec<String> = combo
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(_, v)| v.clone())
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
    let mut csv = String::new();
    let mut header: Vec<String> = others.iter().map(|o| csv_field(o)).collect();
    header.push("seeds".into());
    header.push(format!("{key}_allowable_mean"));
    header.push(format!("{key}_allowable_ci95"));
    csv.push_str(&header.join(","));
    csv.push('\n');
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
        let mut row: Vec<String> = rest.iter().map(|v| csv_field(v)).collect();
        row.push(xs.len().to_string());
        row.push(fmt_opt(mean));
        row.push(fmt_opt(hw));
        csv.push_str(&row.join(","));
        csv.push('\n');
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
    Ok((csv, table))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_short_safe_and_numbered() {
        let axes = vec![("obstacle.*.motion".to_string(), Vec::new())];
        let l = label(
            7,
            &axes,
            &[r#"{ model = "constant-velocity", velocity = [0.0, -0.5] }"#.into()],
        );
        assert_eq!(l, "007-motion=model_constant-velocity");
    }

    #[test]
    fn the_allowable_value_is_the_largest_without_a_collision() {
        assert_eq!(
            largest_allowable(&[(2.0, false), (1.0, false), (3.0, true)]),
            2.0
        );
        // Safe at a higher value though not at a lower one: the higher counts.
        assert_eq!(
            largest_allowable(&[(1.0, false), (2.0, true), (3.0, false)]),
            3.0
        );
        assert_eq!(largest_allowable(&[(1.0, true), (2.0, true)]), 0.0);
    }

    #[test]
    fn values_split_at_top_level_commas_only() {
        assert_eq!(split_values("1, 2,3"), ["1", "2", "3"]);
        assert_eq!(split_values("[1, 2],[3, 4]"), ["[1, 2]", "[3, 4]"]);
        assert_eq!(
            split_values(r#"{ model = "a", v = [1, 2] },"x,y""#),
            [r#"{ model = "a", v = [1, 2] }"#, r#""x,y""#]
        );
    }

    #[test]
    fn combinations_are_the_cartesian_product_first_axis_slowest() {
        let axes = vec![
            ("a".to_string(), vec!["1".to_string(), "2".to_string()]),
            (
                "b".to_string(),
                vec!["x".to_string(), "y".to_string(), "z".to_string()],
            ),
        ];
        let c = combinations(&axes);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], ["1", "x"]);
        assert_eq!(c[1], ["1", "y"]);
        assert_eq!(c[3], ["2", "x"]);
        assert_eq!(combinations(&[]), vec![Vec::<String>::new()]);
    }

    #[test]
    fn the_seed_twice_set_keys_and_empty_values_are_refused() {
        assert!(parse_axes(&["world.seed=1,2".into()]).is_err());
        assert!(parse_axes(&["a=1".into(), "a=2".into()]).is_err());
        assert!(parse_axes(&["a=1,,2".into()]).is_err());
        assert!(parse_axes(&["a".into()]).is_err());
    }

    #[test]
    fn t_quantiles_match_the_table_and_approach_the_normal() {
        assert_eq!(t975(1), 12.706);
        assert_eq!(t975(9), 2.262);
        // Tables: t(0.975, 40) = 2.021, t(0.975, 120) = 1.980.
        assert!((t975(40) - 2.021).abs() < 2e-3, "{}", t975(40));
        assert!((t975(120) - 1.980).abs() < 1e-3, "{}", t975(120));
    }

    #[test]
    fn the_interval_of_a_known_sample() {
        // 1..=5: mean 3, s = sqrt(2.5), half-width t(4) s / sqrt(5).
        let (m, h) = mean_ci(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(m, Some(3.0));
        let want = 2.776 * (2.5f64 / 5.0).sqrt();
        assert!((h.unwrap_or(0.0) - want).abs() < 1e-12);
        assert_eq!(mean_ci(&[2.0]), (Some(2.0), None));
        assert_eq!(mean_ci(&[]), (None, None));
    }
}
