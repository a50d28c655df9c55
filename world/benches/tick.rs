//! The world's own cost per tick against rapier's bare step.
//!
//! `bare_rapier_step`: a rapier2d `PhysicsWorld` with the same bodies as the
//! bench scene (discs, zero gravity, rotations locked, the arena's four
//! walls), one `step` per iteration — the floor. `world_step`: mrsim's
//! `World::step` (actuator model, collision events, state refresh) with
//! every robot under a force command. `world_tick`: what the tick loop adds
//! on top of the step each tick — the per-robot minimum clearance (the
//! grid, bounded by the smallest clearance recorded so far, as the world
//! does) and the snapshot copy a transport makes. Run with
//! `cargo bench -p mrsim-world --bench tick`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mrsim_world::metrics::ClearanceGrid;
use mrsim_world::{Applied, World};
use rapier2d::prelude::*;
use std::hint::black_box;

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
                grid.clearances_below(world.states(), n, |i| least[i], &mut clear);
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

criterion_group!(benches, ticks);
criterion_main!(benches);
