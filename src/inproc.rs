//! Runs with the in-process transport: the world loop in the calling thread
//! and the agents in threads, over `mrsim_transport::inproc` (crossbeam
//! channels). The same world loop, agent code ([`mrsim_agents::join`] and
//! [`mrsim_agents::Driver`]) and planners as a run over iceoryx2, without
//! processes: the fast path for large headless experiments and the lower
//! bound for the IPC cost.
//!
//! Each agent joins in a thread of its own, exactly as an agent process
//! does; once joined it hands its [`Driver`] to one of a few worker threads
//! (one per CPU this process may run on), which receive each snapshot once
//! and answer for all their robots in one batch. A thread per agent woken
//! by every snapshot cost two context switches per agent per tick, which
//! bounded 64 robots at about 20x real time on two cores.

use crate::usage::{AgentUsage, Scope};
use mrsim_agents::{AgentExit, Driver};
use mrsim_scenario::Scenario;
use mrsim_transport::inproc::{InprocWorker, WorkerEvent};
use mrsim_world::metrics::RunMetrics;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Why an in-process run failed.
#[derive(Debug, thiserror::Error)]
pub enum InprocError {
    /// The world could not be built from the scenario.
    #[error("{0}")]
    World(#[from] mrsim_world::WorldError),
    /// The world loop failed.
    #[error("world: {0}")]
    Run(#[from] mrsim_world::run::RunError),
    /// An agent thread could not be started.
    #[error("cannot start the agent thread for {robot}: {source}")]
    Spawn {
        /// The robot.
        robot: String,
        /// Why.
        source: std::io::Error,
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

/// Runs `scenario` with the world in this thread and one thread per agent,
/// writing the outputs (trajectory.csv, events.jsonl, metrics.json,
/// scenario.json) into `out_dir`, which must exist. `stop` ends the run
/// early (the role SIGTERM plays for processes).
pub fn run_scenario(
    scenario: &Scenario,
    out_dir: &Path,
    run_id: &str,
    stop: Arc<AtomicBool>,
) -> Result<InprocOutcome, InprocError> {
    let world = mrsim_world::World::new(scenario)?;
    let n = scenario.robots.len();
    let workers = std::thread::available_parallelism()
        .map_or(1, |p| p.get())
        .clamp(1, n.max(1));
    // In lockstep the world and the workers poll briefly for each other's
    // next message instead of sleeping at once (see `pooled_channels`).
    let spin = if scenario.world.mode == mrsim_scenario::Mode::Lockstep {
        Duration::from_micros(200)
    } else {
        Duration::ZERO
    };
    let (mut link, sides, pool) = mrsim_transport::inproc::pooled_channels(n, workers, stop, spin);
    // Worker w drives the robots i with i % workers == w.
    let mut adopt = Vec::with_capacity(workers);
    let mut worker_handles = Vec::with_capacity(workers);
    for (w, side) in pool.into_iter().enumerate() {
        let (tx, rx) = crossbeam::channel::unbounded::<Driver>();
        adopt.push(tx);
        let expected = (w..n).step_by(workers).count();
        let handle = std::thread::Builder::new()
            .name(format!("agents-{w}"))
            .spawn(move || drive(side, rx, expected))
            .map_err(|source| InprocError::Spawn {
                robot: format!("worker {w}"),
                source,
            })?;
        worker_handles.push(handle);
    }
    let mut handles = Vec::with_capacity(n);
    for (i, (robot, mut side)) in scenario.robots.iter().zip(sides).enumerate() {
        let opts = mrsim_agents::AgentOptions::new(&robot.name);
        let to_worker = adopt[i % workers].clone();
        let handle = std::thread::Builder::new()
            .name(format!("agent-{}", robot.name))
            // Planners keep little on the stack; 1000 agents fit easily.
            .stack_size(512 * 1024)
            .spawn(move || match mrsim_agents::join(&mut side, &opts) {
                Ok(Some(driver)) => {
                    // A worker that is gone (the run ended) drops it.
                    let _ = to_worker.send(driver);
                    None
                }
                Ok(None) => None,
                Err(e) => Some(e.to_string()),
            })
            .map_err(|source| InprocError::Spawn {
                robot: robot.name.clone(),
                source,
            })?;
        handles.push(handle);
    }
    drop(adopt);
    let opts = mrsim_world::RunOptions {
        out_dir: out_dir.to_path_buf(),
        run_id: run_id.to_string(),
        transport: "inproc".to_string(),
        start_timeout: Some(Duration::from_secs(60)),
        verbose: std::env::var_os("MRSIM_VERBOSE").is_some(),
    };
    let outcome = mrsim_world::run(world, &mut link, opts);
    // Dropping the world's side disconnects the channels: an agent still
    // waiting sees the world gone and ends.
    drop(link);
    let mut agent_errors = Vec::with_capacity(n);
    for h in handles {
        agent_errors.push(
            h.join()
                .unwrap_or_else(|_| Some("the agent thread panicked".to_string())),
        );
    }
    // A worker's CPU time is shared equally among its robots.
    let mut agent_usage = vec![AgentUsage::default(); n];
    for (w, h) in worker_handles.into_iter().enumerate() {
        let (usage, errors) = h.join().unwrap_or_else(|_| {
            (
                AgentUsage::default(),
                vec![(None, "the worker thread panicked".to_string())],
            )
        });
        let mine: Vec<usize> = (w..n).step_by(workers).collect();
        for &i in &mine {
            agent_usage[i] = AgentUsage {
                cpu_s: usage.cpu_s / mine.len().max(1) as f64,
                maxrss_kb: usage.maxrss_kb,
            };
        }
        for (robot, e) in errors {
            for &j in mine.iter().filter(|&&j| robot.is_none_or(|i| i == j)) {
                agent_errors[j].get_or_insert_with(|| e.clone());
            }
        }
    }
    Ok(InprocOutcome {
        metrics: outcome?.metrics,
        agent_errors,
        agent_usage,
    })
}

/// A worker thread: adopts the drivers of the robots that joined, and on
/// each snapshot plans for all of them and sends their commands in one
/// batch. Ends on the run's last snapshot, when asked to stop, or when the
/// world is gone. Returns its CPU time (from the first snapshot to the
/// end) and the errors of the robots it drove, by robot index (`None`:
/// every robot of this worker).
fn drive(
    side: InprocWorker,
    adopt: crossbeam::channel::Receiver<Driver>,
    expected: usize,
) -> (AgentUsage, Vec<(Option<usize>, String)>) {
    let mut drivers: Vec<Driver> = Vec::with_capacity(expected);
    let mut latest: Option<(
        mrsim_proto::SnapshotHeader,
        std::sync::Arc<[mrsim_proto::BodyState]>,
    )> = None;
    let mut errors = Vec::new();
    let mut cpu_start = None;
    let mut batch = Vec::with_capacity(expected);
    let mut grid = Grid::default();
    let mut near = Vec::new();
    // The largest reach of this worker's robots (it sizes the grid's cells).
    let mut reach: Option<f64> = None;
    // One robot's turn, from `clock` (the end of the previous robot's: it
    // is when this robot "wakes" and starts planning); returns the clock at
    // its end.
    let step = |d: &mut Driver,
                h: &mrsim_proto::SnapshotHeader,
                b: &[mrsim_proto::BodyState],
                near: Option<&[u32]>,
                clock: u64,
                batch: &mut Vec<mrsim_proto::CommandMsg>,
                errors: &mut Vec<(Option<usize>, String)>| {
        let r = d.on_snapshot_among(h, b, near, clock, Some(clock), &mut |m| {
            batch.push(*m);
            Ok(())
        });
        r.unwrap_or_else(|e| {
            errors.push((Some(d.robot_id()), e.to_string()));
            mrsim_proto::now_ns()
        })
    };
    let exit = loop {
        if side.termination_requested() {
            break AgentExit::Interrupted;
        }
        // Robots that joined since: they answer the newest snapshot at once
        // (in lockstep the world waits for them).
        let mut adopted = false;
        while let Ok(mut d) = adopt.try_recv() {
            batch.push(d.ready());
            if let Some((h, b)) = &latest {
                let clock = mrsim_proto::now_ns();
                step(&mut d, h, b, None, clock, &mut batch, &mut errors);
            }
            reach = [reach, d.reach()].into_iter().flatten().reduce(f64::max);
            drivers.push(d);
            adopted = true;
        }
        if adopted && let Err(e) = side.send_commands(std::mem::take(&mut batch)) {
            errors.push((None, e.to_string()));
            break AgentExit::Finished;
        }
        // Poll often for newcomers until every robot of this worker joined
        // (one whose join failed keeps it polling, which costs little).
        let timeout = if drivers.len() >= expected {
            Duration::from_millis(100)
        } else {
            Duration::from_millis(5)
        };
        match side.next(timeout) {
            WorkerEvent::Snapshot(h, b) => {
                if h.finished != 0 {
                    break AgentExit::Finished;
                }
                cpu_start.get_or_insert_with(|| crate::usage::rusage(Scope::Thread).0);
                let gridded = grid.build(&b, reach);
                let mut clock = mrsim_proto::now_ns();
                for d in drivers.iter_mut() {
                    let among = gridded && grid.near(d, &b, &mut near);
                    let near = among.then_some(near.as_slice());
                    clock = step(d, &h, &b, near, clock, &mut batch, &mut errors);
                }
                if let Err(e) = side.send_commands(std::mem::take(&mut batch)) {
                    errors.push((None, e.to_string()));
                    break AgentExit::Finished;
                }
                latest = Some((h, b));
            }
            WorkerEvent::Idle => {}
            WorkerEvent::WorldGone => {
                errors.push((None, mrsim_agents::AgentError::WorldGone.to_string()));
                break AgentExit::Finished;
            }
        }
    };
    let (cpu_end, maxrss_kb) = crate::usage::rusage(Scope::Thread);
    let usage = AgentUsage {
        cpu_s: cpu_start.map_or(0.0, |s| (cpu_end - s).max(0.0)),
        maxrss_kb,
    };
    for d in drivers {
        let id = d.robot_id();
        if let Err(e) = d.finish(exit) {
            errors.push((Some(id), e.to_string()));
        }
    }
    (usage, errors)
}

/// The bodies of one snapshot bucketed in square cells at least as wide as
/// any of a worker's robots can sense (plus the largest body radius), so
/// each robot's observation looks at the 3 x 3 cells around it instead of
/// every body: at 1000 robots the full scans were half of all CPU time.
/// The candidates are handed over in ascending index order, the order of a
/// full scan, so the observation and everything after it are the same.
#[derive(Default)]
struct Grid {
    cell: f64,
    /// (cell key, body index), sorted.
    keyed: Vec<(i64, u32)>,
}

impl Grid {
    /// Buckets `bodies` for robots sensing up to `reach`; false (no grid)
    /// when no robot has a finite reach, or a position is not finite.
    fn build(&mut self, bodies: &[mrsim_proto::BodyState], reach: Option<f64>) -> bool {
        self.keyed.clear();
        let Some(reach) = reach else {
            return false;
        };
        let rmax = bodies.iter().map(|b| b.radius).fold(0.0f64, f64::max);
        self.cell = (reach + rmax) * (1.0 + 1e-9) + 1e-9;
        if !self.cell.is_finite() || self.cell <= 0.0 {
            return false;
        }
        for (i, b) in bodies.iter().enumerate() {
            match self.key(b.position) {
                Some(k) => self.keyed.push((k, i as u32)),
                None => {
                    self.keyed.clear();
                    return false;
                }
            }
        }
        self.keyed.sort_unstable();
        true
    }

    fn cell_of(&self, p: [f64; 2]) -> Option<(i64, i64)> {
        let (x, y) = (p[0] / self.cell, p[1] / self.cell);
        // Far outside any arena (or not finite): no grid for this snapshot.
        let ok = |v: f64| v.is_finite() && v.abs() < 1e9;
        (ok(x) && ok(y)).then(|| (x.floor() as i64, y.floor() as i64))
    }

    fn key(&self, p: [f64; 2]) -> Option<i64> {
        self.cell_of(p).map(|(cx, cy)| Self::pack(cx, cy))
    }

    fn pack(cx: i64, cy: i64) -> i64 {
        (cx << 32) ^ (cy & 0xffff_ffff)
    }

    /// Fills `out` with the indices of the bodies in the 3 x 3 cells
    /// around `d`'s robot, ascending; false if `d` needs a full scan (its
    /// reach is unlimited or wider than a cell, or its position unknown).
    fn near(&self, d: &Driver, bodies: &[mrsim_proto::BodyState], out: &mut Vec<u32>) -> bool {
        out.clear();
        let (Some(reach), Some(p)) = (d.reach(), d.position(bodies)) else {
            return false;
        };
        self.near_point(reach, p, out)
    }

    /// [`Self::near`] for a robot at `p` sensing up to `reach`.
    fn near_point(&self, reach: f64, p: [f64; 2], out: &mut Vec<u32>) -> bool {
        out.clear();
        if reach > self.cell {
            return false;
        }
        let Some((cx, cy)) = self.cell_of(p) else {
            return false;
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                let k = Self::pack(cx + dx, cy + dy);
                let from = self.keyed.partition_point(|&(key, _)| key < k);
                out.extend(
                    self.keyed[from..]
                        .iter()
                        .take_while(|&&(key, _)| key == k)
                        .map(|&(_, i)| i),
                );
            }
        }
        out.sort_unstable();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::BodyState;

    #[test]
    fn grid_candidates_hold_every_body_within_reach_in_index_order() {
        let mut x = 7u64;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let bodies: Vec<BodyState> = (0..400)
            .map(|i| BodyState {
                id: i,
                position: [next() * 40.0 - 20.0, next() * 40.0 - 20.0],
                radius: 0.1 + 0.4 * next(),
                ..Default::default()
            })
            .collect();
        let mut grid = Grid::default();
        let reach = 3.0;
        assert!(grid.build(&bodies, Some(reach)));
        let mut out = Vec::new();
        for me in &bodies {
            assert!(grid.near_point(reach, me.position, &mut out));
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending");
            for b in &bodies {
                let (dx, dy) = (
                    b.position[0] - me.position[0],
                    b.position[1] - me.position[1],
                );
                if (dx * dx + dy * dy).sqrt() - b.radius <= reach {
                    assert!(out.contains(&b.id), "body {} missed", b.id);
                }
            }
        }
        // No grid without a finite reach or with a position that is not finite.
        assert!(!grid.build(&bodies, None));
        let mut bad = bodies.clone();
        bad[3].position[0] = f64::NAN;
        assert!(!grid.build(&bad, Some(reach)));
    }
}
