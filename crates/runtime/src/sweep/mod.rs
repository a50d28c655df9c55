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

mod axes;
mod figure;
mod metrics;
mod stats;

pub use metrics::{Column, METRICS, ROBOT_MEANS, RobotColumn, SweepRow};
pub use stats::{largest_allowable, mean_ci};

use crate::error::{Invalid, Refusal};
use crate::validate::{ScenarioSource, Validated};
pub use axes::sets;
use axes::{combinations, label, numeric_axis, parse_axes};
pub use metrics::read_run;
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
    /// of more than one value whose values are all numbers).
    pub x: Option<String>,
    /// The metrics the figure draws, in this order (empty: every one of
    /// [`METRICS`]).
    pub metrics: Vec<String>,
    /// How the realtime runs are scheduled (`--cpus LIST`, `--rt`, given
    /// to each realtime run; lockstep runs are not pinned, since the model
    /// decides their timing).
    pub sched: crate::sched::Sched,
    /// Keep a run whose folder already holds a whole run of the same
    /// scenario file, overrides and mode (its `source.json` says so and its
    /// `metrics.json`, written last, reads), instead of running it again:
    /// a sweep cut short (SIGKILL, a cluster's time limit) and started
    /// again with the same command and `--out` goes on where it stopped.
    /// The realtime runs' `--cpus`/`--rt` are not recorded, so not compared.
    pub resume: bool,
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

/// True when a sweep ran more than one seed and every combination's seeds
/// gave the same metrics: the scene has nothing random (no `jitter`, no
/// noise, no random obstacles), so its intervals say nothing.
pub fn seeds_change_nothing(jobs: &[Job], results: &[JobResult]) -> bool {
    let mut first: std::collections::BTreeMap<(usize, bool), &SweepRow> = Default::default();
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
pub type JobResult = Result<SweepRow, String>;

/// A run of a sweep has ended.
#[derive(Debug)]
pub struct JobDone<'a> {
    /// Runs done so far, this one included.
    pub done: usize,
    /// The run.
    pub job: &'a Job,
    /// Why it failed, if it did.
    pub error: Option<&'a str>,
    /// It was not run: its folder already held it ([`SweepPlan::resume`]).
    pub kept: bool,
}

/// A checked plan: every combination valid, the runs listed, nothing
/// made on disk yet.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The swept keys and their values.
    pub axes: Vec<(String, Vec<String>)>,
    /// Every combination of the values, first key slowest.
    pub combos: Vec<Vec<String>>,
    /// Every run, combination by combination, seed by seed (folders
    /// relative to the sweep's).
    pub jobs: Vec<Job>,
    /// The scenario's name.
    pub name: String,
    /// The scenario's length unit (`m`, `cm`, `mm`).
    pub length_unit: &'static str,
    /// Every file the runs read besides the scenario itself (maps' YAML
    /// files and images), as the scenario's loader found them.
    pub files: Vec<PathBuf>,
    /// Each run's memory estimate, in [`Checked::jobs`]' order (every run
    /// an `mrsim run` over shared memory, as [`Sweep::run`] starts them).
    pub estimates: Vec<crate::memory::Estimate>,
}

/// Checks the plan and every combination, refuses runs at once that would
/// not fit in memory together ([`crate::memory::check_at_once`]: the
/// lockstep ones `workers` at once, the realtime ones one at a time), and
/// makes the sweep's folder.
pub fn prepare(plan: &SweepPlan) -> Result<Sweep, SweepError> {
    let Checked {
        axes,
        combos,
        jobs,
        name,
        length_unit,
        files: _,
        estimates,
    } = check(plan)?;
    let workers = plan
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(jobs.len())
        .max(1);
    let limits = mrsim_sys::memory::limits();
    let origin = plan.scenario.display().to_string();
    for &mode in plan.mode.modes() {
        let batch: Vec<crate::memory::Estimate> = jobs
            .iter()
            .zip(&estimates)
            .filter(|(j, _)| j.mode == mode)
            .map(|(_, e)| *e)
            .collect();
        let at_once = match mode {
            Mode::Lockstep => workers,
            Mode::Realtime => 1,
        };
        crate::memory::check_at_once(&origin, &batch, at_once, &limits)?;
    }
    let dir = crate::out::prepare(plan.out.as_deref(), &format!("sweep-{name}"))?;
    std::fs::create_dir_all(dir.join("runs")).map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot create runs/ in it: {e}",
            dir.display()
        ))
    })?;
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

/// Checks the plan and every combination (in each mode) and lists the
/// runs, without making anything on disk.
pub fn check(plan: &SweepPlan) -> Result<Checked, SweepError> {
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
    for m in &plan.metrics {
        if !METRICS.iter().any(|(name, _)| name == m) {
            let known: Vec<&str> = METRICS.iter().map(|(name, _)| *name).collect();
            return Err(Invalid(format!(
                "--metrics {m}: no such metric (known: {})",
                known.join(", ")
            ))
            .into());
        }
    }
    let combos = combinations(&axes);
    // Validate every combination before anything runs.
    let mut name = String::new();
    let mut length_unit = "m";
    let mut files: Vec<PathBuf> = Vec::new();
    let mut combo_estimates: Vec<crate::memory::Estimate> = Vec::new();
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
            if let Some(map) = &v.scenario().map {
                for f in [&map.file, &map.image] {
                    let f = PathBuf::from(f);
                    if !files.contains(&f) {
                        files.push(f);
                    }
                }
            }
            if mode == plan.mode.modes()[0] {
                combo_estimates.push(crate::memory::estimate(
                    v.scenario(),
                    crate::transport::Transport::Shm,
                ));
            }
            name = v.scenario().name.clone();
            length_unit = match v.scenario().length_unit {
                mrsim_scenario::LengthUnit::M => "m",
                mrsim_scenario::LengthUnit::Cm => "cm",
                mrsim_scenario::LengthUnit::Mm => "mm",
            };
        }
    }
    let mut jobs: Vec<Job> = Vec::new();
    let mut estimates = Vec::new();
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
            estimates.extend((1..=plan.seeds).map(|_| combo_estimates[i]));
        }
    }
    Ok(Checked {
        axes,
        combos,
        jobs,
        name,
        length_unit,
        files,
        estimates,
    })
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
                        let (r, kept) = match self.kept(job) {
                            Some(row) => (Ok(row), true),
                            None => (self.run_one(exe, job), false),
                        };
                        let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                        on_done(JobDone {
                            done: n,
                            job,
                            error: r.as_ref().err().map(String::as_str),
                            kept,
                        });
                        if let Ok(mut res) = results.lock() {
                            res[i] = Some(r);
                        }
                    }
                });
            }
        });
    }

    /// Under [`SweepPlan::resume`], the metrics of `job`'s folder if it
    /// already holds that very run, whole.
    fn kept(&self, job: &Job) -> Option<SweepRow> {
        if !self.plan.resume {
            return None;
        }
        let out = self.dir.join(&job.folder);
        let doc: mrsim_runfolder::SourceDoc =
            mrsim_runfolder::read_json(&out, mrsim_runfolder::SOURCE_FILE).ok()?;
        let file = std::fs::canonicalize(&self.plan.scenario).ok()?;
        let set = sets(&self.axes, &self.combos[job.combo], job.seed);
        let same = doc.file.as_deref() == Some(file.as_path())
            && doc.set == set
            && doc.mode.as_deref() == Some(job.mode.to_string().as_str());
        if !same {
            return None;
        }
        read_run(&out).ok()
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
        if job.mode == Mode::Realtime {
            if let Some(cpus) = &self.plan.sched.cpus {
                cmd.args(["--cpus", cpus]);
            }
            if self.plan.sched.rt {
                cmd.arg("--rt");
            }
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

/// Runs one run of a sweep in this process, in lockstep, as the sweep's
/// `mrsim run` child would (the same scenario, overrides and seed give the
/// same metrics: lockstep runs are identical in and out of process), into
/// the folder `out`, and reads its metrics. For callers that spread a
/// sweep's runs themselves (the Python package's `mrsim.sweep`).
pub fn run_in_process(scenario: &Path, set: Vec<String>, out: &Path) -> JobResult {
    let req = crate::launch::InProcess {
        scenario: ScenarioSource {
            path: Some(scenario.to_path_buf()),
            mode: Some(Mode::Lockstep),
            set,
        },
        registry: std::sync::Arc::new(mrsim_planners::Registry::builtin()),
        out: Some(out.to_path_buf()),
        render: false,
        plan_timeout: None,
    };
    let r = crate::launch::run_in_process(&req).map_err(|e| crate::error::in_words(&e))?;
    read_run(&r.dir)
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

impl Sweep {
    /// Each combination's means and 95 % intervals over its seeds, mode by
    /// mode (lockstep first), combination by combination.
    pub fn summarize(&self, results: &[JobResult]) -> Vec<Summary> {
        let mut out = Vec::new();
        for &mode in self.plan.mode.modes() {
            for combo in 0..self.combos.len() {
                let runs: Vec<&SweepRow> = self
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
}

#[cfg(test)]
mod tests {
    use super::axes::split_values;
    use super::figure::key_unit;
    use super::stats::t975;
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
            Ok(SweepRow {
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
