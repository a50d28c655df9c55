//! `mrsim sweep`: a general experiment runner; the runs and their
//! metrics (the tables are the caller's).
//!
//! A sweep runs every combination of the values of some keys (the
//! cartesian product, the first key varying slowest) with each seed 1..=N
//! (`world.seed`). Each run is an ordinary `mrsim run` child process with
//! its own run folder `DIR/runs/<combination>-s<seed>/`. In lockstep (the
//! modelled curve: time costs nothing but what the scenario says) up to
//! `jobs` run at once; in realtime (the measured curve) runs go one at a
//! time, in folders ending `-realtime`, since runs side by side would take
//! each other's CPU and the measurement would be of the sweep, not of the
//! setting. [`SweepMode::Both`] runs every job in lockstep first, then in
//! realtime. Every combination is validated (in each mode) before any run
//! starts.
//!
//! [`Sweep::summarize`] gives each combination's means with their 95 %
//! intervals; [`Sweep::figure`] draws them against a swept number
//! (`sweep.svg`, `sweep.png`).
//!
//! Values are split at commas outside brackets, braces and quotes, so
//! `--set 'obstacle.*.motion={ model = "static" },{ model = "random", ... }'`
//! and `--set 'robot.r0.goal=[1, 2],[3, 4]'` give two values each; a comma
//! inside a plain value cannot be written (none of the scenario format's
//! plain values needs one).

use crate::error::{Invalid, Refusal};
use crate::validate::{ScenarioSource, Validated};
use mrsim_report::sweep_plot::{Figure, Panel, Point, Series, write_figure};
use mrsim_scenario::Mode;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What to sweep.
#[derive(Debug, Clone)]
pub struct SweepPlan {
    /// The scenario file.
    pub scenario: PathBuf,
    /// `KEY=V1,V2,...` per swept key.
    pub set: Vec<String>,
    /// Seeds 1..=N of each combination.
    pub seeds: u64,
    /// Output folder (`None`: a fresh folder under runs/).
    pub out: Option<PathBuf>,
    /// Runs at once (`None`: the number of cores).
    pub jobs: Option<usize>,
    /// A swept numeric key whose largest collision-free value is reported.
    pub allowable: Option<String>,
    /// How the runs keep time.
    pub mode: SweepMode,
    /// The swept key on the figure's x axis (`None`: the first swept key
    /// whose values are all numbers).
    pub x: Option<String>,
}

/// How a sweep's runs keep time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SweepMode {
    /// Every run in lockstep, several at once: the modelled curve.
    #[default]
    Lockstep,
    /// Every run in realtime, one at a time: the measured curve.
    Realtime,
    /// Every run in lockstep, then again in realtime: both curves, on one
    /// figure.
    Both,
}

impl SweepMode {
    /// The modes run, in order.
    pub fn modes(self) -> &'static [Mode] {
        match self {
            SweepMode::Lockstep => &[Mode::Lockstep],
            SweepMode::Realtime => &[Mode::Realtime],
            SweepMode::Both => &[Mode::Lockstep, Mode::Realtime],
        }
    }
}

/// Why a sweep failed.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// Refused before any run: the keys, values, seeds, a combination's
    /// scenario, the output folder.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The running executable is not known.
    #[error("cannot find the mrsim executable")]
    Exe(#[source] std::io::Error),
    /// A sweep worker thread panicked.
    #[error("a sweep worker panicked")]
    Panicked,
}

impl Refusal for SweepError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            SweepError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// Splits `text` at commas outside brackets, braces and quotes.
fn split_values(text: &str) -> Vec<String> {
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
fn parse_axes(set: &[String]) -> Result<Vec<(String, Vec<String>)>, Invalid> {
    let mut axes: Vec<(String, Vec<String>)> = Vec::new();
    for s in set {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| Invalid(format!("--set {s}: expected KEY=V1,V2,...")))?;
        let k = k.trim().to_string();
        if k == "world.seed" {
            return Err(Invalid(format!(
                "--set {s}: the seed is varied by --seeds (runs use seeds 1..=N)"
            )));
        }
        if axes.iter().any(|(a, _)| *a == k) {
            return Err(Invalid(format!("--set {s}: `{k}` is set twice")));
        }
        let values = split_values(v);
        if let Some(i) = values.iter().position(|v| v.is_empty()) {
            return Err(Invalid(format!(
                "--set {s}: value {} of `{k}` is empty",
                i + 1
            )));
        }
        axes.push((k, values));
    }
    Ok(axes)
}

/// Every combination of the axes' values, first axis slowest.
fn combinations(axes: &[(String, Vec<String>)]) -> Vec<Vec<String>> {
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
    /// The run's `spl` (mean over robots).
    pub spl: Option<f64>,
    /// Sum of the robots' times to goal, if every robot arrived.
    pub flowtime: Option<f64>,
    /// Contacts per robot-kilometre.
    pub collisions_per_robot_km: Option<f64>,
    /// Deadlocks detected.
    pub deadlocks: f64,
    /// Means over robots of the interaction metrics, in the order of
    /// [`ROBOT_MEANS`].
    pub robot_means: [Option<f64>; ROBOT_MEANS.len()],
}

/// How a per-robot metric is read from a robot's entry of metrics.json.
pub type RobotColumn = (
    &'static str,
    fn(&mrsim_runfolder::RobotMetrics) -> Option<f64>,
);

/// The per-robot metrics sweep.csv reports as a mean over the run's robots.
pub const ROBOT_MEANS: [RobotColumn; 9] = [
    ("time_not_moving", |r| r.time_not_moving),
    ("ttc_min", |r| r.ttc_min.flatten()),
    ("time_intimate", |r| r.time_intimate),
    ("time_personal", |r| r.time_personal),
    ("time_social", |r| r.time_social),
    ("jerk_mean", |r| r.jerk_mean),
    ("path_irregularity", |r| r.path_irregularity),
    ("heading_change", |r| r.heading_change),
    ("stuck_time", |r| r.stuck_time),
];

/// How a metric column is read from a run's metrics.
pub type Column = (&'static str, fn(&RunMetrics) -> Option<f64>);

/// The metric columns of sweep.csv, in order, with how to get each.
pub const METRICS: [Column; 22] = [
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
    ("spl", |m| m.spl),
    ("flowtime", |m| m.flowtime),
    ("collisions_per_robot_km", |m| m.collisions_per_robot_km),
    ("deadlocks", |m| Some(m.deadlocks)),
    ("time_not_moving", |m| m.robot_means[0]),
    ("ttc_min", |m| m.robot_means[1]),
    ("time_intimate", |m| m.robot_means[2]),
    ("time_personal", |m| m.robot_means[3]),
    ("time_social", |m| m.robot_means[4]),
    ("jerk_mean", |m| m.robot_means[5]),
    ("path_irregularity", |m| m.robot_means[6]),
    ("heading_change", |m| m.robot_means[7]),
    ("stuck_time", |m| m.robot_means[8]),
];

/// A run folder's file that could not be read, in words.
fn file_error(e: mrsim_runfolder::FileError) -> String {
    match e {
        mrsim_runfolder::FileError::Io { path, source } => {
            format!("reading {}: {source}", path.display())
        }
        mrsim_runfolder::FileError::Json { path, source } => {
            format!("parsing {}: {source}", path.display())
        }
    }
}

/// Reads a run folder's metrics.json and scenario.json (with the run
/// folder's schema and the scenario's own type).
fn read_run(dir: &Path) -> Result<RunMetrics, String> {
    let m = mrsim_runfolder::read_metrics(dir).map_err(file_error)?;
    let sc: mrsim_scenario::Scenario =
        mrsim_runfolder::read_json(dir, mrsim_runfolder::SCENARIO_FILE).map_err(file_error)?;
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
    let robot_means = ROBOT_MEANS.map(|(_, get)| {
        let xs: Vec<f64> = m.robots.values().filter_map(get).collect();
        mean(&xs)
    });
    Ok(RunMetrics {
        spl: m.spl,
        flowtime: m.flowtime.flatten(),
        collisions_per_robot_km: m.collisions_per_robot_km.flatten(),
        deadlocks: m.deadlocks.len() as f64,
        robot_means,
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

/// True when a sweep ran more than one seed and every combination's seeds
/// gave the same metrics: the scene has nothing random (no `jitter`, no
/// noise, no random obstacles), so its intervals say nothing.
pub fn seeds_change_nothing(jobs: &[Job], results: &[JobResult]) -> bool {
    let mut first: std::collections::BTreeMap<(usize, bool), &RunMetrics> = Default::default();
    let mut repeated = false;
    for (job, r) in jobs.iter().zip(results) {
        let Ok(m) = r else { continue };
        let key = (job.combo, job.mode == Mode::Realtime);
        match first.get(&key) {
            None => {
                first.insert(key, m);
            }
            Some(f) if *f == m => repeated = true,
            Some(_) => return false,
        }
    }
    repeated
}

/// The 0.975 quantile of Student's t with `df` degrees of freedom (exact
/// to 3 decimals from a table up to 30, Cornish-Fisher expansion beyond).
fn t975(df: usize) -> f64 {
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

/// The largest value of `key` that is allowable for one seed: the largest
/// tested value whose run had no collision (0 if every value collided).
pub fn largest_allowable(runs: &[(f64, bool)]) -> f64 {
    runs.iter()
        .filter(|(_, collided)| !collided)
        .map(|(v, _)| *v)
        .fold(0.0, f64::max)
}

/// One run of a sweep.
#[derive(Debug, Clone)]
pub struct Job {
    /// Its combination (index into [`Sweep::combos`]).
    pub combo: usize,
    /// Its seed.
    pub seed: u64,
    /// How it keeps time.
    pub mode: Mode,
    /// Its folder, relative to the sweep's.
    pub folder: String,
}

/// A checked sweep: every combination valid, the folder made.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// What was asked.
    pub plan: SweepPlan,
    /// The swept keys and their values.
    pub axes: Vec<(String, Vec<String>)>,
    /// Every combination of the values, first key slowest.
    pub combos: Vec<Vec<String>>,
    /// Every run, combination by combination, seed by seed.
    pub jobs: Vec<Job>,
    /// Lockstep runs at once (realtime runs go one at a time).
    pub workers: usize,
    /// The sweep's folder.
    pub dir: PathBuf,
    /// The scenario's name.
    pub name: String,
    /// The scenario's length unit (`m`, `cm`, `mm`), for the figure's axes.
    pub length_unit: &'static str,
}

/// One run's result: its metrics, or why there are none.
pub type JobResult = Result<RunMetrics, String>;

/// A run of a sweep has ended.
#[derive(Debug)]
pub struct JobDone<'a> {
    /// Runs done so far, this one included.
    pub done: usize,
    /// The run.
    pub job: &'a Job,
    /// Why it failed, if it did.
    pub error: Option<&'a str>,
}

/// Checks the plan and every combination, and makes the sweep's folder.
pub fn prepare(plan: &SweepPlan) -> Result<Sweep, SweepError> {
    if plan.seeds == 0 {
        return Err(Invalid::new("--seeds must be at least 1").into());
    }
    if plan.jobs == Some(0) {
        return Err(Invalid::new("--jobs must be at least 1").into());
    }
    let axes = parse_axes(&plan.set)?;
    if let Some(key) = &plan.allowable {
        match axes.iter().find(|(k, _)| k == key) {
            None => {
                return Err(Invalid(format!(
                    "--allowable {key}: not a swept key (give it --set {key}=V1,V2,...)"
                ))
                .into());
            }
            Some((_, vs)) if vs.iter().any(|v| v.parse::<f64>().is_err()) => {
                return Err(
                    Invalid(format!("--allowable {key}: its values must be numbers")).into(),
                );
            }
            _ => {}
        }
    }
    if plan.mode != SweepMode::Lockstep && plan.jobs.is_some_and(|j| j > 1) {
        return Err(Invalid::new(
            "--jobs: realtime runs go one at a time (runs side by side would take each \
             other's CPU); --jobs applies to lockstep runs only, so drop it or use --mode lockstep",
        )
        .into());
    }
    if let Some(x) = &plan.x {
        numeric_axis(&axes, x)?;
    }
    let combos = combinations(&axes);
    // Validate every combination before anything runs.
    let mut name = String::new();
    let mut length_unit = "m";
    for &mode in plan.mode.modes() {
        for combo in &combos {
            let v = Validated::new(ScenarioSource {
                path: Some(plan.scenario.clone()),
                mode: Some(mode),
                set: sets(&axes, combo, 1),
            })
            .map_err(|e| {
                let what: Vec<String> = axes
                    .iter()
                    .zip(combo)
                    .map(|((k, _), v)| format!("{k}={v}"))
                    .collect();
                Invalid(format!("combination {} ({mode}): {e}", what.join(" ")))
            })?;
            if let Some(r) = [v.external_robots(), v.ros2_robots()].concat().first() {
                return Err(Invalid(format!(
                    "{}: robot `{r}` has planner = \"external\" or \"ros2\": a sweep starts its runs \
                     unattended, with no program of yours to join them",
                    v.origin()
                ))
                .into());
            }
            name = v.scenario().name.clone();
            length_unit = match v.scenario().length_unit {
                mrsim_scenario::LengthUnit::M => "m",
                mrsim_scenario::LengthUnit::Cm => "cm",
                mrsim_scenario::LengthUnit::Mm => "mm",
            };
        }
    }
    let dir = crate::out::prepare(plan.out.as_deref(), &format!("sweep-{name}"))?;
    std::fs::create_dir_all(dir.join("runs")).map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot create runs/ in it: {e}",
            dir.display()
        ))
    })?;
    let mut jobs: Vec<Job> = Vec::new();
    for &mode in plan.mode.modes() {
        for (i, c) in combos.iter().enumerate() {
            let l = label(i, &axes, c);
            let suffix = match mode {
                Mode::Lockstep => "",
                Mode::Realtime => "-realtime",
            };
            jobs.extend((1..=plan.seeds).map(|seed| Job {
                combo: i,
                seed,
                mode,
                folder: format!("runs/{l}-s{seed}{suffix}"),
            }));
        }
    }
    let workers = plan
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(jobs.len())
        .max(1);
    Ok(Sweep {
        plan: plan.clone(),
        axes,
        combos,
        jobs,
        workers,
        dir,
        name,
        length_unit,
    })
}

/// The index of swept key `key`, if its values are all numbers.
fn numeric_axis(axes: &[(String, Vec<String>)], key: &str) -> Result<usize, Invalid> {
    match axes.iter().position(|(k, _)| k == key) {
        None => Err(Invalid(format!(
            "--x {key}: not a swept key (give it --set {key}=V1,V2,...)"
        ))),
        Some(i) if axes[i].1.iter().any(|v| v.parse::<f64>().is_err()) => Err(Invalid(format!(
            "--x {key}: its values must be numbers to be an axis"
        ))),
        Some(i) => Ok(i),
    }
}

/// The `--set` overrides of one run: the combination's values and the seed.
fn sets(axes: &[(String, Vec<String>)], combo: &[String], seed: u64) -> Vec<String> {
    let mut s: Vec<String> = axes
        .iter()
        .zip(combo)
        .map(|((k, _), v)| format!("{k}={v}"))
        .collect();
    s.push(format!("world.seed={seed}"));
    s
}

impl Sweep {
    /// Runs every job, each an `mrsim run` child process: the lockstep
    /// ones [`Sweep::workers`] at once, then the realtime ones one at a
    /// time; `on_done` hears of each as it ends (from the worker threads).
    /// A failed run's output is kept in its folder's `sweep-run.log`.
    /// Returns the results in job order.
    pub fn run(
        &self,
        on_done: &(dyn Fn(JobDone<'_>) + Sync),
    ) -> Result<Vec<JobResult>, SweepError> {
        let exe = std::env::current_exe().map_err(SweepError::Exe)?;
        let done = AtomicUsize::new(0);
        let results: Mutex<Vec<Option<JobResult>>> =
            Mutex::new((0..self.jobs.len()).map(|_| None).collect());
        for &mode in self.plan.mode.modes() {
            let batch: Vec<usize> = (0..self.jobs.len())
                .filter(|&i| self.jobs[i].mode == mode)
                .collect();
            let workers = match mode {
                Mode::Lockstep => self.workers,
                Mode::Realtime => 1,
            };
            self.run_batch(&exe, &batch, workers, &done, &results, on_done);
        }
        let results = results.into_inner().map_err(|_| SweepError::Panicked)?;
        Ok(results
            .into_iter()
            .map(|r| r.unwrap_or_else(|| Err("not run".to_string())))
            .collect())
    }

    /// Runs the jobs `batch` (indices into [`Sweep::jobs`]), `workers` at
    /// once.
    fn run_batch(
        &self,
        exe: &Path,
        batch: &[usize],
        workers: usize,
        done: &AtomicUsize,
        results: &Mutex<Vec<Option<JobResult>>>,
        on_done: &(dyn Fn(JobDone<'_>) + Sync),
    ) {
        let next = AtomicUsize::new(0);
        std::thread::scope(|s| {
            for _ in 0..workers.clamp(1, batch.len().max(1)) {
                s.spawn(|| {
                    while let Some(&i) = batch.get(next.fetch_add(1, Ordering::SeqCst)) {
                        let job = &self.jobs[i];
                        let r = self.run_one(exe, job);
                        let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                        on_done(JobDone {
                            done: n,
                            job,
                            error: r.as_ref().err().map(String::as_str),
                        });
                        if let Ok(mut res) = results.lock() {
                            res[i] = Some(r);
                        }
                    }
                });
            }
        });
    }

    fn run_one(&self, exe: &Path, job: &Job) -> JobResult {
        let out = self.dir.join(&job.folder);
        let mut cmd = Command::new(exe);
        cmd.arg("run")
            .arg(&self.plan.scenario)
            .args(["--mode", &job.mode.to_string(), "--quiet", "--out"])
            .arg(&out);
        for s in sets(&self.axes, &self.combos[job.combo], job.seed) {
            cmd.arg("--set").arg(s);
        }
        let o = cmd
            .stdin(Stdio::null())
            .output()
            .map_err(|e| format!("cannot start mrsim run: {e}"))?;
        if o.status.success() {
            read_run(&out)
        } else {
            let log = out.join("sweep-run.log");
            let _ = std::fs::write(&log, [o.stdout, o.stderr].concat());
            Err(format!(
                "mrsim run failed ({}); its output is in {}",
                o.status,
                log.display()
            ))
        }
    }
}

/// One combination's means in one mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The combination (index into [`Sweep::combos`]).
    pub combo: usize,
    /// How its runs kept time.
    pub mode: Mode,
    /// Runs that gave metrics.
    pub runs: usize,
    /// Per column of [`METRICS`], in order: the mean over the runs and the
    /// half-width of its 95 % interval ([`mean_ci`]).
    pub stats: Vec<(Option<f64>, Option<f64>)>,
}

/// A metric's axis label (with its unit) and whether it is a fraction (an
/// axis from 0 to 1), for the figure.
fn metric_axis(name: &str, length: &str) -> (String, bool) {
    match name {
        "success_rate" => ("robots at their goal (fraction)".into(), true),
        "collisions_total" => ("contacts per run".into(), false),
        "collided" => ("runs with a contact (fraction)".into(), true),
        "makespan" => ("last arrival [s]".into(), false),
        "path_length_ratio" => ("path / straight line".into(), false),
        "min_clearance" => (format!("smallest gap [{length}]"), false),
        "time_to_goal" => ("mean time to goal [s]".into(), false),
        "agents_lost" => ("agents lost per run".into(), false),
        "ticks" => ("ticks per run".into(), false),
        other => (other.to_string(), false),
    }
}

/// The unit of a swept key's values, where its name says it (`[ms]` for a
/// key ending `ms`, seconds for `world.dt`, the length unit for a radius).
fn key_unit(key: &str, length: &str) -> Option<String> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let unit = match last {
        "ms" => "ms".to_string(),
        "dt" | "duration" | "stall_timeout" | "horizon" => "s".to_string(),
        "max_speed" => format!("{length}/s"),
        "max_accel" => format!("{length}/s^2"),
        "radius" | "sensing_range" | "goal_tolerance" => length.to_string(),
        _ if last.ends_with("_ms") => "ms".to_string(),
        _ if last.ends_with("_deg") => "deg".to_string(),
        _ if last.ends_with("_s") => "s".to_string(),
        _ => return None,
    };
    Some(unit)
}

/// A legend's text: `key=value` with the key's last part, cut short.
fn short_pair(key: &str, value: &str) -> String {
    let short = key.rsplit('.').next().unwrap_or(key);
    let mut v: String = value.chars().take(32).collect();
    if value.chars().count() > 32 {
        v.push_str("...");
    }
    format!("{short}={v}")
}

impl Sweep {
    /// Each combination's means and 95 % intervals over its seeds, mode by
    /// mode (lockstep first), combination by combination.
    pub fn summarize(&self, results: &[JobResult]) -> Vec<Summary> {
        let mut out = Vec::new();
        for &mode in self.plan.mode.modes() {
            for combo in 0..self.combos.len() {
                let runs: Vec<&RunMetrics> = self
                    .jobs
                    .iter()
                    .zip(results)
                    .filter(|(j, _)| j.combo == combo && j.mode == mode)
                    .filter_map(|(_, r)| r.as_ref().ok())
                    .collect();
                let stats = METRICS
                    .iter()
                    .map(|(_, f)| mean_ci(&runs.iter().filter_map(|m| f(m)).collect::<Vec<_>>()))
                    .collect();
                out.push(Summary {
                    combo,
                    mode,
                    runs: runs.len(),
                    stats,
                });
            }
        }
        out
    }

    /// The swept key on the figure's x axis: `--x`, else the first swept
    /// key whose values are all numbers (none: no figure).
    pub fn x_axis(&self) -> Option<usize> {
        match &self.plan.x {
            Some(x) => numeric_axis(&self.axes, x).ok(),
            None => self
                .axes
                .iter()
                .position(|(_, vs)| vs.iter().all(|v| v.parse::<f64>().is_ok())),
        }
    }

    /// The figure of `summaries` ([`Sweep::summarize`]): every metric
    /// against the swept number [`Sweep::x_axis`], one line per combination
    /// of the other keys (and per mode), with its 95 % band. None if no
    /// swept key is a number.
    pub fn figure(&self, summaries: &[Summary]) -> Option<Figure> {
        let xi = self.x_axis()?;
        let others = |combo: usize| -> Vec<&String> {
            self.combos[combo]
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != xi)
                .map(|(_, v)| v)
                .collect()
        };
        // Lines: (other values, mode), in order of first appearance.
        let mut lines: Vec<(Vec<&String>, Mode)> = Vec::new();
        for s in summaries {
            let key = (others(s.combo), s.mode);
            if !lines.contains(&key) {
                lines.push(key);
            }
        }
        let mut colours: Vec<&Vec<&String>> = Vec::new();
        let both = self.plan.mode == SweepMode::Both;
        let series: Vec<Series> = lines
            .iter()
            .map(|(rest, mode)| {
                let colour = match colours.iter().position(|c| *c == rest) {
                    Some(c) => c,
                    None => {
                        colours.push(rest);
                        colours.len() - 1
                    }
                };
                let pairs: Vec<String> = self
                    .axes
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != xi)
                    .zip(rest)
                    .map(|((_, (k, _)), v)| short_pair(k, v))
                    .collect();
                let how = match mode {
                    Mode::Lockstep => "lockstep (modelled)",
                    Mode::Realtime => "realtime (measured)",
                };
                let label = match (pairs.is_empty(), both) {
                    (true, _) => how.to_string(),
                    (false, false) => pairs.join(", "),
                    (false, true) => format!("{}, {how}", pairs.join(", ")),
                };
                Series {
                    label,
                    colour,
                    measured: *mode == Mode::Realtime,
                }
            })
            .collect();
        let panels = METRICS
            .iter()
            .enumerate()
            .map(|(m, (name, _))| {
                let (y_label, fraction) = metric_axis(name, self.length_unit);
                let lines = lines
                    .iter()
                    .map(|(rest, mode)| {
                        summaries
                            .iter()
                            .filter(|s| s.mode == *mode && others(s.combo) == *rest)
                            .filter_map(|s| {
                                let x = self.combos[s.combo][xi].parse::<f64>().ok()?;
                                let (mean, half_width) = s.stats[m];
                                Some(Point {
                                    x,
                                    mean: mean?,
                                    half_width,
                                })
                            })
                            .collect()
                    })
                    .collect();
                Panel {
                    title: name.to_string(),
                    y_label,
                    fraction,
                    lines,
                }
            })
            .collect();
        let key = &self.axes[xi].0;
        let modes = match self.plan.mode {
            SweepMode::Lockstep => "lockstep runs",
            SweepMode::Realtime => "realtime runs",
            SweepMode::Both => "lockstep (solid) and realtime (dashed) runs",
        };
        Some(Figure {
            title: format!(
                "{}: mean over seeds 1..{} with its 95 % interval, {modes}",
                self.name, self.plan.seeds
            ),
            x_label: match key_unit(key, self.length_unit) {
                Some(u) => format!("{key} [{u}]"),
                None => key.clone(),
            },
            series,
            panels,
        })
    }

    /// Draws [`Sweep::figure`] into `sweep.svg` and `sweep.png` in the
    /// sweep's folder; false (nothing drawn) if no swept key is a number.
    pub fn draw(&self, summaries: &[Summary]) -> Result<bool, mrsim_report::RenderError> {
        match self.figure(summaries) {
            Some(f) => write_figure(
                &f,
                &self.dir.join(mrsim_runfolder::SWEEP_SVG_FILE),
                &self.dir.join(mrsim_runfolder::SWEEP_PNG_FILE),
            )
            .map(|()| true),
            None => Ok(false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_axis_names_the_unit_its_key_says() {
        assert_eq!(key_unit("world.dt", "m").as_deref(), Some("s"));
        assert_eq!(
            key_unit("defaults.timing.compute.ms", "m").as_deref(),
            Some("ms")
        );
        assert_eq!(key_unit("robot.*.max_speed", "cm").as_deref(), Some("cm/s"));
        assert_eq!(
            key_unit("defaults.field_of_view_deg", "m").as_deref(),
            Some("deg")
        );
        assert_eq!(key_unit("generate.count", "m"), None);
    }

    #[test]
    fn seeds_that_give_the_same_runs_are_told_from_seeds_that_do_not() {
        let job = |combo, seed| Job {
            combo,
            seed,
            mode: Mode::Lockstep,
            folder: String::new(),
        };
        let jobs = [job(0, 1), job(0, 2), job(1, 1), job(1, 2)];
        let run = |s: f64| -> JobResult {
            Ok(RunMetrics {
                success_rate: s,
                ..Default::default()
            })
        };
        let same = [run(1.0), run(1.0), run(0.5), run(0.5)];
        assert!(seeds_change_nothing(&jobs, &same));
        let differ = [run(1.0), run(1.0), run(0.5), run(0.25)];
        assert!(!seeds_change_nothing(&jobs, &differ));
        // One seed: nothing to compare.
        assert!(!seeds_change_nothing(&jobs[..1], &same[..1]));
    }

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
