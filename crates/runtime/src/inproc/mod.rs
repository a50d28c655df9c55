//! Runs with the in-process transport: the world loop in the calling thread
//! and the agents in threads, over `mrsim_transport::inproc` (crossbeam
//! channels). The same world loop, agent code ([`mrsim_agents::join`] and
//! [`mrsim_agents::Driver`]) and planners as a run over iceoryx2, without
//! processes: the fast path for large headless experiments and the lower
//! bound for the IPC cost.
//!
//! Each agent joins in a thread of its own, exactly as an agent process
//! does; once joined it hands its [`Driver`] to a shared pool. A few worker
//! threads (one per CPU this process may run on) receive each snapshot once,
//! claim chunks of the pool's robots until none is left, and answer for
//! them in one batch each. A thread per agent woken by every snapshot cost
//! two context switches per agent per tick, which bounded 64 robots at
//! about 20x real time on two cores.
//!
//! In lockstep the world's thread is one of the claimants: it has nothing
//! else to do until the commands are in, so it plans too (through
//! `InprocWorld::help_with`) and the pool has one worker fewer. One busy
//! thread per CPU hands a tick over faster than more threads than CPUs
//! taking turns, and claiming chunks instead of owning robots lets a
//! thread that comes late to a tick (its CPU taken by the recorder, say)
//! leave its share to the others.
//!
//! This is the one exception to the rule that an agent reaches its world
//! only through [`mrsim_transport::AgentTransport`]: each agent thread joins
//! through that trait (as an agent process does), but once joined its
//! [`Driver`] is driven by the pool over [`InprocWorker`], which hands each
//! worker every snapshot once and takes its robots' commands in one batch.
//! The per-agent trait cannot say either (one snapshot read per agent, one
//! command per send), and the per-agent way is what cost the two context
//! switches per agent per tick above. A group transport in
//! `mrsim-transport` (next snapshot or idle or world gone; send a batch of
//! commands) would let the pool be written against a trait; until then the
//! pool is tied to the in-process channels.

mod grid;

use crate::usage::{AgentUsage, Scope};
use grid::Grid;
use mrsim_agents::{AgentExit, Driver};
use mrsim_scenario::Scenario;
use mrsim_transport::AgentTransport;
use mrsim_transport::inproc::{InprocWorker, WorkerEvent};
use mrsim_world::metrics::RunMetrics;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

pub use mrsim_world::run::WorldRunError;

/// Why an in-process run failed. (The messages hold their causes: none is
/// a `source`, so a chain printed by a caller says each thing once.)
#[derive(Debug, thiserror::Error)]
pub enum InprocError {
    /// The world loop failed.
    #[error("world: {0}")]
    Run(WorldRunError),
    /// A thread of the run panicked.
    #[error("{0} panicked")]
    Panicked(&'static str),
    /// An agent or worker thread could not be started.
    #[error("cannot start the agent thread for {robot}: {error}")]
    Spawn {
        /// The robot (or `worker N`).
        robot: String,
        /// Why.
        error: std::io::Error,
    },
}

/// What an in-process run gives back.
#[derive(Debug, Clone)]
pub struct InprocOutcome {
    /// metrics.json.
    pub metrics: RunMetrics,
    /// Per robot (scenario order): the agent's error, if it ended with one.
    pub agent_errors: Vec<Option<String>>,
    /// Per robot: CPU time of its thread while the run ticked (the peak RSS
    /// is the whole process's).
    pub agent_usage: Vec<AgentUsage>,
}

/// Runs `scenario` on `world` (built from it) with the world loop in a
/// thread and the agents in a pool of workers, writing the outputs
/// (trajectory.csv, events.jsonl, metrics.json, scenario.json) into
/// `out_dir`, which must exist. `stop` ends the run early (the role SIGTERM
/// plays for processes). Meanwhile this thread calls `on_wait` about every
/// 20 ms with an observer of the run's live statistics (for progress).
/// Each agent joins with `agents`'s options (its robot's name put in):
/// where planners come from, and what stops the run when one fails.
///
/// With `plan_timeout` (lockstep only) this thread is also the run's
/// watchdog: a robot whose answer has taken longer than that stops the
/// run through `agents.halt` ([`mrsim_agents::PlanFault::TimedOut`], naming
/// the robot and the tick), and the world ends it as a termination request,
/// writing its outputs. A thread cannot be stopped from outside, so the
/// one stuck in the planner is left behind (it ends if the planner ever
/// returns), and the world's thread does not plan in such a run: stuck, it
/// could not end the run.
#[allow(clippy::too_many_arguments)]
pub fn run_scenario(
    scenario: &Scenario,
    world: mrsim_world::World,
    out_dir: &Path,
    run_id: &str,
    stop: Arc<AtomicBool>,
    agents: &mrsim_agents::AgentOptions,
    plan_timeout: Option<Duration>,
    on_wait: &mut dyn FnMut(&mut dyn mrsim_transport::ObserverTransport),
) -> Result<InprocOutcome, InprocError> {
    let n = scenario.robots.len();
    let cpus = std::thread::available_parallelism().map_or(1, |p| p.get());
    let lockstep = scenario.world.mode == mrsim_scenario::Mode::Lockstep;
    let plan_timeout = plan_timeout.filter(|_| lockstep);
    // In lockstep the world's thread plans too while it waits (it has
    // nothing else to do), so the pool has one worker fewer than CPUs;
    // not under a watchdog (above).
    let helps = lockstep && plan_timeout.is_none();
    let workers = if helps { cpus - 1 } else { cpus }.clamp(1, n.max(1));
    // In lockstep the world and the workers poll briefly for each other's
    // next message instead of sleeping at once (see `pooled_channels`).
    let spin = if lockstep {
        Duration::from_micros(200)
    } else {
        Duration::ZERO
    };
    // The agents join in a few groups, each a thread with one side that
    // reads the setup once (a thread and a setup per robot cost O(n²) at
    // start: every agent read the whole setup).
    let groups = join_groups(n, cpus);
    let (mut link, sides, pool_sides) =
        mrsim_transport::inproc::pooled_channels(groups.len(), workers, stop, spin);
    let reach = scenario
        .robots
        .iter()
        .filter_map(mrsim_agents::reach)
        .reduce(f64::max);
    let mut pool = Pool::new(n, reach, workers + usize::from(helps));
    if plan_timeout.is_some() {
        pool.busy = (0..workers).map(|_| Busy::default()).collect();
    }
    let pool = Arc::new(pool);
    if helps {
        let (pool, mut hand) = (pool.clone(), Hand::default());
        link.help_with(Box::new(move |h, b| {
            let start = mrsim_proto::now_ns();
            hand.answer(&pool, h, b);
            pool.note_help(mrsim_proto::now_ns().saturating_sub(start));
            std::mem::take(&mut hand.batch)
        }));
    }
    let mut worker_handles = Vec::with_capacity(workers);
    for (w, side) in pool_sides.into_iter().enumerate() {
        let pool = pool.clone();
        let handle = std::thread::Builder::new()
            .name(format!("agents-{w}"))
            .spawn(move || drive(side, &pool, w))
            .map_err(|error| InprocError::Spawn {
                robot: format!("worker {w}"),
                error,
            })?;
        worker_handles.push(handle);
    }
    let mut handles = Vec::with_capacity(groups.len());
    for (range, mut side) in groups.into_iter().zip(sides) {
        let opts: Vec<_> = scenario.robots[range.clone()]
            .iter()
            .map(|r| {
                let mut o = agents.clone();
                o.robot = r.name.clone();
                o
            })
            .collect();
        let pool = pool.clone();
        let first = range.start;
        let handle = std::thread::Builder::new()
            .name(format!("join-{first}"))
            .spawn(move || join_group(&mut side, &opts, &pool))
            .map_err(|error| InprocError::Spawn {
                robot: scenario.robots[first].name.clone(),
                error,
            })?;
        handles.push((range, handle));
    }
    let opts = mrsim_world::RunOptions {
        out_dir: out_dir.to_path_buf(),
        run_id: run_id.to_string(),
        transport: "inproc".to_string(),
        start_timeout: Some(start_timeout(n)),
        verbose: std::env::var_os("MRSIM_VERBOSE").is_some(),
        routes: crate::routes::of(scenario),
        group_room: None,
    };
    // The world loop in a thread of its own, and this one shows progress
    // (`on_wait`, about every 20 ms) until it ends.
    let mut observer = link.observer();
    let outcome = std::thread::scope(|s| {
        let world = std::thread::Builder::new()
            .name("world".to_string())
            .spawn_scoped(s, move || {
                let outcome = mrsim_world::run(world, &mut link, opts);
                // Dropping the world's side disconnects the channels: an
                // agent still waiting sees the world gone and ends (and the
                // helper lets go of the pool).
                drop(link);
                outcome
            })
            .map_err(|error| InprocError::Spawn {
                robot: "the world".to_string(),
                error,
            })?;
        while !world.is_finished() {
            on_wait(&mut observer);
            if let (Some(limit), Some(halt)) = (plan_timeout, &agents.halt)
                && let Some((robot, tick)) = pool.stuck(limit)
            {
                halt.raise(&mrsim_agents::PlanFailure {
                    robot: scenario
                        .robots
                        .get(robot)
                        .map_or_else(|| format!("#{robot}"), |r| r.name.clone()),
                    tick,
                    what: mrsim_agents::PlanFault::TimedOut(limit),
                });
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        on_wait(&mut observer);
        world
            .join()
            .map_err(|_| InprocError::Panicked("the world thread"))
    })?;
    let mut agent_errors = vec![None; n];
    for (range, h) in handles {
        let e = h
            .join()
            .unwrap_or_else(|_| Some("the agent thread panicked".to_string()));
        if let Some(e) = e {
            // The group's error is every robot's of the group.
            agent_errors[range].fill(Some(e));
        }
    }
    let mut exit = AgentExit::Finished;
    let mut cpu_s = 0.0;
    let mut maxrss_kb = 0;
    for (w, h) in worker_handles.into_iter().enumerate() {
        if pool.busy.get(w).is_some_and(Busy::is_busy) && !h.is_finished() {
            // Still in a planner the watchdog gave up on: left behind.
            pool.fail(None, "a planner did not return".to_string());
            continue;
        }
        match h.join() {
            Ok((e, usage)) => {
                if e == AgentExit::Interrupted {
                    exit = e;
                }
                cpu_s += usage.cpu_s;
                maxrss_kb = maxrss_kb.max(usage.maxrss_kb);
            }
            Err(_) => pool.fail(None, "the worker thread panicked".to_string()),
        }
    }
    let (drivers, errors, help_ns) = pool.finish();
    for d in drivers {
        let id = d.robot_id();
        if let Err(e) = d.finish(exit) {
            agent_errors[id].get_or_insert_with(|| e.to_string());
        }
    }
    for (robot, e) in errors {
        for (j, slot) in agent_errors.iter_mut().enumerate() {
            if robot.is_none_or(|i| i == j) {
                slot.get_or_insert_with(|| e.clone());
            }
        }
    }
    // The pool's CPU time (the workers', and the world's thread while it
    // planned) is shared equally among the robots.
    let cpu_s = cpu_s + help_ns as f64 * 1e-9;
    let agent_usage = vec![
        AgentUsage {
            cpu_s: cpu_s / n.max(1) as f64,
            maxrss_kb,
        };
        n
    ];
    Ok(InprocOutcome {
        metrics: outcome.map_err(InprocError::Run)?.metrics,
        agent_errors,
        agent_usage,
    })
}

/// How long the world waits for every in-process robot to join: a minute,
/// and a millisecond more per robot. Joining costs CPU time per robot
/// (about 0.1 ms each at 100,000 robots), and on a machine whose CPUs
/// other work shares a flat minute of wall time ran out before 100,000
/// robots were in.
fn start_timeout(robots: usize) -> Duration {
    Duration::from_secs(60) + Duration::from_millis(robots as u64)
}

/// The robots each join thread joins: consecutive ranges, a few per CPU
/// (a thread waits for the world's replies most of the time).
fn join_groups(n: usize, cpus: usize) -> Vec<std::ops::Range<usize>> {
    let size = n.div_ceil((4 * cpus).max(1)).max(1);
    (0..n).step_by(size).map(|s| s..(s + size).min(n)).collect()
}

/// Joins the robots of `opts` over `side` and puts their drivers into
/// `pool`, each followed by its ready (and, if a snapshot is being
/// answered already, its answer to it). Returns the error that ended it.
fn join_group(
    side: &mut mrsim_transport::inproc::InprocAgent,
    opts: &[mrsim_agents::AgentOptions],
    pool: &Pool,
) -> Option<String> {
    let drivers = match mrsim_agents::join_group(side, opts) {
        Ok(Some(d)) => d,
        Ok(None) => return None,
        Err(e) => return Some(e.to_string()),
    };
    for driver in drivers {
        // Into the pool first, then ready: the world starts the run once
        // every robot is ready, and the first snapshot must find every
        // driver in the pool.
        let ready = driver.ready();
        let i = driver.robot_id();
        let answer = pool.adopt(i, driver);
        if let Err(e) = std::iter::once(&ready)
            .chain(&answer)
            .try_for_each(|m| side.send_command(m))
        {
            return Some(e.to_string());
        }
    }
    None
}

/// Every robot's [`Driver`], in chunks of consecutive robots. For each
/// snapshot the workers (and in lockstep the world's thread) claim chunks
/// one at a time until none is left, so a thread that comes late to a
/// tick (woken late, or sharing its CPU) takes fewer of them instead of
/// holding the tick up.
struct Pool {
    /// Chunk `k` holds the drivers of robots `k * size .. (k + 1) * size`
    /// that have joined.
    chunks: Vec<std::sync::Mutex<Vec<Driver>>>,
    size: usize,
    /// The tick being answered (low 32 bits) in the high half, and the
    /// next chunk to claim for it in the low half.
    claims: AtomicU64,
    /// The largest finite sensing reach of the robots (sizes the grid).
    reach: Option<f64>,
    errors: std::sync::Mutex<Vec<RobotError>>,
    /// Time the world's thread spent planning, ns.
    help_ns: AtomicU64,
    /// The newest snapshot being answered (for a robot that joins late).
    latest: std::sync::Mutex<Option<Snapshot>>,
    /// Under a watchdog: what each worker is answering (empty otherwise).
    busy: Vec<Busy>,
}

/// The robot a worker is answering and since when, for the watchdog.
struct Busy {
    /// The robot's index; `u64::MAX` between answers.
    robot: AtomicU64,
    /// The tick it answers.
    tick: AtomicU64,
    /// When its answer began (CLOCK_MONOTONIC ns).
    since_ns: AtomicU64,
}

impl Default for Busy {
    fn default() -> Self {
        Self {
            robot: AtomicU64::new(u64::MAX),
            tick: AtomicU64::new(0),
            since_ns: AtomicU64::new(0),
        }
    }
}

impl Busy {
    fn begin(&self, robot: usize, tick: u64, now_ns: u64) {
        self.tick.store(tick, Ordering::Relaxed);
        self.since_ns.store(now_ns, Ordering::Relaxed);
        self.robot.store(robot as u64, Ordering::Release);
    }

    fn end(&self) {
        self.robot.store(u64::MAX, Ordering::Release);
    }

    fn is_busy(&self) -> bool {
        self.robot.load(Ordering::Acquire) != u64::MAX
    }
}

/// A snapshot as the workers get it.
type Snapshot = (mrsim_proto::SnapshotHeader, Arc<[mrsim_proto::BodyState]>);

/// An error of robot `.0` (`None`: of every robot).
type RobotError = (Option<usize>, String);

/// Locks `m`, also after another thread panicked holding it (what it
/// guards stays usable: a driver or a list).
fn lock<T>(m: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl Pool {
    /// A pool for `n` robots whose largest finite reach is `reach`,
    /// answered by `threads` threads.
    fn new(n: usize, reach: Option<f64>, threads: usize) -> Self {
        // About eight chunks a thread: enough for a late thread to leave
        // its share to the others, few enough that claiming costs little.
        let size = (n / (8 * threads.max(1))).clamp(1, 32);
        Self {
            chunks: (0..n.div_ceil(size))
                .map(|_| std::sync::Mutex::new(Vec::with_capacity(size)))
                .collect(),
            size,
            claims: AtomicU64::new(u64::MAX),
            reach,
            errors: std::sync::Mutex::new(Vec::new()),
            help_ns: AtomicU64::new(0),
            latest: std::sync::Mutex::new(None),
            busy: Vec::new(),
        }
    }

    /// A robot (index, tick) whose answer began more than `limit` ago.
    fn stuck(&self, limit: Duration) -> Option<(usize, u64)> {
        let now = mrsim_proto::now_ns();
        let limit_ns = u64::try_from(limit.as_nanos()).unwrap_or(u64::MAX);
        self.busy.iter().find_map(|b| {
            let robot = b.robot.load(Ordering::Acquire);
            let (tick, since) = (
                b.tick.load(Ordering::Relaxed),
                b.since_ns.load(Ordering::Relaxed),
            );
            // Read again: the same answer all along, not a new one begun
            // between the loads.
            let same = b.robot.load(Ordering::Acquire) == robot;
            (robot != u64::MAX && same && now.saturating_sub(since) > limit_ns)
                .then_some((robot as usize, tick))
        })
    }

    /// Takes in the driver of robot `i`. If a snapshot is being answered
    /// already, the robot answers it at once (its chunk may be done, and in
    /// lockstep the world waits for every robot that joined): returns that
    /// command, to be sent after the robot's ready.
    fn adopt(&self, i: usize, mut d: Driver) -> Vec<mrsim_proto::CommandMsg> {
        let mut answer = Vec::new();
        let Some(chunk) = self.chunks.get(i / self.size) else {
            return answer;
        };
        // The chunk stays locked until the driver is in: a thread answering
        // this snapshot either finds it answered or has done the chunk.
        let mut chunk = lock(chunk);
        let latest = lock(&self.latest).clone();
        if let Some((h, b)) = latest {
            let sent = d.on_snapshot(&h, &b, mrsim_proto::now_ns(), &mut |m| {
                answer.push(*m);
                Ok(())
            });
            if let Err(e) = sent {
                self.fail(Some(d.robot_id()), e.to_string());
            }
        }
        chunk.push(d);
        answer
    }

    /// Notes the snapshot being answered, if it is the newest.
    fn saw(&self, h: &mrsim_proto::SnapshotHeader, b: &Arc<[mrsim_proto::BodyState]>) {
        let mut latest = lock(&self.latest);
        if latest.as_ref().is_none_or(|(seen, _)| seen.tick < h.tick) {
            *latest = Some((*h, b.clone()));
        }
    }

    /// The next chunk to answer `tick` with, if any is left. A thread
    /// still on an older tick gets none once a newer one has started.
    fn claim(&self, tick: u64) -> Option<usize> {
        let tag = tick & 0xffff_ffff;
        let mut now = self.claims.load(Ordering::Acquire);
        loop {
            let (at, next) = (now >> 32, now & 0xffff_ffff);
            let (k, new) = if now == u64::MAX || at != tag {
                // The first claim for this tick, unless the tick is older
                // than the one being answered.
                if now != u64::MAX && (tag.wrapping_sub(at) & 0xffff_ffff) >= 1 << 31 {
                    return None;
                }
                (0, (tag << 32) | 1)
            } else {
                (next as usize, now + 1)
            };
            if k >= self.chunks.len() {
                return None;
            }
            match self
                .claims
                .compare_exchange_weak(now, new, Ordering::AcqRel, Ordering::Acquire)
            {
                Ok(_) => return Some(k),
                Err(changed) => now = changed,
            }
        }
    }

    fn fail(&self, robot: Option<usize>, e: String) {
        lock(&self.errors).push((robot, e));
    }

    fn note_help(&self, ns: u64) {
        self.help_ns.fetch_add(ns, Ordering::Relaxed);
    }

    /// Every driver, the errors, and the world thread's planning time.
    fn finish(&self) -> (Vec<Driver>, Vec<RobotError>, u64) {
        // A chunk still held by a worker stuck in a planner stays with it.
        let drivers = self
            .chunks
            .iter()
            .flat_map(|c| match c.try_lock() {
                Ok(mut g) => std::mem::take(&mut *g),
                Err(std::sync::TryLockError::Poisoned(p)) => std::mem::take(&mut *p.into_inner()),
                Err(std::sync::TryLockError::WouldBlock) => Vec::new(),
            })
            .collect();
        let errors = std::mem::take(&mut *lock(&self.errors));
        (drivers, errors, self.help_ns.load(Ordering::Relaxed))
    }
}

/// What a thread answering snapshots keeps between them: its grid, and the
/// batch of commands it is making.
#[derive(Default)]
struct Hand {
    grid: Grid,
    near: Vec<u32>,
    batch: Vec<mrsim_proto::CommandMsg>,
    /// Commands of the last batch: the next one starts with room for as
    /// many (a batch is handed over whole each tick, and growing it from
    /// empty copied it over and over: tens of thousands of commands).
    last: usize,
}

impl Hand {
    /// Claims chunks of `pool` for this snapshot until none is left, and
    /// plans for their robots into `self.batch`. A robot's compute time
    /// starts where the previous robot's ended (the clock is read once per
    /// robot), its wake-up where this thread's previous robot ended.
    fn answer(
        &mut self,
        pool: &Pool,
        h: &mrsim_proto::SnapshotHeader,
        b: &Arc<[mrsim_proto::BodyState]>,
    ) {
        self.answer_watched(pool, h, b, None);
    }

    /// As [`Hand::answer`], noting in `busy` (under a watchdog) each robot
    /// being answered.
    fn answer_watched(
        &mut self,
        pool: &Pool,
        h: &mrsim_proto::SnapshotHeader,
        b: &Arc<[mrsim_proto::BodyState]>,
        busy: Option<&Busy>,
    ) {
        pool.saw(h, b);
        self.batch.reserve(self.last);
        let mut gridded = None;
        let mut clock = mrsim_proto::now_ns();
        while let Some(k) = pool.claim(h.tick) {
            let gridded = *gridded.get_or_insert_with(|| self.grid.build(b, pool.reach));
            for d in lock(&pool.chunks[k]).iter_mut() {
                let among = gridded && self.grid.near(d, b, &mut self.near);
                let near = among.then_some(self.near.as_slice());
                let batch = &mut self.batch;
                if let Some(busy) = busy {
                    busy.begin(d.robot_id(), h.tick, clock);
                }
                clock = d
                    .on_snapshot_among(h, b, near, clock, Some(clock), &mut |m| {
                        batch.push(*m);
                        Ok(())
                    })
                    .unwrap_or_else(|e| {
                        pool.fail(Some(d.robot_id()), e.to_string());
                        mrsim_proto::now_ns()
                    });
                if let Some(busy) = busy {
                    busy.end();
                }
            }
        }
        self.last = self.batch.len();
    }
}

/// Worker `w`: on each snapshot, answers for the chunks of robots it
/// claims and sends their commands in one batch. Ends on the run's last
/// snapshot, when asked to stop, or when the world is gone. Returns how
/// the robots' control ended, and its CPU time (from the first snapshot
/// to the end).
fn drive(side: InprocWorker, pool: &Pool, w: usize) -> (AgentExit, AgentUsage) {
    let mut hand = Hand::default();
    let mut cpu_start = None;
    let exit = loop {
        if side.termination_requested() {
            break AgentExit::Interrupted;
        }
        match side.next(Duration::from_millis(100)) {
            WorkerEvent::Snapshot(h, b) => {
                if h.finished != 0 {
                    break AgentExit::Finished;
                }
                cpu_start.get_or_insert_with(|| crate::usage::rusage(Scope::Thread).0);
                hand.answer_watched(pool, &h, &b, pool.busy.get(w));
                if let Err(e) = side.send_commands(std::mem::take(&mut hand.batch)) {
                    pool.fail(None, e.to_string());
                    break AgentExit::Finished;
                }
            }
            WorkerEvent::Idle => {}
            WorkerEvent::WorldGone => {
                pool.fail(None, mrsim_agents::AgentError::WorldGone.to_string());
                break AgentExit::Finished;
            }
        }
    };
    let (cpu_end, maxrss_kb) = crate::usage::rusage(Scope::Thread);
    let usage = AgentUsage {
        cpu_s: cpu_start.map_or(0.0, |s| (cpu_end - s).max(0.0)),
        maxrss_kb,
    };
    (exit, usage)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::BodyState;

    /// Claims `tick` until none is left.
    fn claim_all(pool: &Pool, tick: u64) -> Vec<usize> {
        std::iter::from_fn(|| pool.claim(tick)).collect()
    }

    #[test]
    fn each_chunk_is_claimed_once_per_tick_and_again_for_the_next() {
        let pool = Pool::new(64, Some(3.0), 2);
        let chunks = pool.chunks.len();
        assert_eq!(chunks, 16, "64 robots for 2 threads: chunks of 4");
        assert_eq!(claim_all(&pool, 1), (0..chunks).collect::<Vec<_>>());
        assert_eq!(pool.claim(1), None);
        assert_eq!(claim_all(&pool, 2), (0..chunks).collect::<Vec<_>>());
    }

    #[test]
    fn a_thread_still_on_an_older_tick_claims_nothing() {
        let pool = Pool::new(64, None, 2);
        assert_eq!(pool.claim(7), Some(0));
        assert_eq!(pool.claim(6), None);
        assert_eq!(pool.claim(7), Some(1));
        // The tick counter's low 32 bits wrap: still newer.
        let pool = Pool::new(8, None, 1);
        assert_eq!(pool.claim(u64::from(u32::MAX)), Some(0));
        assert_eq!(pool.claim(1 << 32), Some(0));
        assert_eq!(pool.claim(u64::from(u32::MAX)), None);
    }

    #[test]
    fn threads_claiming_at_once_share_out_every_chunk_exactly_once() {
        let pool = Pool::new(1000, None, 4);
        let chunks = pool.chunks.len();
        for tick in 1..=50 {
            let mut got: Vec<usize> = std::thread::scope(|s| {
                let hands: Vec<_> = (0..4).map(|_| s.spawn(|| claim_all(&pool, tick))).collect();
                hands
                    .into_iter()
                    .flat_map(|h| h.join().expect("claiming thread"))
                    .collect()
            });
            got.sort_unstable();
            assert_eq!(got, (0..chunks).collect::<Vec<_>>(), "tick {tick}");
        }
    }

    /// The driver of a one-robot run's robot, joined over the in-process
    /// transport as an agent thread joins.
    fn joined_driver() -> Driver {
        use mrsim_transport::WorldTransport;
        let scenario = mrsim_scenario::parse(
            r#"
            name = "late"
            [world]
            arena = { min = [0.0, 0.0], max = [10.0, 10.0] }
            [[robot]]
            name = "a"
            start = [1.0, 5.0]
            goal = [9.0, 5.0]
            planner = "homing"
            "#,
            "late.toml",
        )
        .expect("scenario")
        .scenario;
        let stop = Arc::new(AtomicBool::new(false));
        let (mut world, mut sides) = mrsim_transport::inproc::channels(1, stop);
        let setup = serde_json::json!({"run_id": "late", "out_dir": null, "scenario": scenario});
        world
            .publish_setup(setup.to_string().as_bytes())
            .expect("setup");
        let mut side = sides.pop().expect("one side");
        let agent = std::thread::spawn(move || {
            mrsim_agents::join(&mut side, &mrsim_agents::AgentOptions::new("a"))
        });
        let mut asked = None;
        while asked.is_none() {
            world.wait(Duration::from_millis(10)).expect("wait");
            world.drain_joins(&mut |r| asked = Some(r)).expect("joins");
        }
        let asked = asked.expect("a join request");
        world
            .reply_join(&mrsim_proto::JoinReply {
                nonce: asked.nonce,
                accepted: 1,
                robot_id: 0,
                token: 7,
                protocol_version: mrsim_proto::PROTOCOL_VERSION,
                world_pid: std::process::id(),
                reason: Default::default(),
            })
            .expect("reply");
        match agent.join() {
            Ok(Ok(Some(d))) => d,
            _ => panic!("the agent did not join"),
        }
    }

    #[test]
    fn a_robot_joining_during_a_tick_answers_it_and_only_once() {
        let pool = Pool::new(1, None, 1);
        // Before any snapshot: nothing to answer yet.
        assert!(pool.adopt(0, joined_driver()).is_empty());
        let pool = Pool::new(1, None, 1);
        let header = mrsim_proto::SnapshotHeader {
            tick: 5,
            ..Default::default()
        };
        let bodies: Arc<[BodyState]> = Arc::from(vec![BodyState {
            position: [1.0, 5.0],
            radius: 0.25,
            ..Default::default()
        }]);
        // A thread has started on tick 5 (and done the robot's chunk
        // before the robot was in it): the robot answers tick 5 itself.
        let mut hand = Hand::default();
        hand.answer(&pool, &header, &bodies);
        assert!(hand.batch.is_empty(), "no robot in the pool yet");
        let answer = pool.adopt(0, joined_driver());
        assert_eq!(answer.len(), 1);
        assert_eq!((answer[0].tick, answer[0].token), (5, 7));
        // A thread that reaches the robot's chunk after it joined finds
        // tick 5 answered, and answers the next tick.
        let pool = Pool::new(1, None, 1);
        pool.saw(&header, &bodies);
        assert_eq!(pool.adopt(0, joined_driver()).len(), 1);
        let mut late = Hand::default();
        late.answer(&pool, &header, &bodies);
        assert!(late.batch.is_empty(), "tick 5 answered twice");
        let next = mrsim_proto::SnapshotHeader { tick: 6, ..header };
        late.answer(&pool, &next, &bodies);
        assert_eq!(late.batch.len(), 1);
        assert_eq!(late.batch[0].tick, 6);
    }

    /// An agent's side whose commands say they were sent just after their
    /// tick's deadline, as from an agent that answered late while the
    /// world, itself late, had not yet stopped waiting.
    #[test]
    fn a_command_sent_after_its_deadline_is_a_miss_even_if_the_world_takes_it_in_in_time() {
        let scenario = mrsim_scenario::parse(
            r#"
            name = "sent-late"
            [world]
            mode = "realtime"
            dt = 0.2
            duration = 1.0
            arena = { min = [0.0, 0.0], max = [20.0, 20.0] }
            [[robot]]
            name = "late"
            start = [1.0, 5.0]
            goal = [19.0, 5.0]
            planner = "homing"
            [[robot]]
            name = "prompt"
            start = [1.0, 15.0]
            goal = [19.0, 15.0]
            planner = "homing"
            "#,
            "sent-late.toml",
        )
        .expect("scenario")
        .scenario;
        let out = std::env::temp_dir().join(format!("mrsim-sent-late-{}", std::process::id()));
        std::fs::create_dir_all(&out).expect("out dir");
        let world = mrsim_world::World::new(&scenario).expect("world");
        let stop = Arc::new(AtomicBool::new(false));
        let (mut link, sides) = mrsim_transport::inproc::channels(2, stop);
        let agents: Vec<_> = sides
            .into_iter()
            .zip(["late", "prompt"])
            .map(|(mut side, name)| {
                std::thread::spawn(move || {
                    let mut opts = mrsim_agents::AgentOptions::new(name);
                    if name == "late" {
                        opts.fault = Some(mrsim_agents::fault::Fault::SentLate);
                    }
                    mrsim_agents::run(&mut side, &opts).map(|_| ())
                })
            })
            .collect();
        let outcome = mrsim_world::run(
            world,
            &mut link,
            mrsim_world::RunOptions {
                out_dir: out.clone(),
                run_id: "sent-late".to_string(),
                transport: "inproc".to_string(),
                start_timeout: Some(Duration::from_secs(30)),
                verbose: false,
                routes: Default::default(),
                group_room: None,
            },
        );
        drop(link);
        for a in agents {
            assert!(matches!(a.join(), Ok(Ok(()))));
        }
        let _ = std::fs::remove_dir_all(&out);
        let m = outcome.expect("the run").metrics;
        // The late robot's every answer reached the world within its tick
        // (the in-process channel delivers at once) but says it was sent
        // after the deadline: every tick is a miss, none is taken. (The
        // other robot's answers are taken: the world was listening.)
        let (late, prompt) = (&m.robots["late"], &m.robots["prompt"]);
        assert_eq!(m.ticks, 5);
        assert_eq!(late.deadline_misses, 5, "{late:?}");
        assert_eq!(late.commands_late, 5);
        assert_eq!(late.path_length, 0.0, "a late command moved the robot");
        assert!(prompt.deadline_misses < 5, "{prompt:?}");
    }
}
