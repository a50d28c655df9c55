//! The world's own cost per tick against rapier's bare step.
//!
//! `bare_rapier_step`: a rapier2d `PhysicsWorld` with the same bodies as the
//! bench scene (discs, zero gravity, rotations locked, the arena's four
//! walls), one `step` per iteration — the floor. `world_step`: mrsim's
//! `World::step` (actuator model, collision events, state refresh) with
//! every robot under a force command. `world_tick`: the step plus the per-robot
//! minimum clearance (the grid, bounded by the smallest clearance recorded
//! so far, as the world does) and a snapshot copy — the world process's
//! CPU per tick before the commands. (In a run the clearance is computed
//! on the recording thread, beside the tick loop.)
//!
//! `world_loop`: the world's whole tick as a run has it — publish, collect
//! and check every robot's command, apply, step, goal test, record — timed
//! by the run itself (`mrsim_world::run`, lockstep, the tick loop's wall
//! time divided by its ticks) over a transport whose agents answer at once
//! (the commands are made when the snapshot is published, so no planning
//! and no wake-up is timed). The recording thread (trajectory.csv and the
//! motion metrics) and the timing thread run beside the loop, as they do
//! in a run; `world_loop_cpu` is the process's CPU time per tick, those
//! threads included. Run with `cargo bench -p mrsim-world --bench tick`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mrsim_proto::{
    BodyState, CommandMsg, FixedStr, JoinReply, JoinRequest, PROTOCOL_VERSION, SnapshotHeader,
    command_kind, now_ns,
};
use mrsim_transport::{TransportError, WorldTransport};
use mrsim_world::clearance::ClearanceGrid;
use mrsim_world::{Applied, RunOptions, World};
use rapier2d::prelude::*;
use std::hint::black_box;
use std::time::Duration;

fn scene(n: usize) -> mrsim_scenario::Scenario {
    let queue = n.div_ceil(2) as f64 * 0.75;
    let half = (3.0 + queue + 2.0).ceil();
    let text = format!(
        r#"name = "tick-{n}"
[world]
dt = 0.01
substeps = 1
duration = 10.0
arena = {{ min = [-{half}, -{half}], max = [{half}, {half}] }}
[defaults]
radius = 0.25
max_speed = 1.0
max_accel = 2.0
[generate]
kind = "crossing"
count = {n}
radius = 3.0
planner = "homing"
"#
    );
    match mrsim_scenario::parse(&text, "tick bench") {
        Ok(l) => l.scenario,
        Err(e) => panic!("bench scene: {e}"),
    }
}

fn bare(s: &mrsim_scenario::Scenario) -> PhysicsWorld {
    let mut phys = PhysicsWorld::new();
    phys.gravity = Vector::ZERO;
    phys.integration_parameters.dt = s.world.dt as f32;
    for r in &s.robots {
        let h = phys.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(r.start[0] as f32, r.start[1] as f32))
                .lock_rotations()
                .can_sleep(false)
                .ccd_enabled(true)
                .linvel(Vector::new(0.5, 0.5)),
        );
        phys.insert_collider(
            ColliderBuilder::ball(r.radius as f32)
                .mass(r.mass as f32)
                .active_events(ActiveEvents::COLLISION_EVENTS),
            Some(h),
        );
    }
    for w in s.all_walls() {
        let h = phys.insert_body(RigidBodyBuilder::fixed());
        phys.insert_collider(
            ColliderBuilder::segment(
                Vector::new(w[0][0] as f32, w[0][1] as f32),
                Vector::new(w[1][0] as f32, w[1][1] as f32),
            ),
            Some(h),
        );
    }
    phys
}

fn ticks(c: &mut Criterion) {
    let mut g = c.benchmark_group("tick");
    g.sample_size(30);
    for n in [64usize, 1000] {
        let s = scene(n);
        let mut phys = bare(&s);
        g.bench_with_input(BenchmarkId::new("bare_rapier_step", n), &n, |b, _| {
            b.iter(|| phys.step())
        });
        let mut world = match World::new(&s) {
            Ok(w) => w,
            Err(e) => panic!("{e}"),
        };
        for i in 0..n {
            world.set_command(i, Applied::Force([0.05, 0.05]));
        }
        let mut contacts = Vec::new();
        g.bench_with_input(BenchmarkId::new("world_step", n), &n, |b, _| {
            b.iter(|| world.step(&mut contacts))
        });
        let mut grid = ClearanceGrid::default();
        let mut clear = Vec::new();
        let mut copy = Vec::with_capacity(world.states().len());
        // Each robot's smallest clearance so far, as the world keeps it.
        let mut least = vec![f64::INFINITY; n];
        g.bench_with_input(BenchmarkId::new("world_tick", n), &n, |b, _| {
            b.iter(|| {
                world.step(&mut contacts);
                grid.clearances_below(world.states(), &[], n, |i| least[i], &mut clear);
                for (l, c) in least.iter_mut().zip(&clear) {
                    *l = l.min(*c);
                }
                copy.clear();
                copy.extend_from_slice(world.states());
                black_box((&clear, &copy));
            })
        });
    }
    g.finish();
}

/// A transport whose agents answer every snapshot at once: each robot's
/// command (a constant force) is made as the snapshot is published and
/// taken in at the next drain, stamped then, as a real transport does.
struct InstantAgents {
    names: Vec<String>,
    joined: bool,
    tokens: Vec<Option<u64>>,
    inbox: Vec<CommandMsg>,
}

impl InstantAgents {
    fn new(s: &mrsim_scenario::Scenario) -> Self {
        Self {
            names: s.robots.iter().map(|r| r.name.clone()).collect(),
            joined: false,
            tokens: vec![None; s.robots.len()],
            inbox: Vec::new(),
        }
    }

    fn command(&self, robot: usize, kind: u32, tick: u64, at_ns: u64) -> Option<CommandMsg> {
        Some(CommandMsg {
            robot_id: robot as u32,
            kind,
            token: self.tokens[robot]?,
            tick,
            value: [0.05, 0.05],
            compute_ns: 1_000,
            woke_ns: at_ns,
            sent_ns: at_ns,
            ..CommandMsg::default()
        })
    }
}

impl WorldTransport for InstantAgents {
    fn publish_setup(&mut self, _setup: &[u8]) -> Result<(), TransportError> {
        Ok(())
    }

    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        _bodies: &[BodyState],
    ) -> Result<(), TransportError> {
        if header.finished == 0 {
            for i in 0..self.names.len() {
                let c = self.command(i, command_kind::FORCE, header.tick, header.published_ns);
                self.inbox.extend(c);
            }
        }
        Ok(())
    }

    fn wait(&mut self, _timeout: Duration) -> Result<(), TransportError> {
        Ok(())
    }

    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError> {
        let now = now_ns();
        for c in self.inbox.drain(..) {
            f(c, now);
        }
        Ok(())
    }

    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError> {
        if !std::mem::replace(&mut self.joined, true) {
            for (i, name) in self.names.iter().enumerate() {
                f(JoinRequest {
                    protocol_version: PROTOCOL_VERSION,
                    pid: std::process::id(),
                    nonce: i as u64,
                    robot: FixedStr::new(name),
                    group: self.names.len() as u32,
                });
            }
        }
        Ok(())
    }

    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError> {
        let i = reply.robot_id as usize;
        if reply.accepted == 1 && i < self.tokens.len() {
            self.tokens[i] = Some(reply.token);
            let ready = self.command(i, command_kind::READY, 0, now_ns());
            self.inbox.extend(ready);
        }
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        false
    }

    fn expect_answers(&mut self, _tick: u64, _count: usize) {}

    fn joins_answered(&mut self) -> Result<(), TransportError> {
        Ok(())
    }

    fn cleanup_dead(&mut self) {}

    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        Ok(false)
    }

    fn publish_stats(
        &mut self,
        _header: &mrsim_proto::StatsHeader,
        _robots: &[mrsim_proto::RobotStats],
    ) -> Result<(), TransportError> {
        Ok(())
    }
}

/// Runs `s` (lockstep) over [`InstantAgents`]; the tick loop's wall time
/// and the process's CPU time, each per tick.
fn run_instant(s: &mrsim_scenario::Scenario, dir: &std::path::Path) -> (Duration, Duration) {
    let world = match World::new(s) {
        Ok(w) => w,
        Err(e) => panic!("{e}"),
    };
    let opts = RunOptions {
        out_dir: dir.to_path_buf(),
        run_id: "bench".into(),
        transport: "instant".into(),
        start_timeout: None,
        verbose: false,
        routes: Default::default(),
        group_room: None,
    };
    let out = match mrsim_world::run(world, &mut InstantAgents::new(s), opts) {
        Ok(o) => o,
        Err(e) => panic!("bench run: {e}"),
    };
    let m = &out.metrics;
    assert!(
        m.ticks > 0 && m.commands_rejected == 0,
        "every command taken: {} ticks, {} rejected",
        m.ticks,
        m.commands_rejected
    );
    let per_tick = |s: f64| Duration::from_secs_f64(s / m.ticks as f64);
    (per_tick(m.timing.wall_s), per_tick(m.timing.process_cpu_s))
}

fn loops(c: &mut Criterion) {
    let mut g = c.benchmark_group("tick");
    g.sample_size(10);
    let dir = std::env::temp_dir().join(format!("mrsim-tick-bench-{}", std::process::id()));
    if let Err(e) = std::fs::create_dir_all(&dir) {
        panic!("{}: {e}", dir.display());
    }
    for n in [64usize, 1000] {
        let mut s = scene(n);
        s.world.mode = mrsim_scenario::Mode::Lockstep;
        // A run per sample: 300 ticks (3 s simulated).
        s.world.duration = 3.0;
        for (id, cpu) in [("world_loop", false), ("world_loop_cpu", true)] {
            g.bench_with_input(BenchmarkId::new(id, n), &n, |b, _| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    let mut left = iters;
                    while left > 0 {
                        let (wall, cpu_time) = run_instant(&s, &dir);
                        // One run stands for as many ticks as it had.
                        let ticks = (s.world.duration / s.world.dt).round() as u64;
                        let k = left.min(ticks);
                        total += if cpu { cpu_time } else { wall } * k as u32;
                        left -= k;
                    }
                    total
                })
            });
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    g.finish();
}

criterion_group!(benches, ticks, loops);
criterion_main!(benches);
