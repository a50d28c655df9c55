//! BENCHMARKS.md "Robots, scans and maps": the cost of a 400 x 400 map's
//! load, of 64 robots' 360-beam scans (in that map and in the shipped
//! office map; all in one thread, as the world would compute them, and
//! each robot's on its own in threads over every CPU, as the agents do),
//! and of the world's tick with that map against the same scene without
//! it. The map is made here (a 20 m square at 0.05 m a cell, a border and
//! a 9 x 9 grid of 0.5 m pillars), not committed. Run with
//! `cargo run --release -p mrsim-world --example robots_cost`.

use mrsim_lidar::{Scanner, Walls};
use mrsim_planners::lidar::LaserScan;
use mrsim_proto::BodyState;
use mrsim_scenario::map::OccupancyMap;
use mrsim_scenario::{Lidar, Scenario, UnknownCells};
use std::time::Instant;

const CELLS: usize = 400;

/// A PGM of the scene: 0 (black) = occupied, 254 = free.
fn pgm() -> Vec<u8> {
    let mut img = vec![254u8; CELLS * CELLS];
    for y in 0..CELLS {
        for x in 0..CELLS {
            let border = x < 4 || y < 4 || x >= CELLS - 4 || y >= CELLS - 4;
            // Pillars 10 cells wide every 40 cells, from 35.
            let pillar = |c: usize| c >= 35 && (c - 35) % 40 < 10 && c < 365;
            if border || (pillar(x) && pillar(y)) {
                img[y * CELLS + x] = 0;
            }
        }
    }
    let mut out = format!("P5\n{CELLS} {CELLS}\n255\n").into_bytes();
    out.extend_from_slice(&img);
    out
}

/// 64 robots on the free lanes between pillars (lanes at 0.75 m + 2 m k).
fn robots() -> String {
    let mut s = String::new();
    for i in 0..64 {
        let (row, col) = (i / 8, i % 8);
        let x = -10.0 + 2.75 + 2.0 * col as f64;
        let y = -10.0 + 2.75 + 2.0 * row as f64 - 1.0;
        s += &format!(
            "[[robot]]\nname = \"r{i}\"\nstart = [{x}, {y}]\ngoal = [{x}, {}]\n",
            y + 0.5
        );
    }
    s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::temp_dir().join(format!("mrsim-robots-cost-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join("big.pgm"), pgm())?;
    std::fs::write(
        dir.join("big.yaml"),
        "image: big.pgm\nresolution: 0.05\norigin: [-10, -10, 0]\nnegate: 0\n\
         occupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )?;
    let head = "[world]\ndt = 0.1\nsubsteps = 10\nduration = 60.0\n\
                [defaults]\nradius = 0.25\nplanner = \"homing\"\n";
    let with_map = format!("{head}[map]\nfile = \"big.yaml\"\n{}", robots());
    let without = format!("{head}\n{}", robots()).replace(
        "[world]\n",
        "[world]\narena = { min = [-9.8, -9.8], max = [9.8, 9.8] }\n",
    );
    std::fs::write(dir.join("with.toml"), &with_map)?;
    std::fs::write(dir.join("without.toml"), &without)?;

    // Map load: parse, trace and validate the whole scenario, best of 5.
    let mut best = f64::INFINITY;
    let mut loaded = None;
    for _ in 0..5 {
        let t = Instant::now();
        let l = mrsim_scenario::load(&dir.join("with.toml"))?;
        best = best.min(t.elapsed().as_secs_f64());
        loaded = Some(l);
    }
    let with = loaded.ok_or("no load")?.scenario;
    let walls = with.map.as_ref().map_or(0, |m| m.walls);
    println!(
        "400x400 map: scenario load (trace + validate) {:.1} ms best of 5, {walls} wall segments",
        best * 1e3
    );
    let without = mrsim_scenario::load(&dir.join("without.toml"))?.scenario;

    // World tick, every robot under a small force, 200 ticks after 20.
    for (name, s) in [("with the map", &with), ("without (arena only)", &without)] {
        let mut w = mrsim_world::World::new(s)?;
        for i in 0..64 {
            w.set_command(i, mrsim_world::Applied::Force([0.05, 0.05]));
        }
        let mut c = Vec::new();
        for _ in 0..20 {
            w.step(&mut c);
        }
        let (t, mut phys) = (Instant::now(), 0u64);
        for _ in 0..200 {
            w.step(&mut c);
            phys += w.physics_ns();
        }
        println!(
            "world step, 64 robots, {name}: {:.0} us/tick (rapier {:.0} us)",
            t.elapsed().as_secs_f64() * 1e6 / 200.0,
            phys as f64 / 1e3 / 200.0
        );
    }

    // Scans: 64 robots x 360 beams, range 10, among the big map's walls
    // and among the office map's (64 robots on its free cells).
    scan_costs(
        "400 x 400 map",
        &with,
        with.robots.iter().map(|r| r.start).collect(),
    )?;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let office = mrsim_scenario::load(&root.join("scenarios/maps/office.toml"))?.scenario;
    let grid = mrsim_scenario::map::load(&root.join("scenarios/maps/office.yaml"))?;
    scan_costs("office map", &office, free_points(&grid, 64))?;
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

/// `n` points spread over the free cells of `grid` with 0.4 m free around.
fn free_points(grid: &OccupancyMap, n: usize) -> Vec<[f64; 2]> {
    let free = |p: [f64; 2]| {
        [-0.4, 0.0, 0.4].iter().all(|dx| {
            [-0.4, 0.0, 0.4].iter().all(|dy| {
                grid.cell_of([p[0] + dx, p[1] + dy])
                    .is_some_and(|(i, j)| !grid.is_wall(i, j, UnknownCells::Occupied))
            })
        })
    };
    let mut all = Vec::new();
    for j in -70..70 {
        for i in -120..120 {
            let p = [f64::from(i) * 0.1, f64::from(j) * 0.1];
            if free(p) {
                all.push(p);
            }
        }
    }
    let step = (all.len() / n).max(1);
    all.into_iter().step_by(step).take(n).collect()
}

/// Prints the cost of one tick's scans of robots at `at` (360 beams,
/// 10 m) among the walls of `scenario`: every scan in one thread with one
/// scanner (the world's way), and each robot's own scanner in threads
/// over every CPU (the agents' way: what a tick waits for).
fn scan_costs(
    name: &str,
    scenario: &Scenario,
    at: Vec<[f64; 2]>,
) -> Result<(), Box<dyn std::error::Error>> {
    let segments = scenario.all_walls();
    let t = Instant::now();
    let walls = Walls::new(segments.iter().copied());
    let build_us = t.elapsed().as_secs_f64() * 1e6;
    let mut spec = scenario.robots.first().ok_or("no robot")?.clone();
    spec.sensor = Some(Lidar {
        beams: 360,
        fov_deg: 360.0,
        range: 10.0,
        noise: 0.0,
        record: false,
    });
    let bodies: Vec<BodyState> = at
        .iter()
        .enumerate()
        .map(|(i, p)| BodyState {
            id: i as u32,
            position: *p,
            radius: spec.radius,
            heading: 0.3 * i as f64,
            ..Default::default()
        })
        .collect();
    let n = bodies.len();
    let rounds = 50;
    // The world's way: one thread, one scanner, every robot each tick.
    let mut scanner = Scanner::new(walls.clone());
    let mut scan = LaserScan::default();
    let mut hits = 0usize;
    let t = Instant::now();
    for tick in 0..rounds {
        for me in 0..n {
            scanner.scan_robot(&mut scan, 1, tick, me, &spec, &bodies, &[]);
            hits += scan.ranges.iter().filter(|r| r.is_finite()).count();
        }
    }
    let serial_us = t.elapsed().as_secs_f64() * 1e6 / rounds as f64;
    // The agents' way: each robot its own scanner, the robots shared out
    // over one thread per CPU.
    let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
    let mut scanners: Vec<Scanner> = (0..n).map(|_| Scanner::new(walls.clone())).collect();
    let t = Instant::now();
    for tick in 0..rounds {
        std::thread::scope(|s| {
            for (c, chunk) in scanners.chunks_mut(n.div_ceil(cpus)).enumerate() {
                let (bodies, spec) = (&bodies, &spec);
                s.spawn(move || {
                    let mut scan = LaserScan::default();
                    for (k, sc) in chunk.iter_mut().enumerate() {
                        let me = c * n.div_ceil(cpus) + k;
                        sc.scan_robot(&mut scan, 1, tick, me, spec, bodies, &[]);
                    }
                });
            }
        });
    }
    let parallel_us = t.elapsed().as_secs_f64() * 1e6 / rounds as f64;
    println!(
        "scans, {name}, {n} robots x 360 beams among {} walls (built in {build_us:.0} us): \
         one thread {serial_us:.0} us/tick ({:.0} us a scan, {:.0}% of beams hit); \
         {cpus} threads {parallel_us:.0} us/tick",
        walls.len(),
        serial_us / n as f64,
        100.0 * hits as f64 / (rounds as usize * n * 360) as f64,
    );
    Ok(())
}
