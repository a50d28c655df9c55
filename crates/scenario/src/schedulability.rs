//! Schedulability analysis of the robots' planners as a real-time task set:
//! the classical tests, as pure functions of a [`TaskSet`], for the three
//! schedulers of the cores' model (`fair`, `fifo`, `deadline`).
//!
//! Every robot whose planner does CPU work is a task: C, its CPU per call
//! (for the verdict: a fixed time; a uniform model's `max_ms`; a
//! log-normal model's 99th percentile, `median_ms` e^(2.326 `sigma`), since
//! it has no maximum; a per-body model's time with every other body of the
//! scene in view), T its period (`period_ticks` x `dt`), D its deadline
//! (`deadline` x `dt`); tasks in name order, fifo's levels as the cores'
//! model gives them ([`crate::cores::fifo_levels`]). The utilisation shown is the mean CPU per call over
//! T (the log-normal's mean `median_ms` e^(`sigma`²/2); the per-body
//! bound as for C). The world's own CPU (`world_ms` each tick) is one more
//! task of period and deadline `dt` at the highest priority. m is the
//! number of cores.
//!
//! - **fifo** (global fixed-priority preemptive): U <= m (necessary);
//!   where the priorities are rate-monotonic and every deadline is its
//!   period, on one core the Liu & Layland bound U <= n (2^(1/n) - 1)
//!   (Liu & Layland, JACM 1973), on m cores the global RM bound
//!   U <= m/2 (1 - u_max) + u_max (Bertogna, Cirinei & Lipari, OPODIS
//!   2005); per robot, response-time analysis: on one core the exact
//!   recurrence R = C + sum over higher priorities of ceil(R / T_j) C_j
//!   (Joseph & Pandya 1986; Audsley et al. 1993), on m cores the bound of
//!   Guan, Stigge, Yi & Yu (RTSS 2009): Bertogna & Cirinei's (RTSS 2007)
//!   R = C + floor(1/m sum min(W_j(R), R - C + 1)), where only m - 1 of
//!   the higher-priority tasks may carry work into the window, in whole
//!   microseconds. Equal priorities are taken in the order of the tasks
//!   (the caller sorts them by name).
//! - **deadline** (global EDF, each reservation a constant-bandwidth
//!   server): U <= m (necessary); the GFB bound U <= m - (m - 1) u_max
//!   (Goossens, Funk & Baruah, Real-Time Systems 2003; with densities
//!   C / min(D, T) where a deadline is shorter than its period); per robot
//!   the test of Bertogna, Cirinei & Lipari (ECRTS 2005): task k keeps its
//!   deadlines if sum over i != k of min(beta_i, 1 - lambda_k) < m (1 -
//!   lambda_k). A robot with a reservation `{ runtime_ms, period_ms }`
//!   enters these tests as its server (C = runtime, T = D = period, its
//!   bandwidth runtime / period) and keeps its deadlines only if, besides,
//!   its CPU per call fits the runtime and the server's period its deadline:
//!   a call that needs more is throttled until the next period. The world
//!   runs above the servers, as in the model: with `world_ms` > 0 the GFB
//!   bound does not apply, and the per-task test counts the world's whole
//!   CPU in each window.
//! - **fair** (processor sharing among the runnable agents, each at most
//!   one core): overloaded if U > m; per robot, the response time when
//!   every robot's call starts at once (at tick 0 every period begins
//!   together), the world first on one core for `world_ms`, then the cores
//!   shared out equally among the calls still running (water-filling); a
//!   robot misses if its call ends after its deadline.
//!
//! A robot whose compute is a wait (`cpu = false`) takes no CPU: it misses
//! only if its wait alone is longer than its deadline.
//!
//! Sufficient tests that fail are inconclusive (the set may still keep
//! every deadline); a necessary test that fails means some robot must miss.

use crate::timing::{Compute, Priority};
use crate::types::Scenario;
use std::fmt::Write;

/// One robot's planner as a task.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// The robot's name.
    pub name: String,
    /// True if its compute time is CPU work that shares the cores; false if
    /// it is a wait.
    pub cpu: bool,
    /// CPU (or wait) per call for the verdict, ns (see the module's text).
    pub c_ns: u64,
    /// Mean CPU (or wait) per call, ns, for the utilisation.
    pub mean_ns: u64,
    /// Period, ns (`period_ticks` x `dt`), > 0.
    pub period_ns: u64,
    /// Relative deadline, ns (`deadline` x `dt`), > 0.
    pub deadline_ns: u64,
    /// Fixed priority under fifo: higher runs first.
    pub priority: u32,
    /// What the priority was given as, for the table (e.g. `7`,
    /// `rate-monotonic`).
    pub priority_text: String,
    /// Under deadline: the reservation, (runtime, period) in ns.
    pub reservation: Option<(u64, u64)>,
}

/// The task set of a scenario's robots on its cores.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSet {
    /// Cores the agents' CPU work shares, m >= 1.
    pub cores: u32,
    /// True without `[world.cpus]`: a core of its own per robot.
    pub own_cores: bool,
    /// The tick, ns.
    pub dt_ns: u64,
    /// The world's own CPU each tick, ns (0: none).
    pub world_ns: u64,
    /// The robots' tasks, in name order.
    pub tasks: Vec<Task>,
}

/// The task set of `sc`'s robots and the name of its scheduler, if the
/// scenario has `[world.cpus]` or a robot with `cpu = true`; None for any
/// other scenario. Without `[world.cpus]` every CPU robot has a core of its
/// own (m = their number, `fair`).
pub fn task_set(sc: &Scenario) -> Option<(TaskSet, &'static str)> {
    let cpu = |t: &Option<crate::timing::Timing>| t.as_ref().is_some_and(|t| t.cpu);
    let cpus = sc.world.cpus;
    if cpus.is_none() && !sc.robots.iter().any(|r| cpu(&r.timing)) {
        return None;
    }
    let dt_ns = crate::timing::s_to_ns(sc.world.dt).max(1);
    let deadline_ns = crate::timing::s_to_ns(sc.world.dt * sc.world.deadline).max(1);
    let others = sc.body_count().saturating_sub(1) as f64;
    let mut robots: Vec<&crate::types::RobotSpec> = sc.robots.iter().collect();
    robots.sort_by(|a, b| a.name.cmp(&b.name));
    let model: Vec<crate::cores::Task> = robots
        .iter()
        .map(|r| {
            let t = r.timing.clone().unwrap_or_default();
            crate::cores::Task {
                name: r.name.clone(),
                period_ticks: t.period_ticks,
                priority: t.priority,
                reservation: t.reservation,
            }
        })
        .collect();
    let levels = crate::cores::fifo_levels(&model);
    let tasks = robots
        .iter()
        .zip(&levels)
        .map(|(r, &level)| {
            let t = r.timing.clone().unwrap_or_default();
            let (c_ms, mean_ms) = match t.compute {
                Compute::None => (0.0, 0.0),
                Compute::Fixed { ms } => (ms, ms),
                Compute::Uniform { min_ms, max_ms } => (max_ms, (min_ms + max_ms) / 2.0),
                Compute::Lognormal { median_ms, sigma } => (
                    median_ms * (Z99 * sigma).exp(),
                    median_ms * (sigma * sigma / 2.0).exp(),
                ),
                Compute::PerBody {
                    base_ms,
                    per_body_ms,
                } => {
                    let all = base_ms + per_body_ms * others;
                    (all, all)
                }
            };
            Task {
                name: r.name.clone(),
                cpu: t.cpu,
                c_ns: crate::timing::ms_to_ns(c_ms),
                mean_ns: crate::timing::ms_to_ns(mean_ms),
                period_ns: dt_ns * u64::from(t.period_ticks.max(1)),
                deadline_ns,
                priority: u32::from(level),
                priority_text: match t.priority {
                    Some(Priority::Level(l)) => l.to_string(),
                    _ => format!("{level} (rate-monotonic)"),
                },
                reservation: t.reservation.map(|v| (v.runtime_ns(), v.period_ns())),
            }
        })
        .collect::<Vec<_>>();
    let (cores, scheduler, world_ns) = match cpus {
        Some(c) => (
            c.count.max(1),
            c.scheduler.name(),
            crate::timing::ms_to_ns(c.world_ms),
        ),
        None => (
            u32::try_from(tasks.iter().filter(|t| t.cpu).count())
                .unwrap_or(u32::MAX)
                .max(1),
            "fair",
            0,
        ),
    };
    Some((
        TaskSet {
            cores,
            own_cores: cpus.is_none(),
            dt_ns,
            world_ns,
            tasks,
        },
        scheduler,
    ))
}

/// The task set and verdict of `sc` ([`task_set`], [`verdict`]), None for
/// a scenario without `[world.cpus]` and without CPU robots.
pub fn of_scenario(sc: &Scenario) -> Option<(TaskSet, Verdict)> {
    let (set, scheduler) = task_set(sc)?;
    let v = verdict(&set, scheduler)?;
    Some((set, v))
}

/// What a test concludes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Conclusion {
    /// Passed: the deadlines it covers are kept.
    Holds,
    /// A sufficient test failed: no conclusion.
    Inconclusive,
    /// A necessary test failed: some deadline must be missed.
    Fails,
    /// The test's premises do not hold for this set.
    NotApplicable,
}

impl Conclusion {
    /// A word for the table.
    pub fn word(self) -> &'static str {
        match self {
            Conclusion::Holds => "holds",
            Conclusion::Inconclusive => "fails (inconclusive: a sufficient test)",
            Conclusion::Fails => "fails: some robot must miss",
            Conclusion::NotApplicable => "does not apply",
        }
    }
}

/// One test of the set as a whole.
#[derive(Debug, Clone, PartialEq)]
pub struct SetTest {
    /// The test and its source, e.g. `GFB bound (Goossens, Funk & Baruah 2003)`.
    pub name: String,
    /// The inequality with the set's numbers, e.g. `U = 1.60 <= 2`.
    pub detail: String,
    /// What it concludes.
    pub conclusion: Conclusion,
}

/// One robot's verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotVerdict {
    /// The robot's name.
    pub name: String,
    /// Its response-time bound, ns, where the test gives one (None: no
    /// bound found below the deadline).
    pub response_ns: Option<u64>,
    /// True if the analysis predicts it may miss deadlines.
    pub may_miss: bool,
    /// Why, in a few words.
    pub why: String,
}

/// The verdict of one scheduler's tests on a task set.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// `fair`, `fifo` or `deadline`.
    pub scheduler: &'static str,
    /// The per-robot test's name and source.
    pub robot_test: String,
    /// The tests of the whole set.
    pub set_tests: Vec<SetTest>,
    /// Per robot, in the task set's order.
    pub robots: Vec<RobotVerdict>,
}

impl Verdict {
    /// The robots predicted to miss, by name.
    pub fn predicted_misses(&self) -> Vec<&str> {
        self.robots
            .iter()
            .filter(|r| r.may_miss)
            .map(|r| r.name.as_str())
            .collect()
    }
}

/// The number of standard deviations of the 99th percentile of a normal
/// variable: the log-normal compute's C is `median` e^(Z99 `sigma`).
pub const Z99: f64 = 2.326_347_874;

impl TaskSet {
    fn cpu_tasks(&self) -> impl Iterator<Item = &Task> {
        self.tasks.iter().filter(|t| t.cpu)
    }

    /// The world's utilisation of one core.
    pub fn world_utilisation(&self) -> f64 {
        if self.dt_ns == 0 {
            0.0
        } else {
            self.world_ns as f64 / self.dt_ns as f64
        }
    }

    /// The mean utilisation of the cores: the world's and every CPU task's
    /// mean CPU per call over its period.
    pub fn utilisation(&self) -> f64 {
        self.world_utilisation() + self.cpu_tasks().map(Task::utilisation).sum::<f64>()
    }

    /// The utilisation with the verdict's C (the tests' U).
    fn worst_utilisation(&self) -> f64 {
        self.world_utilisation() + self.cpu_tasks().map(Task::worst_utilisation).sum::<f64>()
    }
}

impl Task {
    /// Mean CPU per call over the period, at most 1: a planner is one
    /// thread, which a call longer than its period keeps busy.
    pub fn utilisation(&self) -> f64 {
        (self.mean_ns as f64 / self.period_ns.max(1) as f64).min(1.0)
    }

    /// The verdict's CPU per call over the period, at most 1.
    fn worst_utilisation(&self) -> f64 {
        (self.c_ns as f64 / self.period_ns.max(1) as f64).min(1.0)
    }
}

/// A task as the tests see it: C, T, D (ns).
#[derive(Debug, Clone, Copy)]
struct Ctd {
    c: u64,
    t: u64,
    d: u64,
}

fn world_ctd(set: &TaskSet) -> Option<Ctd> {
    (set.world_ns > 0).then_some(Ctd {
        c: set.world_ns,
        t: set.dt_ns.max(1),
        d: set.dt_ns.max(1),
    })
}

fn ms(ns: u64) -> String {
    let v = ns as f64 / 1e6;
    if (v - v.round()).abs() < 1e-9 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

fn wait_verdict(t: &Task) -> RobotVerdict {
    let miss = t.c_ns > t.deadline_ns;
    RobotVerdict {
        name: t.name.clone(),
        response_ns: Some(t.c_ns),
        may_miss: miss,
        why: if miss {
            format!(
                "its wait, {} ms, exceeds its deadline {} ms",
                ms(t.c_ns),
                ms(t.deadline_ns)
            )
        } else {
            "waits, no CPU".into()
        },
    }
}

fn utilisation_test(set: &TaskSet) -> SetTest {
    let u = set.worst_utilisation();
    let m = f64::from(set.cores);
    SetTest {
        name: "U <= m (necessary)".into(),
        detail: format!(
            "U = {u:.3} {} {}",
            if u <= m { "<=" } else { ">" },
            set.cores
        ),
        conclusion: if u <= m + 1e-12 {
            Conclusion::Holds
        } else {
            Conclusion::Fails
        },
    }
}

/// True if the priorities are rate-monotonic (a shorter period never has a
/// lower priority) and every CPU task's deadline is its period.
fn rate_monotonic(set: &TaskSet) -> bool {
    let cpu: Vec<&Task> = set.cpu_tasks().collect();
    cpu.iter().all(|t| t.deadline_ns == t.period_ns)
        && cpu.iter().all(|a| {
            cpu.iter()
                .all(|b| !(a.period_ns < b.period_ns && a.priority < b.priority))
        })
        && (set.world_ns == 0 || cpu.iter().all(|t| t.period_ns >= set.dt_ns))
}

/// The fifo scheduler's tests: U <= m, the RM utilisation bound, and
/// response-time analysis per robot.
pub fn fifo(set: &TaskSet) -> Verdict {
    let m = set.cores.max(1);
    let mut set_tests = vec![utilisation_test(set)];
    let u = set.worst_utilisation();
    let cpu: Vec<(usize, &Task)> = set
        .tasks
        .iter()
        .enumerate()
        .filter(|(_, t)| t.cpu)
        .collect();
    let n = cpu.len() + usize::from(set.world_ns > 0);
    let rm = rate_monotonic(set);
    if m == 1 {
        let bound = if n == 0 {
            1.0
        } else {
            n as f64 * (2f64.powf(1.0 / n as f64) - 1.0)
        };
        set_tests.push(SetTest {
            name: "Liu & Layland bound (1973), U <= n (2^(1/n) - 1)".into(),
            detail: if rm {
                format!("U = {u:.3}, bound {bound:.3} for n = {n}")
            } else {
                "the priorities are not rate-monotonic, or a deadline is not its period".into()
            },
            conclusion: match (rm, u <= bound + 1e-12) {
                (false, _) => Conclusion::NotApplicable,
                (true, true) => Conclusion::Holds,
                (true, false) => Conclusion::Inconclusive,
            },
        });
    } else {
        let u_max = cpu
            .iter()
            .map(|(_, t)| t.worst_utilisation())
            .chain([set.world_utilisation()])
            .fold(0.0, f64::max);
        let mf = f64::from(m);
        let bound = mf / 2.0 * (1.0 - u_max) + u_max;
        set_tests.push(SetTest {
            name: "global RM bound (Bertogna, Cirinei & Lipari 2005), U <= m/2 (1 - u_max) + u_max"
                .into(),
            detail: if rm {
                format!("U = {u:.3}, bound {bound:.3} (u_max = {u_max:.3})")
            } else {
                "the priorities are not rate-monotonic, or a deadline is not its period".into()
            },
            conclusion: match (rm, u <= bound + 1e-12) {
                (false, _) => Conclusion::NotApplicable,
                (true, true) => Conclusion::Holds,
                (true, false) => Conclusion::Inconclusive,
            },
        });
    }
    // Linux's real-time throttling (`sched_rt_runtime_us` of
    // `sched_rt_period_us`, 0.95 of each core by default, as the cores'
    // model applies it): beyond it the real-time work of a second cannot
    // be done in that second, and the calls caught in a throttled window
    // wait for the next, whatever their priority.
    let rt_cap =
        f64::from(m) * crate::cores::RT_RUNTIME_NS as f64 / crate::cores::RT_PERIOD_NS as f64;
    let throttled = u > rt_cap + 1e-12;
    set_tests.push(SetTest {
        name: "Linux's real-time throttling (sched_rt_runtime_us / sched_rt_period_us = 0.95 a core), U <= 0.95 m"
            .into(),
        detail: format!(
            "U = {u:.3} {} {rt_cap:.3}",
            if throttled { ">" } else { "<=" }
        ),
        conclusion: if throttled {
            Conclusion::Fails
        } else {
            Conclusion::Holds
        },
    });
    // Priority order: the world first, then by priority (stable: ties in
    // the tasks' order).
    let mut order: Vec<(usize, &Task)> = cpu.clone();
    order.sort_by_key(|t| std::cmp::Reverse(t.1.priority));
    // Higher-priority tasks with their response bound (None: unbounded).
    let mut higher: Vec<(Ctd, Option<u64>)> = Vec::new();
    if let Some(w) = world_ctd(set) {
        higher.push((w, (w.c <= w.d).then_some(w.c)));
    }
    let mut responses: Vec<Option<u64>> = vec![None; set.tasks.len()];
    for (i, t) in &order {
        let me = Ctd {
            c: t.c_ns,
            t: t.period_ns.max(1),
            d: t.deadline_ns,
        };
        let r = if m == 1 {
            rta_one_core(me, &higher)
        } else {
            rta_global(me, &higher, u64::from(m))
        };
        responses[*i] = r;
        higher.push((me, r));
    }
    let robots = set
        .tasks
        .iter()
        .zip(&responses)
        .map(|(t, r)| {
            if !t.cpu {
                return wait_verdict(t);
            }
            match r {
                Some(r) => RobotVerdict {
                    name: t.name.clone(),
                    response_ns: Some(*r),
                    may_miss: throttled,
                    why: format!(
                        "R <= {} ms{}",
                        ms(*r),
                        if throttled {
                            " on whole cores, but throttled"
                        } else {
                            ""
                        }
                    ),
                },
                None => RobotVerdict {
                    name: t.name.clone(),
                    response_ns: None,
                    may_miss: true,
                    why: format!("R > D = {} ms", ms(t.deadline_ns)),
                },
            }
        })
        .collect();
    Verdict {
        scheduler: "fifo",
        robot_test: if m == 1 {
            "response-time analysis (Joseph & Pandya 1986; Audsley et al. 1993)".into()
        } else {
            "response-time bound for global fixed priority (Guan, Stigge, Yi & Yu 2009)".into()
        },
        set_tests,
        robots,
    }
}

/// Exact response time on one core (Joseph & Pandya): the least R with
/// R = C + sum ceil(R / T_j) C_j over the higher priorities; None if it
/// exceeds the deadline (or a higher-priority task is unbounded).
fn rta_one_core(me: Ctd, higher: &[(Ctd, Option<u64>)]) -> Option<u64> {
    if higher.iter().any(|(_, r)| r.is_none()) {
        return None;
    }
    let mut r = me.c;
    loop {
        let next = me.c
            + higher
                .iter()
                .map(|(h, _)| r.div_ceil(h.t) * h.c)
                .sum::<u64>();
        if next > me.d {
            return None;
        }
        if next == r {
            return Some(r);
        }
        r = next;
    }
}

/// Guan, Stigge, Yi & Yu (RTSS 2009), global fixed priority on m cores,
/// in whole microseconds (C rounded up, T and D down): the least x >= C
/// with x = floor(Omega(x) / m) + C, where Omega sums every higher-priority
/// task's interference without carry-in, I_NC = min(W_NC(x), x - C + 1),
/// plus the m - 1 largest extras of one with carry-in, I_CI - I_NC:
/// W_NC(x) = floor(x / T_i) C_i + min(x mod T_i, C_i), W_CI(x) =
/// floor(max(x - C_i, 0) / T_i) C_i + C_i + alpha, alpha = min(max(max(x -
/// C_i, 0) mod T_i - (T_i - R_i), 0), C_i - 1). It refines Bertogna &
/// Cirinei's bound (RTSS 2007), where every task may carry in. A
/// higher-priority task without a bound interferes as much as the window
/// allows. None if R exceeds the deadline.
fn rta_global(me: Ctd, higher: &[(Ctd, Option<u64>)], m: u64) -> Option<u64> {
    const US: u64 = 1000;
    let c = me.c.div_ceil(US);
    let d = me.d / US;
    let hp: Vec<(u64, u64, Option<u64>)> = higher
        .iter()
        .map(|(h, r)| {
            (
                h.c.div_ceil(US),
                (h.t / US).max(1),
                r.map(|r| r.div_ceil(US)),
            )
        })
        .collect();
    let mut x = c;
    let mut extras: Vec<u64> = Vec::with_capacity(hp.len());
    loop {
        if x > d {
            return None;
        }
        let cap = x - c + 1;
        let mut omega: u64 = 0;
        extras.clear();
        for &(ci, ti, ri) in &hp {
            let nc = ((x / ti) * ci + (x % ti).min(ci)).min(cap);
            let Some(ri) = ri else {
                omega += cap;
                continue;
            };
            let y = x.saturating_sub(ci);
            let alpha = ((y % ti).saturating_sub(ti.saturating_sub(ri))).min(ci.saturating_sub(1));
            let ci_w = ((y / ti) * ci + ci + alpha).min(cap);
            omega += nc;
            extras.push(ci_w.saturating_sub(nc));
        }
        let carry = usize::try_from(m - 1).unwrap_or(usize::MAX);
        if extras.len() > carry {
            extras.select_nth_unstable_by(carry, |a, b| b.cmp(a));
            extras.truncate(carry);
        }
        omega += extras.iter().sum::<u64>();
        let next = omega / m + c;
        if next <= x {
            return Some(x * US);
        }
        x = next;
    }
}

/// The deadline scheduler's tests: U <= m, the GFB bound, and per robot
/// the test of Bertogna, Cirinei & Lipari (2005) with its reservation.
pub fn deadline(set: &TaskSet) -> Verdict {
    let m = set.cores.max(1);
    let mf = f64::from(m);
    // Every EDF task: each CPU robot's server (or itself). The world runs
    // above them all.
    let mut tasks: Vec<(Option<usize>, Ctd)> = Vec::new();
    let mut demand = set.world_utilisation();
    for (i, t) in set.tasks.iter().enumerate().filter(|(_, t)| t.cpu) {
        let own = t.worst_utilisation();
        let ctd = match t.reservation {
            Some((q, p)) => {
                demand += own.min(q as f64 / p.max(1) as f64);
                Ctd {
                    c: q,
                    t: p.max(1),
                    d: p.max(1),
                }
            }
            None => {
                demand += own;
                Ctd {
                    c: t.c_ns,
                    t: t.period_ns.max(1),
                    d: t.deadline_ns.max(1),
                }
            }
        };
        tasks.push((Some(i), ctd));
    }
    let density = |c: &Ctd| c.c as f64 / c.d.min(c.t) as f64;
    let lambda: f64 = tasks.iter().map(|(_, c)| density(c)).sum();
    let l_max = tasks.iter().map(|(_, c)| density(c)).fold(0.0, f64::max);
    let gfb = mf - (mf - 1.0) * l_max;
    let set_tests = vec![
        SetTest {
            name: "U <= m (necessary)".into(),
            detail: format!(
                "U = {demand:.3} {} {m} (each robot at most its reservation)",
                if demand <= mf { "<=" } else { ">" }
            ),
            conclusion: if demand <= mf + 1e-12 {
                Conclusion::Holds
            } else {
                Conclusion::Fails
            },
        },
        SetTest {
            name: "GFB bound (Goossens, Funk & Baruah 2003), U <= m - (m - 1) u_max".into(),
            detail: if set.world_ns > 0 {
                "the world's own CPU runs above the reservations".into()
            } else {
                format!("U = {lambda:.3}, bound {gfb:.3} (u_max = {l_max:.3})")
            },
            conclusion: if set.world_ns > 0 {
                Conclusion::NotApplicable
            } else if lambda <= gfb + 1e-12 {
                Conclusion::Holds
            } else {
                Conclusion::Inconclusive
            },
        },
    ];
    let gfb_holds = set_tests[1].conclusion == Conclusion::Holds;
    let robots = set
        .tasks
        .iter()
        .enumerate()
        .map(|(i, t)| {
            if !t.cpu {
                return wait_verdict(t);
            }
            let k = tasks.iter().position(|(j, _)| *j == Some(i)).unwrap_or(0);
            let edf_ok = gfb_holds || bcl_edf(&tasks, k, m, world_ctd(set));
            let (fits, bound) = match t.reservation {
                Some((q, p)) => (t.c_ns <= q && p <= t.deadline_ns, p),
                None => (true, t.deadline_ns),
            };
            let why = match (edf_ok, t.reservation) {
                (false, _) => "the EDF test fails for it".to_string(),
                (true, Some((q, _))) if t.c_ns > q => format!(
                    "needs {} ms a call, its runtime is {} ms: throttled",
                    ms(t.c_ns),
                    ms(q)
                ),
                (true, Some((_, p2))) if p2 > t.deadline_ns => format!(
                    "its reservation's period {} ms exceeds its deadline {} ms",
                    ms(p2),
                    ms(t.deadline_ns)
                ),
                (true, Some((q, p))) => format!(
                    "bandwidth {:.3} ({} ms every {} ms)",
                    q as f64 / p as f64,
                    ms(q),
                    ms(p)
                ),
                (true, None) => "keeps its deadlines".into(),
            };
            RobotVerdict {
                name: t.name.clone(),
                response_ns: (edf_ok && fits).then_some(bound),
                may_miss: !(edf_ok && fits),
                why,
            }
        })
        .collect();
    Verdict {
        scheduler: "deadline",
        robot_test: "global EDF per task (Bertogna, Cirinei & Lipari 2005), with its reservation"
            .into(),
        set_tests,
        robots,
    }
}

/// Bertogna, Cirinei & Lipari (ECRTS 2005), global EDF: task k keeps its
/// deadlines if sum_{i != k} min(beta_i, 1 - lambda_k) < m (1 - lambda_k),
/// or equals it with some 0 < beta_i <= 1 - lambda_k, where lambda_k =
/// C_k / D_k, beta_i = (N C_i + min(C_i, max(0, D_k - N T_i))) / D_k and
/// N = floor((D_k - D_i) / T_i) + 1. The world, above every server, enters
/// with its whole workload in a window of D_k: floor(D_k / dt) world_ms +
/// min(world_ms, D_k mod dt).
fn bcl_edf(tasks: &[(Option<usize>, Ctd)], k: usize, m: u32, world: Option<Ctd>) -> bool {
    let me = tasks[k].1;
    if me.c > me.d {
        return false;
    }
    let dk = me.d as f64;
    let slack = 1.0 - me.c as f64 / dk;
    let mut sum = 0.0;
    let mut some_small = false;
    let mut add = |w: i128| {
        let beta = w as f64 / dk;
        if beta > 0.0 && beta <= slack {
            some_small = true;
        }
        sum += beta.min(slack);
    };
    for (j, (_, o)) in tasks.iter().enumerate() {
        if j == k {
            continue;
        }
        let diff = me.d as i128 - o.d as i128;
        let n = (diff.div_euclid(o.t as i128) + 1).max(0);
        let rest = (me.d as i128 - n * o.t as i128).max(0);
        add(n * o.c as i128 + rest.min(o.c as i128));
    }
    if let Some(w) = world {
        let n = (me.d / w.t) as i128;
        add(n * w.c as i128 + ((me.d % w.t) as i128).min(w.c as i128));
    }
    let limit = f64::from(m) * slack;
    sum < limit - 1e-12 || ((sum - limit).abs() <= 1e-12 && some_small)
}

/// The fair scheduler's tests: overload (U > m) and, per robot, its
/// response time under processor sharing when every call starts at once.
pub fn fair(set: &TaskSet) -> Verdict {
    let m = f64::from(set.cores.max(1));
    let u = set.worst_utilisation();
    let set_tests = vec![SetTest {
        name: "overload, U > m".into(),
        detail: format!(
            "U = {u:.3} {} {}",
            if u <= m { "<=" } else { ">" },
            set.cores
        ),
        conclusion: if u <= m + 1e-12 {
            Conclusion::Holds
        } else {
            Conclusion::Fails
        },
    }];
    let finish = sharing(set);
    let robots = set
        .tasks
        .iter()
        .zip(&finish)
        .map(|(t, f)| {
            if !t.cpu {
                return wait_verdict(t);
            }
            let miss = *f > t.deadline_ns;
            RobotVerdict {
                name: t.name.clone(),
                response_ns: Some(*f),
                may_miss: miss,
                why: format!(
                    "its share ends its call at {} ms {} D = {} ms",
                    ms(*f),
                    if miss { ">" } else { "<=" },
                    ms(t.deadline_ns)
                ),
            }
        })
        .collect();
    Verdict {
        scheduler: "fair",
        robot_test: "processor sharing, every call started together".into(),
        set_tests,
        robots,
    }
}

/// Processor sharing from a common start: the world on one core for its
/// `world_ns`, the cores left shared equally among the running calls, each
/// at most one core. Per task its call's end, ns (0 for a task without
/// CPU work).
fn sharing(set: &TaskSet) -> Vec<u64> {
    let m = f64::from(set.cores.max(1));
    let mut left: Vec<f64> = set
        .tasks
        .iter()
        .map(|t| if t.cpu { t.c_ns as f64 } else { 0.0 })
        .collect();
    let mut end = vec![0u64; left.len()];
    let mut now = 0.0f64;
    let world_end = set.world_ns as f64;
    loop {
        let running: Vec<usize> = (0..left.len()).filter(|&i| left[i] > 0.0).collect();
        if running.is_empty() {
            return end;
        }
        let cores = if now < world_end { m - 1.0 } else { m };
        let rate = (cores / running.len() as f64).min(1.0);
        // The next event: the world's end or the shortest call's.
        let shortest = running
            .iter()
            .map(|&i| left[i])
            .fold(f64::INFINITY, f64::min);
        let mut dt = if rate > 0.0 {
            shortest / rate
        } else {
            f64::INFINITY
        };
        if now < world_end {
            dt = dt.min(world_end - now);
        }
        now += dt;
        for &i in &running {
            left[i] -= rate * dt;
            if left[i] <= 1e-6 {
                left[i] = 0.0;
                end[i] = now.round() as u64;
            }
        }
    }
}

/// The verdict of `scheduler` (`fair`, `fifo` or `deadline`); None for
/// another name.
pub fn verdict(set: &TaskSet, scheduler: &str) -> Option<Verdict> {
    match scheduler {
        "fair" => Some(fair(set)),
        "fifo" => Some(fifo(set)),
        "deadline" => Some(deadline(set)),
        _ => None,
    }
}

/// The task set and the verdict as text: one line per robot (CPU per call,
/// period, deadline, utilisation, priority or reservation, the per-robot
/// test's result), the utilisation in all against the cores, each test of
/// the set, and the robots predicted to miss.
pub fn render(set: &TaskSet, v: &Verdict) -> String {
    let mut out = String::new();
    if set.own_cores {
        let _ = writeln!(
            out,
            "task set: {} robots, no [world.cpus]: a core of its own per CPU robot ({}), each {} ms tick",
            set.tasks.len(),
            set.cores,
            ms(set.dt_ns)
        );
    } else {
        let _ = writeln!(
            out,
            "task set: {} robots on {} cores, scheduler {}, the world {} ms of CPU each {} ms tick",
            set.tasks.len(),
            set.cores,
            v.scheduler,
            ms(set.world_ns),
            ms(set.dt_ns)
        );
    }
    let policy = match v.scheduler {
        "fifo" => "priority",
        "deadline" => "reservation",
        _ => "",
    };
    let mut rows: Vec<Vec<String>> = vec![
        [
            "robot",
            "cpu/call ms",
            "mean ms",
            "period ms",
            "deadline ms",
            "u",
            policy,
            "verdict",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
    ];
    for (t, r) in set.tasks.iter().zip(&v.robots) {
        let pol = match v.scheduler {
            "fifo" => t.priority_text.clone(),
            "deadline" => t
                .reservation
                .map(|(q, p)| format!("{} / {} ms", ms(q), ms(p)))
                .unwrap_or_else(|| "-".into()),
            _ => String::new(),
        };
        rows.push(vec![
            t.name.clone(),
            if t.cpu {
                ms(t.c_ns)
            } else {
                format!("{} (wait)", ms(t.c_ns))
            },
            ms(t.mean_ns),
            ms(t.period_ns),
            ms(t.deadline_ns),
            if t.cpu {
                format!("{:.3}", t.utilisation())
            } else {
                "0".into()
            },
            pol,
            format!(
                "{}{}",
                if r.may_miss { "MAY MISS: " } else { "ok: " },
                r.why
            ),
        ]);
    }
    let cols = rows[0].len();
    let widths: Vec<usize> = (0..cols)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    for r in &rows {
        let mut line = String::from("  ");
        for (c, (cell, w)) in r.iter().zip(&widths).enumerate() {
            if cell.is_empty() && *w == 0 {
                continue;
            }
            if (1..6).contains(&c) {
                let _ = write!(line, "{cell:>w$}  ");
            } else {
                let _ = write!(line, "{cell:<w$}  ");
            }
        }
        let _ = writeln!(out, "{}", line.trim_end());
    }
    let u = set.utilisation();
    let _ = writeln!(
        out,
        "  utilisation: {u:.3} of {} cores ({:.0} %), the world's {:.3}",
        set.cores,
        100.0 * u / f64::from(set.cores.max(1)),
        set.world_utilisation()
    );
    let _ = writeln!(out, "{} tests:", v.scheduler);
    for t in &v.set_tests {
        let _ = writeln!(out, "  {}: {}: {}", t.name, t.detail, t.conclusion.word());
    }
    let _ = writeln!(out, "  per robot: {}", v.robot_test);
    let miss = v.predicted_misses();
    let _ = writeln!(
        out,
        "predicted to miss: {}",
        if miss.is_empty() {
            "none".to_string()
        } else {
            format!(
                "{} of {} ({})",
                miss.len(),
                set.tasks.len(),
                miss.join(", ")
            )
        }
    );
    out
}

/// Predicted and measured misses side by side, per robot: the verdict's
/// prediction and the run's `deadline_misses` of `calls` planned calls,
/// then the set: how many robots were predicted to miss and how many did.
pub fn side_by_side(v: &Verdict, measured: &[(String, u64, u64)]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "predicted ({}) and measured misses:", v.scheduler);
    let w = v
        .robots
        .iter()
        .map(|r| r.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(out, "  {:<w$}  {:<9}  measured", "robot", "predicted");
    let mut agree = 0;
    let mut missed = 0;
    for r in &v.robots {
        let (misses, calls) = measured
            .iter()
            .find(|(n, _, _)| *n == r.name)
            .map(|(_, a, b)| (*a, *b))
            .unwrap_or((0, 0));
        if misses > 0 {
            missed += 1;
        }
        if (misses > 0) == r.may_miss {
            agree += 1;
        }
        let _ = writeln!(
            out,
            "  {:<w$}  {:<9}  {misses} of {calls}",
            r.name,
            if r.may_miss { "may miss" } else { "keeps" }
        );
    }
    let _ = writeln!(
        out,
        "  robots predicted to miss {}, measured to miss {}; the prediction matches {} of {} robots",
        v.predicted_misses().len(),
        missed,
        agree,
        v.robots.len()
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn task(name: &str, c_ms: u64, t_ms: u64, priority: u32) -> Task {
        Task {
            name: name.into(),
            cpu: true,
            c_ns: c_ms * MS,
            mean_ns: c_ms * MS,
            period_ns: t_ms * MS,
            deadline_ns: t_ms * MS,
            priority,
            priority_text: priority.to_string(),
            reservation: None,
        }
    }

    fn set(cores: u32, tasks: Vec<Task>) -> TaskSet {
        TaskSet {
            cores,
            own_cores: false,
            dt_ns: 100 * MS,
            world_ns: 0,
            tasks,
        }
    }

    /// `n` robots of `c_ms` CPU each 100 ms, rate-monotonic (ties by name).
    fn circle(cores: u32, n: usize, c_ms: u64) -> TaskSet {
        set(
            cores,
            (0..n)
                .map(|i| task(&format!("g{i:02}"), c_ms, 100, 1))
                .collect(),
        )
    }

    fn response(v: &Verdict, name: &str) -> Option<u64> {
        v.robots
            .iter()
            .find(|r| r.name == name)
            .and_then(|r| r.response_ns)
    }

    #[test]
    fn two_tasks_on_one_core_have_the_response_times_computed_by_hand() {
        // a: C 20, T 50 (higher); b: C 40, T 100. R_a = 20; R_b: 40 -> 40 +
        // 20 = 60 -> 40 + ceil(60/50) 20 = 80 -> 40 + ceil(80/50) 20 = 80.
        let s = set(1, vec![task("a", 20, 50, 2), task("b", 40, 100, 1)]);
        let v = fifo(&s);
        assert_eq!(response(&v, "a"), Some(20 * MS));
        assert_eq!(response(&v, "b"), Some(80 * MS));
        assert!(v.predicted_misses().is_empty());
    }

    #[test]
    fn a_lower_priority_task_that_cannot_finish_by_its_deadline_is_predicted_to_miss() {
        // b: 40 + 2 x 30 = 100 > D = 90 (its deadline shortened); U = 0.9,
        // under the real-time throttling's 0.95.
        let mut b = task("b", 40, 100, 1);
        b.deadline_ns = 90 * MS;
        let s = set(1, vec![task("a", 30, 60, 2), b]);
        let v = fifo(&s);
        assert_eq!(v.predicted_misses(), vec!["b"]);
    }

    #[test]
    fn a_rate_monotonic_set_under_the_liu_layland_bound_passes_it() {
        // U = 0.4 + 0.4 = 0.8 <= 2 (sqrt 2 - 1) = 0.828.
        let s = set(1, vec![task("a", 20, 50, 2), task("b", 40, 100, 1)]);
        let v = fifo(&s);
        assert_eq!(v.set_tests[1].conclusion, Conclusion::Holds);
        // U = 0.4 + 0.5 = 0.9 > 0.828: inconclusive, yet RTA shows it
        // schedulable (R_b = 50 + 2 x 20 = 90 <= 100).
        let s = set(1, vec![task("a", 20, 50, 2), task("b", 50, 100, 1)]);
        let v = fifo(&s);
        assert_eq!(v.set_tests[1].conclusion, Conclusion::Inconclusive);
        assert_eq!(response(&v, "b"), Some(90 * MS));
    }

    #[test]
    fn the_liu_layland_bound_does_not_apply_to_priorities_against_the_periods() {
        let s = set(1, vec![task("a", 20, 50, 1), task("b", 40, 100, 2)]);
        assert_eq!(fifo(&s).set_tests[1].conclusion, Conclusion::NotApplicable);
    }

    #[test]
    fn three_equal_tasks_on_two_cores_leave_the_third_waiting_for_one_call() {
        let v = fifo(&circle(2, 3, 20));
        assert_eq!(response(&v, "g00"), Some(20 * MS));
        assert_eq!(response(&v, "g01"), Some(20 * MS));
        assert_eq!(response(&v, "g02"), Some(40 * MS));
    }

    #[test]
    fn eight_robots_of_twenty_ms_on_two_cores_keep_every_deadline_under_each_scheduler() {
        let s = circle(2, 8, 20);
        for name in ["fair", "fifo", "deadline"] {
            let v = verdict(&s, name).expect("a scheduler");
            assert!(v.predicted_misses().is_empty(), "{name}: {v:?}");
        }
        // The last's bound: its window of x holds 7 x 20 ms of the others'
        // calls without carry-in and one carried in, x = 20 + (140 + 19.999) / 2.
        assert_eq!(response(&fifo(&s), "g07"), Some(99_999_000));
    }

    #[test]
    fn a_set_over_the_cores_fails_the_necessary_test_under_every_scheduler() {
        // 12 x 0.2 = 2.4 > 2.
        let s = circle(2, 12, 20);
        for name in ["fair", "fifo", "deadline"] {
            let v = verdict(&s, name).expect("a scheduler");
            assert_eq!(v.set_tests[0].conclusion, Conclusion::Fails, "{name}");
            assert!(!v.predicted_misses().is_empty(), "{name}");
        }
        // Under fair every call ends at 12 x 20 / 2 = 120 ms > 100.
        let v = fair(&s);
        assert_eq!(v.predicted_misses().len(), 12);
        assert_eq!(response(&v, "g00"), Some(120 * MS));
        // Under fifo the response-time bound still clears the first robots
        // in priority order on whole cores, but U > 0.95 m: Linux's
        // real-time throttling may make any of them late.
        let v = fifo(&s);
        assert!(v.robots[0].response_ns.is_some() && v.robots[11].response_ns.is_none());
        assert!(v.robots.iter().all(|r| r.may_miss));
        let throttling = v.set_tests.iter().find(|t| t.name.contains("throttling"));
        assert_eq!(throttling.map(|t| t.conclusion), Some(Conclusion::Fails));
    }

    #[test]
    fn dhall_s_set_passes_u_below_m_and_fails_gfb_with_the_heavy_task_predicted() {
        // m = 2 light tasks (2 ms every 100 ms) and one heavy (100 ms every
        // 101 ms): U = 0.04 + 0.990 = 1.030 <= 2, GFB 2 - 0.990 = 1.010.
        let s = set(
            2,
            vec![
                task("heavy", 100, 101, 1),
                task("light0", 2, 100, 1),
                task("light1", 2, 100, 1),
            ],
        );
        let v = deadline(&s);
        assert_eq!(v.set_tests[0].conclusion, Conclusion::Holds);
        assert_eq!(v.set_tests[1].conclusion, Conclusion::Inconclusive);
        assert_eq!(v.predicted_misses(), vec!["heavy"]);
    }

    #[test]
    fn a_set_under_the_gfb_bound_keeps_every_deadline_under_deadline() {
        // U = 4 x 0.3 = 1.2 <= 2 - 0.3 = 1.7.
        let v = deadline(&circle(2, 4, 30));
        assert_eq!(v.set_tests[1].conclusion, Conclusion::Holds);
        assert!(v.predicted_misses().is_empty());
    }

    #[test]
    fn a_reservation_confines_an_overrunning_robot_and_the_others_keep_their_deadlines() {
        // Seven robots of 20 ms reserved 20 ms every 100 ms, one of 90 ms
        // reserved the same: the servers' U = 8 x 0.2 = 1.6 <= 2 - 0.2, and
        // only the overrunning robot is throttled.
        let mut s = circle(2, 8, 20);
        s.tasks[3].c_ns = 90 * MS;
        s.tasks[3].mean_ns = 90 * MS;
        for t in &mut s.tasks {
            t.reservation = Some((20 * MS, 100 * MS));
        }
        let v = deadline(&s);
        assert_eq!(v.predicted_misses(), vec!["g03"]);
        assert!(v.robots[3].why.contains("throttled"), "{}", v.robots[3].why);
    }

    #[test]
    fn on_one_core_a_reservation_keeps_the_deadlines_that_processor_sharing_loses() {
        // Four robots of 22 ms reserved 22 / 100 ms and one that would run
        // 150 ms reserved 10 / 100: U = 0.88 + 0.10 = 0.98 <= 1, only the
        // overrunning robot is throttled. Sharing the core equally, the
        // four end their calls at 5 x 22 = 110 ms > 100.
        let mut s = circle(1, 5, 22);
        for t in &mut s.tasks {
            t.reservation = Some((22 * MS, 100 * MS));
        }
        s.tasks[4].c_ns = 150 * MS;
        s.tasks[4].mean_ns = 150 * MS;
        s.tasks[4].reservation = Some((10 * MS, 100 * MS));
        assert_eq!(deadline(&s).predicted_misses(), vec!["g04"]);
        let f = fair(&s);
        assert_eq!(f.predicted_misses().len(), 5);
        assert_eq!(response(&f, "g00"), Some(110 * MS));
    }

    #[test]
    fn the_world_s_cpu_counts_as_the_highest_priority_task() {
        // One core, the world 30 ms each 100 ms tick, a robot of 60 ms:
        // R = 60 + 30 = 90 <= 100; 80 ms would be 110 > 100.
        let mut s = set(1, vec![task("a", 60, 100, 1)]);
        s.world_ns = 30 * MS;
        assert_eq!(response(&fifo(&s), "a"), Some(90 * MS));
        s.tasks[0].c_ns = 80 * MS;
        assert_eq!(fifo(&s).predicted_misses(), vec!["a"]);
        // Under fair the world holds the one core for 30 ms first.
        assert_eq!(response(&fair(&s), "a"), Some(110 * MS));
    }

    #[test]
    fn a_robot_that_waits_takes_no_cpu_and_misses_only_when_its_wait_is_too_long() {
        let mut s = circle(1, 2, 60);
        s.tasks[1].cpu = false;
        let v = fifo(&s);
        assert!(v.predicted_misses().is_empty());
        s.tasks[1].c_ns = 150 * MS;
        assert_eq!(fifo(&s).predicted_misses(), vec!["g01"]);
    }

    #[test]
    fn the_rendered_verdict_names_the_tests_and_the_robots_predicted_to_miss() {
        let s = circle(2, 12, 20);
        let v = fifo(&s);
        let text = render(&s, &v);
        assert!(text.contains("U = 2.400 > 2"), "{text}");
        assert!(text.contains("Guan, Stigge, Yi & Yu 2009"), "{text}");
        assert!(text.contains("predicted to miss: "), "{text}");
        assert!(text.contains("g11"), "{text}");
        let measured: Vec<(String, u64, u64)> = (0..12)
            .map(|i| (format!("g{i:02}"), u64::from(i >= 10) * 100, 100))
            .collect();
        let side = side_by_side(&v, &measured);
        assert!(side.contains("measured to miss 2"), "{side}");
    }

    const SCENE: &str = r#"
[world]
dt = 0.1
deadline = 0.8
[world.cpus]
count = 2
scheduler = "fifo"
world_ms = 1.0
[defaults.timing]
compute = { ms = 20, cpu = true }
[[robot]]
name = "b"
start = [0, 0]
goal = [1, 0]
[robot.timing]
period_ticks = 2
compute = { model = "uniform", min_ms = 10, max_ms = 30, cpu = true }
[[robot]]
name = "a"
start = [0, 2]
goal = [1, 2]
[robot.timing]
priority = 50
[[robot]]
name = "c"
start = [0, 4]
goal = [1, 4]
[robot.timing]
compute = { model = "lognormal", median_ms = 10, sigma = 0.5, cpu = false }
"#;

    #[test]
    fn a_scenario_s_robots_become_tasks_in_name_order_with_their_model_s_c_t_and_d() {
        let l = crate::parse(SCENE, "scene.toml").expect("a valid scene");
        let (s, scheduler) = task_set(&l.scenario).expect("a task set");
        assert_eq!(scheduler, "fifo");
        assert_eq!((s.cores, s.world_ns, s.dt_ns), (2, MS, 100 * MS));
        let names: Vec<&str> = s.tasks.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["a", "b", "c"]);
        let (a, b, c) = (&s.tasks[0], &s.tasks[1], &s.tasks[2]);
        assert_eq!(
            (a.c_ns, a.period_ns, a.deadline_ns),
            (20 * MS, 100 * MS, 80 * MS)
        );
        assert_eq!(a.priority, 50);
        // Uniform: C its maximum, the mean its middle; two ticks a period.
        assert_eq!(
            (b.c_ns, b.mean_ns, b.period_ns),
            (30 * MS, 20 * MS, 200 * MS)
        );
        // Rate-monotonic: the longer period ranks below the one-tick ones.
        assert_eq!(b.priority, 98);
        // A wait: no CPU; C its 99th percentile, 10 e^(2.326 x 0.5) ms.
        assert!(!c.cpu);
        assert_eq!(c.c_ns, crate::timing::ms_to_ns(10.0 * (Z99 * 0.5).exp()));
        assert_eq!(c.priority, 99);
    }

    #[test]
    fn a_scenario_without_cores_or_cpu_work_has_no_task_set() {
        let plain = SCENE
            .replace(
                "[world.cpus]\ncount = 2\nscheduler = \"fifo\"\nworld_ms = 1.0\n",
                "",
            )
            .replace(", cpu = true", "");
        let l = crate::parse(&plain, "plain.toml").expect("a valid scene");
        assert!(task_set(&l.scenario).is_none());
        // CPU work without [world.cpus]: a core of its own per CPU robot.
        let own = SCENE.replace(
            "[world.cpus]\ncount = 2\nscheduler = \"fifo\"\nworld_ms = 1.0\n",
            "",
        );
        let l = crate::parse(&own, "own.toml").expect("a valid scene");
        let (s, scheduler) = task_set(&l.scenario).expect("a task set");
        assert_eq!((s.cores, s.own_cores, scheduler), (2, true, "fair"));
        assert!(fair(&s).predicted_misses().is_empty());
    }
}
