//! `mrsim sweep`: a general experiment runner; the runs and their
//! metrics (the tables are the caller's).
//!
//! A sweep runs every combination of the values of some keys (the
//! cartesian product, the first key varying slowest) with each seed 1..=N
//! (`world.seed`). Each run is an ordinary `mrsim run` child process,
//! forced to lockstep, with its own run folder `DIR/runs/<combination>-s<seed>/`;
//! up to `jobs` run at once. Every combination is validated before any run
//! starts.
//!
//! Values are split at commas outside brackets, braces and quotes, so
//! `--set 'obstacle.*.motion={ model = "static" },{ model = "random", ... }'`
//! and `--set 'robot.r0.goal=[1, 2],[3, 4]'` give two values each; a comma
//! inside a plain value cannot be written (none of the scenario format's
//! plain values needs one).

use crate::error::{Invalid, Refusal};
use crate::validate::{ScenarioSource, Validated};
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
    let mut first: std::collections::BTreeMap<usize, &RunMetrics> = Default::default();
    let mut repeated = false;
    for (job, r) in jobs.iter().zip(results) {
        let Ok(m) = r else { continue };
        match first.get(&job.combo) {
            None => {
                first.insert(job.combo, m);
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
    /// Runs at once.
    pub workers: usize,
    /// The sweep's folder.
    pub dir: PathBuf,
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
    let combos = combinations(&axes);
    // Validate every combination before anything runs.
    let mut name = String::new();
    for combo in &combos {
        let v = Validated::new(ScenarioSource {
            path: Some(plan.scenario.clone()),
            mode: Some(Mode::Lockstep),
            set: sets(&axes, combo, 1),
        })
        .map_err(|e| {
            let what: Vec<String> = axes
                .iter()
                .zip(combo)
                .map(|((k, _), v)| format!("{k}={v}"))
                .collect();
            Invalid(format!("combination {}: {e}", what.join(" ")))
        })?;
        if let Some(r) = v.external_robots().first() {
            return Err(Invalid(format!(
                "{}: robot `{r}` has planner = \"external\": a sweep starts its runs \
                 unattended, with no program of yours to join them",
                v.origin()
            ))
            .into());
        }
        name = v.scenario().name.clone();
    }
    let dir = crate::out::prepare(plan.out.as_deref(), &format!("sweep-{name}"))?;
    std::fs::create_dir_all(dir.join("runs")).map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot create runs/ in it: {e}",
            dir.display()
        ))
    })?;
    let jobs: Vec<Job> = combos
        .iter()
        .enumerate()
        .flat_map(|(i, c)| {
            let l = label(i, &axes, c);
            (1..=plan.seeds).map(move |seed| Job {
                combo: i,
                seed,
                folder: format!("runs/{l}-s{seed}"),
            })
        })
        .collect();
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
    })
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
    /// Runs every job, [`Sweep::workers`] at once, each an `mrsim run` child
    /// process; `on_done` hears of each as it ends (from the worker
    /// threads). A failed run's output is kept in its folder's
    /// `sweep-run.log`. Returns the results in job order.
    pub fn run(
        &self,
        on_done: &(dyn Fn(JobDone<'_>) + Sync),
    ) -> Result<Vec<JobResult>, SweepError> {
        let exe = std::env::current_exe().map_err(SweepError::Exe)?;
        let next = AtomicUsize::new(0);
        let done = AtomicUsize::new(0);
        let results: Mutex<Vec<Option<JobResult>>> =
            Mutex::new((0..self.jobs.len()).map(|_| None).collect());
        std::thread::scope(|s| {
            for _ in 0..self.workers {
                s.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        let Some(job) = self.jobs.get(i) else { break };
                        let r = self.run_one(&exe, job);
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
        let results = results.into_inner().map_err(|_| SweepError::Panicked)?;
        Ok(results
            .into_iter()
            .map(|r| r.unwrap_or_else(|| Err("not run".to_string())))
            .collect())
    }

    fn run_one(&self, exe: &Path, job: &Job) -> JobResult {
        let out = self.dir.join(&job.folder);
        let mut cmd = Command::new(exe);
        cmd.arg("run")
            .arg(&self.plan.scenario)
            .args(["--mode", "lockstep", "--quiet", "--out"])
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_that_give_the_same_runs_are_told_from_seeds_that_do_not() {
        let job = |combo, seed| Job {
            combo,
            seed,
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
