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
//!   rate-monotonic: its level is `99 - r`, `r` its rank among the
//!   rate-monotonic robots by `period_ticks` (shortest 0), equal periods
//!   by name, at least 1 ([`fifo_levels`]): a level of its own, so that
//!   the kernel, which runs equal SCHED_FIFO levels in the order they
//!   became runnable, runs them in the model's order too (for the first
//!   98; the rest share level 1). Equal levels given by hand are ordered
//!   by name in the model, by arrival in the kernel.
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
//! - Real-time throttling (`fifo`): Linux lets SCHED_FIFO tasks use at most
//!   `sched_rt_runtime_us` of every `sched_rt_period_us` on each core (95 %
//!   of each second by default), then runs none of them until the window
//!   ends, so a set that keeps both cores busy loses 50 ms a second. The
//!   model does the same with the defaults ([`RT_RUNTIME_NS`] per core
//!   every [`RT_PERIOD_NS`], windows from time 0; the kernel's are aligned
//!   to its own clock), over the agents' and the world's work summed over
//!   the cores. SCHED_DEADLINE and SCHED_OTHER tasks are not throttled so.
//!
//! Cost: each event (a release, a completion, a budget used up, a
//! replenishment, the world's work done) costs O(log n) in the tasks the
//! model holds (O(m + log n) under `fifo` and `deadline`, whose `m` first
//! ready jobs run); the ready queue's nodes aside, no allocation once its
//! buffers have grown.

use crate::timing::{Priority, Reservation};
use crate::types::{Cpus, Scheduler};
use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

/// Linux's real-time bandwidth window (`/proc/sys/kernel/sched_rt_period_us`
/// by default), ns: under `fifo` the model throttles as the kernel does.
pub const RT_PERIOD_NS: u64 = 1_000_000_000;
/// What SCHED_FIFO tasks may use of each core per window
/// (`sched_rt_runtime_us` by default: 95 %), ns.
pub const RT_RUNTIME_NS: u64 = 950_000_000;

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
    /// fifo and deadline: its key in the ready queue while it is there.
    ready: Option<u64>,
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
    /// Reused: the indices of the jobs that run.
    running: Vec<usize>,
    /// fifo and deadline: the runnable jobs by (key, rank, index), the
    /// first running; the throttled servers by the deadline they wait for;
    /// the tasks released with no demand since the last completions.
    ready: BTreeSet<(u64, u32, usize)>,
    throttled: BinaryHeap<Reverse<(u64, usize)>>,
    zero: Vec<usize>,
    /// fifo: the real-time bandwidth left in the current window (summed
    /// over the cores), and the window's end ([`RT_PERIOD_NS`]).
    rt_left: u64,
    rt_window_end: u64,
    /// `fair`: the service every runnable job has had since time 0 (all
    /// progress alike), and each job's end in that service, earliest
    /// first (ties by task index).
    service: u128,
    ends: BinaryHeap<Reverse<(u128, usize)>>,
    ended: Vec<usize>,
}

/// The SCHED_FIFO level of every task (1..=99): its own
/// [`Priority::Level`], or rate-monotonic (see the module's doc).
pub fn fifo_levels(tasks: &[Task]) -> Vec<u8> {
    let is_rm = |t: &Task| !matches!(t.priority, Some(Priority::Level(_)));
    // The rate-monotonic tasks by period, equal periods by name: each a
    // level of its own, so the kernel runs them in the model's order.
    let mut rm: Vec<usize> = (0..tasks.len()).filter(|&i| is_rm(&tasks[i])).collect();
    rm.sort_by(|&a, &b| {
        (tasks[a].period_ticks, &tasks[a].name, a).cmp(&(tasks[b].period_ticks, &tasks[b].name, b))
    });
    let mut levels: Vec<u8> = tasks
        .iter()
        .map(|t| match t.priority {
            Some(Priority::Level(l)) => l,
            _ => 1,
        })
        .collect();
    for (r, &i) in rm.iter().enumerate() {
        levels[i] = 99u8
            .saturating_sub(u8::try_from(r).unwrap_or(u8::MAX))
            .max(1);
    }
    levels
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
                ready: None,
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
            ready: BTreeSet::new(),
            throttled: BinaryHeap::new(),
            zero: Vec::new(),
            rt_left: u64::from(cpus.count) * RT_RUNTIME_NS,
            rt_window_end: RT_PERIOD_NS,
            service: 0,
            ends: BinaryHeap::new(),
            ended: Vec::new(),
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
        if self.scheduler == Scheduler::Fair {
            self.ends
                .push(Reverse((self.service + u128::from(demand_ns), task)));
        }
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
        if self.scheduler != Scheduler::Fair {
            // A job replaced keeps no place in the queue of the one before.
            self.unready(task);
            if self.slots[task].server.is_none_or(|v| !v.throttled) {
                self.make_ready(task);
            }
            if demand_ns == 0 {
                self.zero.push(task);
            }
        }
    }

    /// The cores free for agents now.
    fn agent_cores(&self) -> usize {
        let m = self.cores as usize;
        if self.world_left > 0 { m - 1 } else { m }
    }

    /// fifo and deadline: the order of slot `i` among the runnable, the
    /// first running first: its server's deadline, or 99 minus its level;
    /// equal keys by the rank of the name.
    fn key(&self, i: usize) -> (u64, u32) {
        let s = &self.slots[i];
        match s.server {
            Some(v) => (v.deadline, s.rank),
            None => (u64::from(99 - s.level.min(99)), s.rank),
        }
    }

    /// fifo and deadline: slot `i` becomes runnable (a job, its server not
    /// throttled) and joins the ready queue.
    fn make_ready(&mut self, i: usize) {
        if self.scheduler == Scheduler::Fair || self.slots[i].ready.is_some() {
            return;
        }
        let (key, rank) = self.key(i);
        self.slots[i].ready = Some(key);
        self.ready.insert((key, rank, i));
    }

    /// fifo and deadline: slot `i` leaves the ready queue (its job ended,
    /// or its server was throttled).
    fn unready(&mut self, i: usize) {
        if let Some(key) = self.slots[i].ready.take() {
            self.ready.remove(&(key, self.slots[i].rank, i));
        }
    }

    /// Runs the model to `until_ns` (not past it). Each job that ends is
    /// handed to `done`, at its time; `done` may answer a new job for the
    /// same task (demand, tag), released then, without a wake-up (the
    /// planner goes straight on to its next snapshot).
    ///
    /// fifo and deadline: the runnable jobs are held in order (a
    /// [`BTreeSet`] of their keys) and the throttled servers by deadline
    /// (a heap), so an event costs O(m + log n): the `c` first of the
    /// queue run, the next event is the earliest of their ends and budgets
    /// and the first replenishment, and only they can end or use up their
    /// budget. It decides exactly as the scan over every task it replaces
    /// (a test holds the two together).
    pub fn run_until(&mut self, until_ns: u64, mut done: impl FnMut(Done) -> Option<(u64, u64)>) {
        if self.scheduler == Scheduler::Fair {
            return self.run_fair(until_ns, done);
        }
        let fifo = self.scheduler == Scheduler::Fifo;
        loop {
            // fifo: a new window of real-time bandwidth.
            if fifo && self.now >= self.rt_window_end {
                let behind = (self.now - self.rt_window_end) / RT_PERIOD_NS + 1;
                self.rt_window_end += behind * RT_PERIOD_NS;
                self.rt_left = u64::from(self.cores) * RT_RUNTIME_NS;
            }
            // Throttled (fifo, the window's bandwidth used up): nothing of
            // the world's or the agents' runs until the window ends.
            let throttled = fifo && self.rt_left == 0;
            // The c first of the ready queue run.
            let c = self.agent_cores();
            self.running.clear();
            if !throttled {
                self.running
                    .extend(self.ready.iter().take(c).map(|&(_, _, i)| i));
            }
            let world_runs = self.world_left > 0 && !throttled;
            // The next event, as time from now.
            let mut step = until_ns.saturating_sub(self.now);
            if world_runs {
                step = step.min(self.world_left);
            }
            let in_use = (self.running.len() + usize::from(world_runs)) as u64;
            // The window's end matters only to work that runs or waits
            // for it: idle cores step straight to the next event.
            if fifo && (in_use > 0 || throttled) {
                step = step.min(self.rt_window_end - self.now);
                if in_use > 0 {
                    step = step.min(self.rt_left.div_ceil(in_use));
                }
            }
            if !self.zero.is_empty() {
                step = 0;
            }
            for &i in &self.running {
                let s = &self.slots[i];
                if let Some(job) = s.job {
                    step = step.min(job.left);
                }
                if let Some(v) = s.server {
                    step = step.min(v.budget);
                }
            }
            if let Some(&Reverse((d, _))) = self.throttled.peek() {
                step = step.min(d.saturating_sub(self.now));
            }
            // Advance.
            if world_runs {
                self.world_left -= step.min(self.world_left);
            }
            if fifo {
                self.rt_left = self.rt_left.saturating_sub(step.saturating_mul(in_use));
            }
            for &i in &self.running {
                let s = &mut self.slots[i];
                if let Some(job) = s.job.as_mut() {
                    job.left -= step.min(job.left);
                }
                if let Some(v) = s.server.as_mut() {
                    v.budget -= step.min(v.budget);
                }
            }
            self.now += step;
            let now = self.now;
            // Replenishments.
            while let Some(&Reverse((d, i))) = self.throttled.peek()
                && d <= now
            {
                self.throttled.pop();
                if let Some(v) = self.slots[i].server.as_mut() {
                    v.throttled = false;
                    v.deadline += v.period;
                    v.budget = v.runtime;
                }
                if self.slots[i].job.is_some() {
                    self.make_ready(i);
                }
            }
            // Budgets used up by running: throttled until the deadline
            // (even if the job ends now, as the kernel does).
            for k in 0..self.running.len() {
                let i = self.running[k];
                if let Some(v) = self.slots[i].server
                    && v.budget == 0
                    && !v.throttled
                {
                    self.unready(i);
                    if let Some(v) = self.slots[i].server.as_mut() {
                        v.throttled = true;
                    }
                    self.throttled.push(Reverse((v.deadline, i)));
                }
            }
            // Completions, in task order: the running jobs done, and the
            // jobs of no demand (which end at once, running or not).
            self.ended.clear();
            self.ended.append(&mut self.zero);
            for &i in &self.running {
                if self.slots[i].job.is_some_and(|j| j.left == 0) {
                    self.ended.push(i);
                }
            }
            self.ended.sort_unstable();
            self.ended.dedup();
            for k in 0..self.ended.len() {
                let i = self.ended[k];
                let Some(job) = self.slots[i].job.filter(|j| j.left == 0) else {
                    continue;
                };
                self.slots[i].job = None;
                self.unready(i);
                if let Some((demand, tag)) = done(Done {
                    task: i,
                    tag: job.tag,
                    at_ns: now,
                }) {
                    self.arrive(i, demand, tag, false);
                }
            }
            if now >= until_ns && self.zero.is_empty() {
                return;
            }
        }
    }
}

impl Cores {
    /// [`Cores::run_until`] under `fair`: every runnable job has the same
    /// service, so the next to end is the one whose end in service comes
    /// first (O(log n) per event).
    fn run_fair(&mut self, until_ns: u64, mut done: impl FnMut(Done) -> Option<(u64, u64)>) {
        loop {
            let n = self.ends.len() as u128;
            let c = self.agent_cores() as u128;
            let mut step = until_ns.saturating_sub(self.now);
            if self.world_left > 0 {
                step = step.min(self.world_left);
            }
            if let Some(&Reverse((end, _))) = self.ends.peek() {
                let left = end.saturating_sub(self.service);
                let to_end = if n <= c {
                    left
                } else if c == 0 {
                    u128::MAX
                } else {
                    (left * n).div_ceil(c)
                };
                step = step.min(u64::try_from(to_end).unwrap_or(u64::MAX));
            }
            let served = if n <= c {
                u128::from(step)
            } else if c == 0 {
                0
            } else {
                u128::from(step) * c / n
            };
            self.world_left -= step.min(self.world_left);
            if n > 0 {
                self.service += served;
            }
            self.now += step;
            self.ended.clear();
            while let Some(&Reverse((end, i))) = self.ends.peek()
                && end <= self.service
            {
                self.ends.pop();
                self.ended.push(i);
            }
            for k in 0..self.ended.len() {
                let i = self.ended[k];
                let Some(job) = self.slots[i].job.take() else {
                    continue;
                };
                if let Some((demand, tag)) = done(Done {
                    task: i,
                    tag: job.tag,
                    at_ns: self.now,
                }) {
                    self.arrive(i, demand, tag, false);
                }
            }
            let due = self
                .ends
                .peek()
                .is_some_and(|&Reverse((end, _))| end <= self.service);
            if self.now >= until_ns && !due {
                return;
            }
        }
    }
}

/// One planner call's command as the cores' model sends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoreSend {
    /// The robot (its index in the scenario).
    pub robot: usize,
    /// The tick of the snapshot it read, which the command answers.
    pub tick: u64,
    /// When it is sent, ns after that tick's publication.
    pub sent_ns: u64,
    /// The CPU work of the call, ns.
    pub cpu_ns: u64,
    /// Lost on its way (`command_loss`).
    pub lost: bool,
}

#[derive(Debug, Clone)]
struct Member {
    robot: usize,
    timing: crate::timing::Timing,
    /// The demand of the job it runs.
    demand: u64,
}

/// The world's side of the cores in lockstep: which robots whose compute
/// is CPU work (`cpu = true`) read each tick's snapshot, and when their
/// commands are sent, from the [`Cores`] model over every such robot.
///
/// Tick `k` covers [k dt, (k+1) dt): at its start the world's own CPU is
/// released, and every member that is free and plans at `k` (its period,
/// its snapshot not lost) reads snapshot `k`; a member whose job ends
/// inside the tick sends then and, if it read an earlier snapshot, reads
/// snapshot `k` at once (the newest it has not seen), as
/// [`crate::timing::Clerk`] does alone. A job that ends exactly at the
/// tick's end reads the next snapshot at its start.
#[derive(Debug, Clone)]
pub struct Contention {
    cores: Cores,
    members: Vec<Member>,
    /// Member of each scenario robot.
    member_of: Vec<Option<usize>>,
    seed: u64,
    dt_ns: u64,
    /// Which scenario robots read the current tick's snapshot.
    reads: Vec<bool>,
    sends: Vec<CoreSend>,
}

impl Contention {
    /// The model of `scenario`'s cores, if it has `[world.cpus]`, runs in
    /// lockstep and has a robot with `cpu = true` (a robot replaying a
    /// record keeps it).
    pub fn of(scenario: &crate::Scenario) -> Result<Option<Self>, CoresError> {
        let w = &scenario.world;
        let Some(cpus) = &w.cpus else {
            return Ok(None);
        };
        if w.mode != crate::Mode::Lockstep {
            return Ok(None);
        }
        let mut members = Vec::new();
        let mut tasks = Vec::new();
        let mut member_of = vec![None; scenario.robots.len()];
        for (i, r) in scenario.robots.iter().enumerate() {
            let Some(t) = r.timing.as_ref().filter(|t| t.cpu && r.replay.is_none()) else {
                continue;
            };
            member_of[i] = Some(members.len());
            tasks.push(Task {
                name: r.name.clone(),
                period_ticks: t.period_ticks,
                priority: t.priority,
                reservation: t.reservation,
            });
            members.push(Member {
                robot: i,
                timing: t.clone(),
                demand: 0,
            });
        }
        if members.is_empty() {
            return Ok(None);
        }
        Ok(Some(Self {
            cores: Cores::new(cpus, &tasks)?,
            members,
            member_of,
            seed: w.seed,
            dt_ns: crate::timing::s_to_ns(w.dt).max(1),
            reads: vec![false; scenario.robots.len()],
            sends: Vec::new(),
        }))
    }

    /// True if scenario robot `robot` is timed by the model.
    pub fn has(&self, robot: usize) -> bool {
        self.member_of.get(robot).is_some_and(Option::is_some)
    }

    /// The robot's timing, if it is timed by the model.
    pub fn timing(&self, robot: usize) -> Option<&crate::timing::Timing> {
        let m = (*self.member_of.get(robot)?)?;
        Some(&self.members[m].timing)
    }

    /// Runs tick `tick` (ticks in increasing order, from 0): afterwards
    /// [`Contention::reads`] says who reads its snapshot and
    /// [`Contention::sends`] the commands sent within it. `sensed(robot)`
    /// is the number of bodies the robot senses in the tick's state (for
    /// `per-body` compute; asked only then).
    pub fn tick(&mut self, tick: u64, mut sensed: impl FnMut(usize) -> usize) {
        let start = tick * self.dt_ns;
        let end = start + self.dt_ns;
        self.sends.clear();
        self.reads.fill(false);
        self.cores.world_tick();
        let seed = self.seed;
        let demand = |m: &Member, sensed: &mut dyn FnMut(usize) -> usize| {
            let n = match m.timing.compute {
                crate::timing::Compute::PerBody { .. } => sensed(m.robot),
                _ => 0,
            };
            m.timing.compute_ns(seed, m.robot as u64, tick, n)
        };
        for (i, m) in self.members.iter_mut().enumerate() {
            if self.cores.busy(i) || m.timing.skips(seed, m.robot as u64, tick).is_some() {
                continue;
            }
            m.demand = demand(m, &mut sensed);
            self.cores.release(i, m.demand, tick);
            self.reads[m.robot] = true;
        }
        let (members, reads, sends, dt_ns) = (
            &mut self.members,
            &mut self.reads,
            &mut self.sends,
            self.dt_ns,
        );
        self.cores.run_until(end, |d| {
            let m = &mut members[d.task];
            let robot = m.robot as u64;
            sends.push(CoreSend {
                robot: m.robot,
                tick: d.tag,
                sent_ns: d.at_ns - d.tag * dt_ns,
                cpu_ns: m.demand,
                lost: m.timing.command_lost(seed, robot, d.tag),
            });
            if d.tag >= tick || d.at_ns >= end || m.timing.skips(seed, robot, tick).is_some() {
                return None;
            }
            m.demand = demand(m, &mut sensed);
            reads[m.robot] = true;
            Some((m.demand, tick))
        });
    }

    /// The run is over: every job still running is run to its end (no
    /// snapshot is read any more); [`Contention::sends`] lists them.
    pub fn drain(&mut self) {
        self.sends.clear();
        self.reads.fill(false);
        let (members, sends, dt_ns, seed) = (&self.members, &mut self.sends, self.dt_ns, self.seed);
        self.cores.run_until(u64::MAX / 4, |d| {
            let m = &members[d.task];
            sends.push(CoreSend {
                robot: m.robot,
                tick: d.tag,
                sent_ns: d.at_ns - d.tag * dt_ns,
                cpu_ns: m.demand,
                lost: m.timing.command_lost(seed, m.robot as u64, d.tag),
            });
            None
        });
    }

    /// True if scenario robot `robot` reads the current tick's snapshot.
    pub fn reads(&self, robot: usize) -> bool {
        self.reads.get(robot).copied().unwrap_or(false)
    }

    /// The commands sent within the current tick, in the order they were.
    pub fn sends(&self) -> &[CoreSend] {
        &self.sends
    }
}

#[cfg(test)]
mod tests;
