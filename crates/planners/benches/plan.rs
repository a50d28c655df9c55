//! One `plan` call per planner with 64 sensed bodies.
use criterion::{Criterion, criterion_group, criterion_main};
use mrsim_planners::{
    BodyKind, DesignatedPath, Observation, PLANNERS, ParamValue, Params, SelfState, Sensed, Vec2,
    build,
};

fn scene(n: usize) -> Vec<Sensed> {
    (0..n)
        .map(|i| {
            let a = i as f64 * 0.7;
            Sensed::disc(
                i as u32 + 1,
                if i % 2 == 0 {
                    BodyKind::Robot
                } else {
                    BodyKind::Obstacle
                },
                Vec2::new(5.0 + 3.0 * a.cos() * (1.0 + i as f64 * 0.1), 3.0 * a.sin()),
                Vec2::new(-(a.sin()), a.cos()),
                0.3,
            )
        })
        .collect()
}

/// Zhu & Loh's planners: growth with the number of obstacles (20-step
/// horizon) and with the horizon (16 obstacles).
fn zhu_loh(c: &mut Criterion) {
    use mrsim_planners::ParamValue;
    let dt = 0.1;
    let me = SelfState {
        id: 0,
        position: Vec2::new(0.0, 0.0),
        velocity: Vec2::new(0.5, 0.1),
        radius: 0.3,
        shape: mrsim_planners::Shape::disc(0.3),
        mass: 1.0,
        damping: 0.5,
        max_speed: 2.0,
        max_accel: 5.0,
        heading: 0.0,
        angular_velocity: 0.0,
        steering: 0.0,
        kinematics: mrsim_planners::Kinematics::Holonomic,
    };
    // (obstacles, horizon steps)
    let cases = [(4, 20), (16, 20), (64, 20), (16, 10), (16, 40)];
    for (name, extra) in [
        ("trajectory_guided", vec![("candidates", 32.0)]),
        // grid 0.14 with max_speed 2 and 20 steps: a 65 x 65 window.
        ("free_space", vec![("grid", 0.14)]),
    ] {
        let mut g = c.benchmark_group(format!("zhu_loh_{name}"));
        for &(bodies, steps) in &cases {
            let others = scene(bodies);
            let obs = Observation {
                tick: 10,
                time: 1.0,
                dt,
                me,
                goal: Vec2::new(20.0, 1.0),
                goal_tolerance: 0.2,
                goal_hold_ticks: 3,
                others: &others,
                walls: &[],
                path: None,
                scan: None,
            };
            let mut params = Params::new();
            params.insert("horizon".into(), ParamValue::Number(steps as f64 * dt));
            for (k, v) in &extra {
                params.insert(k.to_string(), ParamValue::Number(*v));
            }
            let Ok(mut p) = build(&name.replace('_', "-"), &params) else {
                continue;
            };
            g.bench_function(format!("{bodies}_obstacles_{steps}_steps"), |b| {
                b.iter(|| p.plan(std::hint::black_box(&obs)))
            });
        }
        g.finish();
    }
}

fn bench(c: &mut Criterion) {
    let others = scene(64);
    let obs = Observation {
        tick: 10,
        time: 1.0,
        dt: 0.1,
        me: SelfState {
            id: 0,
            position: Vec2::new(0.0, 0.0),
            velocity: Vec2::new(0.5, 0.1),
            radius: 0.3,
            shape: mrsim_planners::Shape::disc(0.3),
            mass: 1.0,
            damping: 0.5,
            max_speed: 2.0,
            max_accel: 5.0,
            heading: 0.0,
            angular_velocity: 0.0,
            steering: 0.0,
            kinematics: mrsim_planners::Kinematics::Holonomic,
        },
        goal: Vec2::new(20.0, 1.0),
        goal_tolerance: 0.2,
        goal_hold_ticks: 3,
        others: &others,
        walls: &[],
        path: None,
        scan: None,
    };
    let mut g = c.benchmark_group("plan_64_bodies");
    for info in PLANNERS {
        let Ok(mut p) = build(info.name, &Params::new()) else {
            continue;
        };
        g.bench_function(info.name, |b| b.iter(|| p.plan(std::hint::black_box(&obs))));
    }
    g.finish();
}

/// `designated-path` on the paper's kind of scene: a designated path, 16 sensed bodies,
/// 6 speeds (the current one and 0.1..0.5 m/s), a robot in the paper's
/// speed range among them.
fn bench_designated_path(c: &mut Criterion) {
    let others: Vec<Sensed> = scene(16)
        .into_iter()
        .map(|mut s| {
            s.position *= 0.5;
            s.velocity *= 0.3;
            s.radius = 0.2;
            s
        })
        .collect();
    let path = DesignatedPath {
        points: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 0.0),
            Vec2::new(3.0, 3.0),
            Vec2::new(6.0, 3.0),
        ],
        boundary: 1.0,
    };
    let obs = Observation {
        tick: 10,
        time: 1.0,
        dt: 0.1,
        me: SelfState {
            id: 0,
            position: Vec2::new(0.0, 0.0),
            velocity: Vec2::new(0.2, 0.0),
            radius: 0.2,
            shape: mrsim_planners::Shape::disc(0.2),
            mass: 1.0,
            damping: 0.0,
            max_speed: 0.5,
            max_accel: 0.5,
            heading: 0.0,
            angular_velocity: 0.0,
            steering: 0.0,
            kinematics: mrsim_planners::Kinematics::Holonomic,
        },
        goal: Vec2::new(6.0, 3.0),
        goal_tolerance: 0.1,
        goal_hold_ticks: 3,
        others: &others,
        walls: &[],
        path: Some(&path),
        scan: None,
    };
    let mut params = Params::new();
    params.insert("subgoal_spacing".into(), ParamValue::Number(0.5));
    let mut g = c.benchmark_group("plan_16_bodies_with_path");
    if let Ok(mut p) = build("designated-path", &params) {
        g.bench_function("designated-path", |b| {
            b.iter(|| p.plan(std::hint::black_box(&obs)))
        });
    }
    g.finish();
}

/// `orca` as one agent of RVO2's Circle of 250 sees it: 249 other discs of
/// radius 1.5 on a jittered grid 4 apart (13 within `neighbor_dist` 15, 10
/// used), all moving; compare with RVO2's `doStep` / 250 (BENCHMARKS.md).
fn bench_orca_crowd(c: &mut Criterion) {
    let others: Vec<Sensed> = (0..250)
        .filter(|&k| k != 125)
        .map(|k| {
            let (i, j) = ((k % 25) as f64 - 12.0, (k / 25) as f64 - 5.0);
            let wobble = (k as f64 * 1.7).sin();
            Sensed::disc(
                k as u32,
                BodyKind::Robot,
                Vec2::new(i * 4.0 + 0.3 * wobble, j * 4.0 - 0.2 * wobble),
                Vec2::new((k as f64).cos(), (k as f64 * 0.3).sin()),
                1.5,
            )
        })
        .collect();
    let obs = Observation {
        tick: 10,
        time: 2.5,
        dt: 0.25,
        me: SelfState {
            id: 125,
            position: Vec2::new(0.1, 0.05),
            velocity: Vec2::new(0.9, 0.2),
            radius: 1.5,
            shape: mrsim_planners::Shape::disc(1.5),
            mass: 1.0,
            damping: 0.0,
            max_speed: 2.0,
            max_accel: 1e9,
            heading: 0.0,
            angular_velocity: 0.0,
            steering: 0.0,
            kinematics: mrsim_planners::Kinematics::Holonomic,
        },
        goal: Vec2::new(200.0, 0.0),
        goal_tolerance: 1.5,
        goal_hold_ticks: 3,
        others: &others,
        walls: &[],
        path: None,
        scan: None,
    };
    let mut g = c.benchmark_group("orca_circle_250");
    if let Ok(mut p) = build("orca", &Params::new()) {
        g.bench_function("one_agent_249_others", |b| {
            b.iter(|| p.plan(std::hint::black_box(&obs)))
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    bench,
    bench_designated_path,
    zhu_loh,
    bench_orca_crowd
);
criterion_main!(benches);
