//! BENCHMARKS.md "Robots, scans and maps": the cost of a 400 x 400 map's
//! load, of 64 robots' 360-beam scans, and of the world's tick with that
//! map against the same scene without it. The map is made here (a 20 m
//! square at 0.05 m a cell, a border and a 9 x 9 grid of 0.5 m pillars),
//! not committed. Run with
//! `cargo run --release -p mrsim-world --example robots_cost`.

use mrsim_planners::lidar::{LaserScan, LidarConfig};
use mrsim_planners::{Segment, Vec2};
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
    let without = format!("{head}\n{}", robots().replacen("[[robot]]", "[[robot]]", 1)).replace(
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

    // Scans: 64 robots x 360 beams, range 10, among the map's walls and
    // the 63 other discs.
    let segs: Vec<Segment> = with
        .all_walls()
        .iter()
        .map(|w| Segment {
            a: Vec2::new(w[0][0], w[0][1]),
            b: Vec2::new(w[1][0], w[1][1]),
        })
        .collect();
    let discs: Vec<(Vec2, f64)> = with
        .robots
        .iter()
        .map(|r| (Vec2::new(r.start[0], r.start[1]), r.radius))
        .collect();
    let cfg = LidarConfig {
        beams: 360,
        fov: std::f64::consts::TAU,
        range: 10.0,
        noise: 0.0,
    };
    let mut scan = LaserScan::default();
    let rounds = 20;
    let t = Instant::now();
    for _ in 0..rounds {
        for (me, (p, _)) in discs.iter().enumerate() {
            let others = discs
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != me)
                .map(|(_, d)| *d);
            mrsim_planners::lidar::scan(&mut scan, &cfg, *p, 0.0, others, &segs, &mut || 0.0);
        }
    }
    let per_tick = t.elapsed().as_secs_f64() * 1e6 / rounds as f64;
    println!(
        "scans, 64 robots x 360 beams among {} walls: {:.0} us per tick for all ({:.0} us per scan)",
        segs.len(),
        per_tick,
        per_tick / 64.0
    );
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
