//! A deterministic discrete-event model of the cores the planners' CPU
//! work shares (`[world.cpus]`): `m` cores, one job at a time per robot
//! (the CPU work of one planner call), integer nanoseconds, no clock.
//!
//! - `fair`: processor sharing, the idealised share of Linux's SCHED_OTHER
//!   (CFS/EEVDF at equal weights): `n` runnable jobs on `c` free cores each
//!   progress at min(1, c/n). Service is counted in whole ns, rounded down
//!   at each event (a job loses less than 1 ns per event).
//! - `fifo`: global fixed-priority preemptive scheduling (SCHED_FIFO over
//!   every core): the `c` runnable jobs of highest priority run. Priority:
//!   the higher [`Priority::Level`] first; equal levels by robot name. A
//!   robot without a level, or with [`Priority::RateMonotonic`], is
//!   rate-monotonic: its level is `99 - r`, `r` the rank of its
//!   `period_ticks` among the rate-monotonic robots' distinct periods
//!   (shortest 0), at least 1 ([`fifo_levels`]): shorter periods first,
//!   equal periods by name. (Linux orders equal SCHED_FIFO levels by
//!   arrival instead; the model's order by name keeps it deterministic.)
//! - `deadline`: global EDF over constant-bandwidth servers, as
//!   SCHED_DEADLINE (Abeni & Buttazzo 1998; the kernel's
//!   Documentation/scheduler/sched-deadline.rst): each robot's server has a
//!   runtime `Q` per period `P` and a scheduling deadline `d`, its remaining
//!   runtime `q`; the `c` eligible servers of earliest `d` run (equal
//!   deadlines by robot name), each consuming `q` as it runs. A job that
//!   arrives at an idle server at time `t` resets it (`d = t + P`, `q = Q`)
//!   if `d <= t` or `q / (d - t) > Q / P` (the wake-up rule), else it
//!   keeps `q` and `d`; a planner that reads its next snapshot as it
//!   finishes does not sleep, so that job keeps the server as it is. A
//!   server whose `q` reaches 0 is throttled until `d`; then `d += P`, `q =
//!   Q` (replenishment). Simplifications: the relative deadline is the
//!   period; no reclaiming (GRUB), no admission test (the realtime side
//!   makes the kernel's); the kernel's push/pull migration is idealised as
//!   one global queue.
//! - `world_ms`: the world's own CPU each tick, released at the tick's
//!   start (see [`Cores::world_tick`]) above every agent: while it runs it
//!   takes one of the cores (`c = m - 1`).
//!
//! Cost: each event (a release, a completion, a budget used up, a
//! replenishment, the world's work done) costs O(n) in the jobs the model
//! holds, with no allocation once its buffers have grown.

use crate::timing::{Priority, Reservation};
use crate::types::{Cpus, Scheduler};

/// One robot's part in the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// The robot's name (equal priorities and deadlines are ordered by it).
    pub name: String,
    /// Its `timing.period_ticks` (rate-monotonic priorities).
    pub period_ticks: u32,
    /// Its `timing.priority` (fifo); `None` is rate-monotonic.
    pub priority: Option<Priority>,
    /// Its `timing.reservation` (deadline; needed there).
    pub reservation: Option<Reservation>,
}

/// Why a model cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CoresError {
    /// Under `deadline`, a task without a reservation.
    #[error("robot `{0}` has no timing.reservation, which scheduler \"deadline\" needs")]
    NoReservation(String),
    /// `count` is 0.
    #[error("[world.cpus] count must be >= 1")]
    NoCores,
}

/// The end of a job's CPU work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Done {
    /// The task's index.
    pub task: usize,
    /// The tag the job was released with (the tick of the snapshot read).
    pub tag: u64,
    /// When it ended, ns.
    pub at_ns: u64,
}

#[derive(Debug, Clone, Copy)]
struct Job {
    left: u64,
    tag: u64,
}

/// A constant-bandwidth server's state.
#[derive(Debug, Clone, Copy)]
struct Server {
    runtime: u64,
    period: u64,
    /// Remaining runtime `q`.
    budget: u64,
    /// Scheduling deadline `d`.
    deadline: u64,
    /// Throttled until `deadline` (its budget used up).
    throttled: bool,
}

#[derive(Debug, Clone)]
struct Slot {
    /// Order of equal priorities and deadlines: the rank of the name.
    rank: u32,
    /// fifo level, higher first.
    level: u8,
    server: Option<Server>,
    job: Option<Job>,
}

/// The model: the cores, every task's job and server, and the time.
#[derive(Debug, Clone)]
pub struct Cores {
    cores: u32,
    scheduler: Scheduler,
    world_ns: u64,
    world_left: u64,
    now: u64,
    slots: Vec<Slot>,
    /// Reused: the indices of the jobs that run, and candidates.
    running: Vec<usize>,
    candidates: Vec<usize>,
}

/// The SCHED_FIFO level of every task (1..=99): its own
/// [`Priority::Level`], or rate-monotonic (see the module's doc).
pub fn fifo_levels(tasks: &[Task]) -> Vec<u8> {
    let is_rm = |t: &Task| !matches!(t.priority, Some(Priority::Level(_)));
    let mut periods: Vec<u32> = tasks
        .iter()
        .filter(|t| is_rm(t))
        .map(|t| t.period_ticks)
        .collect();
    periods.sort_unstable();
    periods.dedup();
    tasks
        .iter()
        .map(|t| match t.priority {
            Some(Priority::Level(l)) => l,
            _ => {
                let r = periods.partition_point(|&p| p < t.period_ticks);
                99u8.saturating_sub(u8::try_from(r).unwrap_or(u8::MAX))
                    .max(1)
            }
        })
        .collect()
}

impl Cores {
    /// The model of `cpus` for `tasks` (indexed as given), at time 0.
    pub fn new(cpus: &Cpus, tasks: &[Task]) -> Result<Self, CoresError> {
        if cpus.count == 0 {
            return Err(CoresError::NoCores);
        }
        let mut by_name: Vec<usize> = (0..tasks.len()).collect();
        by_name.sort_by(|&a, &b| tasks[a].name.cmp(&tasks[b].name).then(a.cmp(&b)));
        let mut rank = vec![0u32; tasks.len()];
        for (r, &i) in by_name.iter().enumerate() {
            rank[i] = r as u32;
        }
        let levels = fifo_levels(tasks);
        let mut slots = Vec::with_capacity(tasks.len());
        for (i, t) in tasks.iter().enumerate() {
            let server = match (cpus.scheduler, t.reservation) {
                (Scheduler::Deadline, None) => {
                    return Err(CoresError::NoReservation(t.name.clone()));
                }
                (Scheduler::Deadline, Some(r)) => Some(Server {
                    runtime: r.runtime_ns().max(1),
                    period: r.period_ns().max(1),
                    budget: 0,
                    deadline: 0,
                    throttled: false,
                }),
                _ => None,
            };
            slots.push(Slot {
                rank: rank[i],
                level: levels[i],
                server,
                job: None,
            });
        }
        Ok(Self {
            cores: cpus.count,
            scheduler: cpus.scheduler,
            world_ns: crate::timing::ms_to_ns(cpus.world_ms),
            world_left: 0,
            now: 0,
            slots,
            running: Vec::new(),
            candidates: Vec::new(),
        })
    }

    /// The model's time, ns.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// True if task `task` has a job (released, not yet done).
    pub fn busy(&self, task: usize) -> bool {
        self.slots[task].job.is_some()
    }

    /// The world's CPU of one tick (`world_ms`) is released now.
    pub fn world_tick(&mut self) {
        self.world_left += self.world_ns;
    }

    /// Releases a job of `demand_ns` CPU for task `task` now, tagged `tag`
    /// (the task must be free: a job it still has is replaced). A job of
    /// no demand ends at once, at the next [`Cores::run_until`].
    pub fn release(&mut self, task: usize, demand_ns: u64, tag: u64) {
        self.arrive(task, demand_ns, tag, true);
    }

    fn arrive(&mut self, task: usize, demand_ns: u64, tag: u64, woke: bool) {
        let now = self.now;
        let slot = &mut self.slots[task];
        slot.job = Some(Job {
            left: demand_ns,
            tag,
        });
        if let Some(s) = slot.server.as_mut()
            && woke
            && !s.throttled
        {
            // The wake-up rule: q / (d - t) > Q / P, in integers.
            let reset = s.deadline <= now
                || u128::from(s.budget) * u128::from(s.period)
                    > u128::from(s.runtime) * u128::from(s.deadline - now);
            if reset {
                s.deadline = now + s.period;
                s.budget = s.runtime;
            }
        }
    }

    /// The cores free for agents now.
    fn agent_cores(&self) -> usize {
        let m = self.cores as usize;
        if self.world_left > 0 { m - 1 } else { m }
    }

    /// Fills `running` with the jobs that run now; returns the number of
    /// runnable jobs (fair shares the cores among them all).
    fn choose(&mut self) -> usize {
        let c = self.agent_cores();
        self.running.clear();
        self.candidates.clear();
        for (i, s) in self.slots.iter().enumerate() {
            if s.job.is_some() && s.server.is_none_or(|v| !v.throttled) {
                self.candidates.push(i);
            }
        }
        let n = self.candidates.len();
        match self.scheduler {
            Scheduler::Fair => self.running.extend_from_slice(&self.candidates),
            Scheduler::Fifo | Scheduler::Deadline => {
                let slots = &self.slots;
                let key = |i: usize| {
                    let s = &slots[i];
                    match s.server {
                        Some(v) => (v.deadline, s.rank),
                        None => (u64::from(99 - s.level.min(99)), s.rank),
                    }
                };
                if n > c && c > 0 {
                    self.candidates
                        .select_nth_unstable_by_key(c - 1, |&i| key(i));
                }
                let take = n.min(c);
                self.running.extend_from_slice(&self.candidates[..take]);
            }
        }
        n
    }

    /// Runs the model to `until_ns` (not past it). Each job that ends is
    /// handed to `done`, at its time; `done` may answer a new job for the
    /// same task (demand, tag), released then, without a wake-up (the
    /// planner goes straight on to its next snapshot).
    pub fn run_until(&mut self, until_ns: u64, mut done: impl FnMut(Done) -> Option<(u64, u64)>) {
        loop {
            let n = self.choose();
            let c = self.agent_cores();
            let fair_shared = self.scheduler == Scheduler::Fair && n > c;
            // The next event, as time from now.
            let mut step = until_ns.saturating_sub(self.now);
            if self.world_left > 0 {
                step = step.min(self.world_left);
            }
            for &i in &self.running {
                let s = &self.slots[i];
                let Some(job) = s.job else { continue };
                let to_end = if fair_shared {
                    if c == 0 {
                        u64::MAX
                    } else {
                        let t = (u128::from(job.left) * n as u128).div_ceil(c as u128);
                        u64::try_from(t).unwrap_or(u64::MAX)
                    }
                } else {
                    job.left
                };
                step = step.min(to_end);
                if let Some(v) = s.server {
                    step = step.min(v.budget);
                }
            }
            for s in &self.slots {
                if let Some(v) = s.server
                    && v.throttled
                {
                    step = step.min(v.deadline.saturating_sub(self.now));
                }
            }
            // Advance.
            let served = if fair_shared {
                if c == 0 {
                    0
                } else {
                    u64::try_from(u128::from(step) * c as u128 / n as u128).unwrap_or(u64::MAX)
                }
            } else {
                step
            };
            self.world_left -= step.min(self.world_left);
            for &i in &self.running {
                let s = &mut self.slots[i];
                if let Some(job) = s.job.as_mut() {
                    job.left -= served.min(job.left);
                }
                if let Some(v) = s.server.as_mut() {
                    v.budget -= step.min(v.budget);
                }
            }
            self.now += step;
            let now = self.now;
            // Replenishments.
            for s in &mut self.slots {
                if let Some(v) = s.server.as_mut()
                    && v.throttled
                    && v.deadline <= now
                {
                    v.throttled = false;
                    v.deadline += v.period;
                    v.budget = v.runtime;
                }
            }
            // Budgets used up by running: throttled until the deadline
            // (even if the job ends now, as the kernel does).
            for &i in &self.running {
                if let Some(v) = self.slots[i].server.as_mut()
                    && v.budget == 0
                {
                    v.throttled = true;
                }
            }
            // Completions, in task order.
            for i in 0..self.slots.len() {
                let Some(job) = self.slots[i].job else {
                    continue;
                };
                if job.left == 0 {
                    self.slots[i].job = None;
                    if let Some((demand, tag)) = done(Done {
                        task: i,
                        tag: job.tag,
                        at_ns: now,
                    }) {
                        self.arrive(i, demand, tag, false);
                    }
                }
            }
            if now >= until_ns
                && !self
                    .slots
                    .iter()
                    .any(|s| s.job.is_some_and(|j| j.left == 0))
            {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests;
