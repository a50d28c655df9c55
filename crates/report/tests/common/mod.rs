//! A synthetic run folder in exactly the format the world writes.
#![allow(dead_code)]

use mrsim_scenario::{
    Arena, LengthUnit, Mode, Motion, ObstacleSpec, RobotSpec, Scenario, VelocitySource, WorldConfig,
};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Ticks of the synthetic run (0..=TICKS).
pub const TICKS: u64 = 40;
/// Tick of the collision between r2 and o1 in the 3-robot run.
pub const COLLISION_TICK: u64 = 20;
pub const DT: f64 = 0.1;

/// A fresh, empty folder under the system temp dir, removed when dropped
/// unless the test is failing (then it is kept to look at).
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

pub fn temp_dir(tag: &str) -> TempDir {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "mrsim-report-{tag}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

fn robot(name: &str, start: [f64; 2], goal: [f64; 2]) -> RobotSpec {
    RobotSpec {
        name: name.into(),
        start,
        goal,
        planner: "homing".into(),
        params: BTreeMap::new(),
        radius: 0.3,
        shape: Default::default(),
        mass: 1.0,
        damping: 0.0,
        max_speed: 2.0,
        max_accel: 2.0,
        velocity_lag: 0.0,
        sensing_range: 5.0,
        field_of_view_deg: 360.0,
        goal_tolerance: 0.1,
        goal_hold_ticks: 1,
        velocity_source: VelocitySource::Truth,
        position_noise: 0.0,
        path: vec![],
        boundary: None,
        kinematics: Default::default(),
        max_angular_speed: mrsim_scenario::DEFAULT_MAX_ANGULAR_SPEED,
        max_angular_accel: mrsim_scenario::DEFAULT_MAX_ANGULAR_ACCEL,
        lookahead: mrsim_scenario::DEFAULT_LOOKAHEAD,
        ackermann: None,
        goal_heading: None,
        route: Default::default(),
        lane: Default::default(),
        sensor: None,
        timing: None,
        replay: None,
    }
}

/// Start and goal of robot `i` of `n`: three hand-placed rows for n <= 3,
/// else an antipodal circle.
pub fn start_goal(i: usize, n: usize) -> ([f64; 2], [f64; 2]) {
    if n <= 3 {
        [
            ([-4.0, -3.0], [4.0, -3.0]),
            ([4.0, 0.0], [-4.0, 0.0]),
            ([-4.0, 3.0], [4.0, 3.0]),
        ][i]
    } else {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        (
            [4.0 * a.cos(), 4.0 * a.sin()],
            [-4.0 * a.cos(), -4.0 * a.sin()],
        )
    }
}

/// Robot `i` of `n` at `tick`: straight from start to goal over TICKS.
pub fn robot_at(i: usize, n: usize, tick: u64) -> [f64; 2] {
    let (s, g) = start_goal(i, n);
    let k = tick as f64 / TICKS as f64;
    [s[0] + (g[0] - s[0]) * k, s[1] + (g[1] - s[1]) * k]
}

/// The obstacle at `tick`: from (0, 4.5) down at 0.5 m/s.
pub fn obstacle_at(tick: u64) -> [f64; 2] {
    [0.0, 4.5 - 0.5 * tick as f64 * DT]
}

pub fn scenario(n: usize) -> Scenario {
    Scenario {
        name: format!("synthetic-{n}"),
        description: "report crate test run".into(),
        length_unit: LengthUnit::M,
        world: WorldConfig {
            dt: DT,
            substeps: 10,
            duration: TICKS as f64 * DT,
            mode: Mode::Realtime,
            on_deadline_miss: Default::default(),
            seed: 1,
            arena: Some(Arena {
                min: [-5.0, -5.0],
                max: [5.0, 5.0],
            }),
            deadline: 1.0,
            stall_timeout: 2.0,
            robots_per_agent: 1,
            stuck_after: mrsim_scenario::DEFAULT_STUCK_AFTER,
            end_when_stuck: false,
            end_on: Default::default(),
            cpus: None,
        },
        robots: (0..n)
            .map(|i| {
                let (s, g) = start_goal(i, n);
                robot(&format!("r{i}"), s, g)
            })
            .collect(),
        obstacles: vec![ObstacleSpec {
            name: "o1".into(),
            start: obstacle_at(0),
            radius: 0.4,
            shape: Default::default(),
            heading: 0.0,
            motion: Motion::ConstantVelocity {
                velocity: [0.0, -0.5],
            },
        }],
        people: Vec::new(),
        walls: vec![mrsim_scenario::WallSpec {
            segment: [[-1.0, -5.0], [-1.0, -4.0]],
        }],
        map: None,
        output: Default::default(),
    }
}

/// Writes a complete run folder with `n` robots and one obstacle:
/// r2 hits o1 at COLLISION_TICK (n >= 3), r1 misses the deadline at ticks
/// 5 and 6, r2's agent is lost from 25 to 28, everyone reaches the goal at
/// the last tick; diagnostics when `diagnostics` is set.
pub fn write_run(dir: &Path, n: usize, diagnostics: bool) {
    let sc = scenario(n);
    std::fs::write(
        dir.join("scenario.json"),
        serde_json::to_string_pretty(&sc).unwrap(),
    )
    .unwrap();

    let mut csv = String::from("tick,time,body,kind,x,y,vx,vy\n");
    for tick in 0..=TICKS {
        let t = tick as f64 * DT;
        for i in 0..n {
            let p = robot_at(i, n, tick);
            let (s, g) = start_goal(i, n);
            let v = [
                (g[0] - s[0]) / (TICKS as f64 * DT),
                (g[1] - s[1]) / (TICKS as f64 * DT),
            ];
            writeln!(
                csv,
                "{tick},{t},r{i},robot,{},{},{},{}",
                p[0], p[1], v[0], v[1]
            )
            .unwrap();
        }
        let o = obstacle_at(tick);
        writeln!(csv, "{tick},{t},o1,obstacle,{},{},0,-0.5", o[0], o[1]).unwrap();
    }
    std::fs::write(dir.join("trajectory.csv"), csv).unwrap();

    let mut ev = String::new();
    let t = |tick: u64| tick as f64 * DT;
    if n > 1 {
        for tick in [5u64, 6] {
            writeln!(
                ev,
                r#"{{"tick":{tick},"time":{},"type":"deadline_miss","robot":"r1","late_us":1500}}"#,
                t(tick)
            )
            .unwrap();
        }
    }
    if n >= 3 {
        let r = robot_at(2, n, COLLISION_TICK);
        let o = obstacle_at(COLLISION_TICK);
        let (x, y) = ((r[0] + o[0]) / 2.0, (r[1] + o[1]) / 2.0);
        writeln!(ev, r#"{{"tick":{COLLISION_TICK},"time":{},"type":"collision","a":"r2","b":"o1","x":{x},"y":{y}}}"#, t(COLLISION_TICK)).unwrap();
        writeln!(
            ev,
            r#"{{"tick":25,"time":{},"type":"agent_lost","robot":"r2","reason":"stalled"}}"#,
            t(25)
        )
        .unwrap();
        writeln!(
            ev,
            r#"{{"tick":28,"time":{},"type":"agent_rejoined","robot":"r2"}}"#,
            t(28)
        )
        .unwrap();
    }
    writeln!(
        ev,
        r#"{{"tick":3,"time":0.3,"type":"a_type_from_the_future","robot":"r0","extra":[1,2]}}"#
    )
    .unwrap();
    writeln!(
        ev,
        r#"{{"tick":4,"time":0.4,"type":"command_rejected","robot":"r0","reason":"not its robot"}}"#
    )
    .unwrap();
    for i in 0..n {
        writeln!(
            ev,
            r#"{{"tick":{TICKS},"time":{},"type":"goal_reached","robot":"r{i}"}}"#,
            t(TICKS)
        )
        .unwrap();
    }
    std::fs::write(dir.join("events.jsonl"), ev).unwrap();

    let robots: serde_json::Map<String, serde_json::Value> = (0..n)
        .map(|i| {
            (
                format!("r{i}"),
                serde_json::json!({
                    "reached_goal": true, "time_to_goal": TICKS as f64 * DT, "path_length": 8.0,
                    "collisions": if i == 2 { 1 } else { 0 }, "min_clearance": 0.1, "max_speed": 2.0,
                    "deadline_misses": if i == 1 { 2 } else { 0 },
                    "latency_us": {"p50": 50.0, "p99": 90.0, "p999": 120.0, "max": 1500.0},
                    "compute_us": {"p50": 5.0, "p99": 9.0, "max": 12.0},
                    "agent_pid": 1000 + i, "planner": "homing"
                }),
            )
        })
        .collect();
    let metrics = serde_json::json!({
        "robots": robots, "collisions_total": if n >= 3 { 1 } else { 0 }, "success_rate": 1.0,
        "ticks": TICKS, "mode": "realtime", "realtime_factor": 0.98, "agents_lost": 1,
        "commands_rejected": 1, "world_pid": 999
    });
    std::fs::write(dir.join("metrics.json"), metrics.to_string()).unwrap();

    if diagnostics {
        let mut d = String::from("tick,time,robot,name,value\n");
        for tick in 0..=TICKS {
            for i in 0..n {
                writeln!(
                    d,
                    "{tick},{},r{i},potential,{}",
                    t(tick),
                    (tick as f64 * 0.3 + i as f64).sin()
                )
                .unwrap();
                writeln!(d, "{tick},{},r{i},mode,{}", t(tick), (tick / 10) % 2).unwrap();
            }
        }
        std::fs::write(dir.join("diagnostics.csv"), d).unwrap();
    }
}

/// Decodes an RGB or RGBA 8-bit PNG into (width, height, RGB pixels).
pub fn decode_png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("{}: unexpected colour type {other:?}", path.display()),
    };
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width, info.height, pixels)
}

/// Whether two colours differ by at most `tol` in every channel.
pub fn near(a: [u8; 3], b: [u8; 3], tol: u8) -> bool {
    a.iter().zip(b.iter()).all(|(x, y)| x.abs_diff(*y) <= tol)
}

/// A big run in memory: `n` robots on the antipodal circle of
/// [`scenario`], moving in straight lines over ticks 0..=`ticks`, no
/// obstacle track, no events.
pub fn big_run(dir: &Path, n: usize, ticks: u64) -> mrsim_report::RunData {
    let mut sc = scenario(n);
    sc.world.duration = ticks as f64 * DT;
    let bodies = (0..n)
        .map(|i| {
            let (s, g) = start_goal(i, n);
            let samples = (0..=ticks)
                .map(|tick| {
                    let k = tick as f64 / ticks as f64;
                    mrsim_report::Sample {
                        tick,
                        time: tick as f64 * DT,
                        x: s[0] + (g[0] - s[0]) * k,
                        y: s[1] + (g[1] - s[1]) * k,
                        vx: (g[0] - s[0]) / (ticks as f64 * DT),
                        vy: (g[1] - s[1]) / (ticks as f64 * DT),
                        theta: None,
                    }
                })
                .collect();
            mrsim_report::BodyTrack {
                name: format!("r{i}"),
                kind: mrsim_report::BodyKind::Robot,
                samples,
            }
        })
        .collect();
    mrsim_report::RunData {
        dir: dir.to_path_buf(),
        scenario: sc,
        trajectory: mrsim_report::Trajectory {
            ticks: (0..=ticks).collect(),
            times: (0..=ticks).map(|t| t as f64 * DT).collect(),
            bodies,
        },
        events: vec![],
        metrics: None,
        diagnostics: None,
        routes: Default::default(),
        encounters: Vec::new(),
        cut: Vec::new(),
    }
}

/// The JSON a replay page embeds.
pub fn replay_json(dir: &Path) -> serde_json::Value {
    let page = std::fs::read_to_string(dir.join("replay.html")).unwrap();
    let start = page.find(r#"type="application/json">"#).unwrap() + 24;
    let end = start + page[start..].find("</script>").unwrap();
    serde_json::from_str(&page[start..end]).unwrap()
}
