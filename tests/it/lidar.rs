//! The laser scan end to end: what a planner gets in its observation is,
//! range for range, what the world writes to scan.csv (one scanner,
//! `mrsim-lidar`, on both sides, with the same noise stream).

use crate::common::*;
use mrsim::{Command, InProcess, Observation, Planner, Registry, ScenarioSource, Vec2};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// The scans a robot got, by tick, as scan.csv writes them.
type Seen = Arc<Mutex<BTreeMap<u64, String>>>;

/// Goes straight for the goal and notes every scan it gets.
struct ScanLogger(Seen);

impl Planner for ScanLogger {
    fn plan(&mut self, obs: &Observation) -> Command {
        if let Some(s) = obs.scan {
            let mut row = format!("{},{},{}", s.angle_min, s.angle_increment, s.range_max);
            for r in &s.ranges {
                if r.is_finite() {
                    row += &format!(",{r:.6}");
                } else {
                    row += ",inf";
                }
            }
            if let Ok(mut seen) = self.0.lock() {
                seen.insert(obs.tick, row);
            }
        }
        let to_goal: Vec2 = obs.goal - obs.me.position;
        Command::Velocity(to_goal.cap_magnitude(obs.me.max_speed))
    }
}

#[test]
fn the_recorded_scans_are_the_scans_the_planner_got() {
    let seen: Seen = Arc::default();
    let mut registry = Registry::builtin();
    let log = seen.clone();
    registry
        .register_simple("scan-logger", "notes its scans", move || {
            ScanLogger(log.clone())
        })
        .expect("a new name");
    let out = fresh_dir("lidar-seen");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(root().join("scenarios/lidar-demo.toml")),
            set: vec![
                "robot.scout.planner=scan-logger".to_string(),
                "world.duration=8".to_string(),
            ],
            ..Default::default()
        },
        registry: Arc::new(registry),
        out: Some(out.clone()),
        render: false,
        plan_timeout: None,
    })
    .expect("the run");
    let text = std::fs::read_to_string(result.dir.join("scan.csv")).expect("scan.csv");
    let seen = seen.lock().expect("the planner's scans");
    let mut compared = 0;
    for line in text.lines().skip(1) {
        let mut cells = line.splitn(3, ',');
        let (Some(tick), Some(robot), Some(rest)) = (cells.next(), cells.next(), cells.next())
        else {
            panic!("short row {line}");
        };
        assert_eq!(robot, "scout", "only scout records");
        let tick: u64 = tick.parse().expect("tick");
        if let Some(got) = seen.get(&tick) {
            assert_eq!(rest, got, "tick {tick}");
            compared += 1;
        }
    }
    // 8 s at dt 0.1: every tick the planner was asked about.
    assert!(compared >= 79, "{compared} ticks compared");
    let _ = std::fs::remove_dir_all(&out);
}

/// scan.csv's tick-0 ranges of the lidar demo (scout's 360 beams) with the
/// scanner's noise `noise` and the world's seed `seed`.
fn first_scan(noise: f64, seed: u64, tag: &str) -> Vec<f64> {
    let out = fresh_dir(tag);
    let o = run(
        &root().join("scenarios/lidar-demo.toml"),
        &out,
        &run_id(tag),
        &[
            "--transport",
            "inproc",
            "--quiet",
            "--no-report",
            "--set",
            "world.duration=0.2",
            "--set",
            &format!("world.seed={seed}"),
            "--set",
            &format!(
                "robot.scout.sensor={{ kind = \"lidar\", beams = 360, fov_deg = 360, range = 8.0, noise = {noise}, record = true }}"
            ),
        ],
    );
    assert_ok(&o);
    let text = std::fs::read_to_string(out.join("scan.csv")).expect("scan.csv");
    let row = text.lines().nth(1).expect("a first row");
    let ranges: Vec<f64> = row
        .split(',')
        .skip(5)
        .map(|c| {
            if c == "inf" {
                f64::INFINITY
            } else {
                c.parse().expect("a range")
            }
        })
        .collect();
    assert_eq!(ranges.len(), 360, "{row}");
    let _ = std::fs::remove_dir_all(&out);
    ranges
}

#[test]
fn lidar_noise_has_the_configured_sigma_and_repeats_with_the_seed_only() {
    let exact = first_scan(0.0, 3, "noise0");
    let noisy = first_scan(0.05, 3, "noise5");
    // The beams that hit something well inside the range (no clamping).
    let errors: Vec<f64> = exact
        .iter()
        .zip(&noisy)
        .filter(|(e, _)| e.is_finite() && **e > 0.5 && **e < 7.5)
        .map(|(e, n)| n - e)
        .collect();
    assert!(errors.len() > 200, "{} beams compared", errors.len());
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let sigma = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    // With 200+ samples the estimate is within about 5 % of 0.05 (1 sigma);
    // 20 % is four of those.
    assert!((sigma - 0.05).abs() < 0.01, "sigma {sigma}");
    assert!(mean.abs() < 0.01, "mean {mean}");
    // Seeded: the same seed gives the same noise, another seed other noise.
    assert_eq!(noisy, first_scan(0.05, 3, "noise5-again"));
    let other = first_scan(0.05, 4, "noise5-seed4");
    assert_ne!(noisy, other);
}

/// The office's TurtleBots, driven by dwa from their scans alone, for 15 s
/// in lockstep over `transport`, every scan recorded; the run folder.
fn office_scans_over(transport: &str) -> std::path::PathBuf {
    let out = fresh_dir(&format!("lidar-over-{transport}"));
    let o = run(
        &root().join("scenarios/maps/office-turtlebots.toml"),
        &out,
        &run_id(&format!("lidar-{transport}")),
        &[
            "--quiet",
            "--no-report",
            "--transport",
            transport,
            "--set",
            "world.duration=15",
            "--set",
            "defaults.sensor.record=true",
        ],
    );
    assert_ok(&o);
    out
}

#[test]
fn agents_over_shared_memory_and_zenoh_get_the_scans_of_an_in_process_run() {
    // Every planner here sees the world only through its scan: one range
    // off anywhere and the trajectories part. The world records the scan
    // it computes (scan.csv); the agents, in their own processes over
    // iceoryx2 or Zenoh, compute theirs from the snapshots they receive.
    let inproc = office_scans_over("inproc");
    let scans = std::fs::read(inproc.join("scan.csv")).expect("scan.csv");
    assert!(
        scans.len() > 100_000,
        "scans recorded: {} bytes",
        scans.len()
    );
    let trajectory = std::fs::read(inproc.join("trajectory.csv")).expect("trajectory.csv");
    for transport in ["shm", "zenoh"] {
        let out = office_scans_over(transport);
        assert!(
            std::fs::read(out.join("trajectory.csv")).expect("trajectory.csv") == trajectory,
            "{transport}: the trajectory differs from the in-process run's"
        );
        assert!(
            std::fs::read(out.join("scan.csv")).expect("scan.csv") == scans,
            "{transport}: scan.csv differs from the in-process run's"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
    let _ = std::fs::remove_dir_all(&inproc);
}

/// What a standing robot sensed each tick: the bodies and its scan as
/// scan.csv writes it.
type Sensings = Arc<Mutex<BTreeMap<u64, (Vec<mrsim::Sensed>, String)>>>;

/// Stands still and notes what it senses.
struct Seer(Sensings);

impl Planner for Seer {
    fn plan(&mut self, obs: &Observation) -> Command {
        let mut row = String::new();
        if let Some(s) = obs.scan {
            row = format!("{},{},{}", s.angle_min, s.angle_increment, s.range_max);
            for r in &s.ranges {
                row += &if r.is_finite() {
                    format!(",{r:.6}")
                } else {
                    ",inf".to_string()
                };
            }
        }
        if let Ok(mut seen) = self.0.lock() {
            seen.insert(obs.tick, (obs.others.to_vec(), row));
        }
        Command::Velocity(Vec2::zeros())
    }
}

#[test]
fn a_turned_rectangle_reaches_the_planner_and_scan_csv_as_a_rectangle() {
    let dir = fresh_dir("lidar-box");
    let scenario = dir.join("box.toml");
    // A 2 x 1 box centred at (3, 0) turned 30 degrees: the beam along +x
    // from the origin meets its long side at x = 2 (see the lidar crate's
    // analytic test, the box there at (4, 0)); its disc, of radius
    // sqrt(1.25) = 1.118, would be met at 1.882.
    std::fs::write(
        &scenario,
        r#"
name = "box"
[world]
dt = 0.1
duration = 1.0
[[robot]]
name = "scout"
start = [0.0, 0.0]
goal = [0.0, 3.0]
planner = "seer"
sensor = { kind = "lidar", beams = 4, fov_deg = 360, range = 8.0, record = true }
[[obstacle]]
name = "box"
start = [3.0, 0.0]
shape = { kind = "rectangle", length = 2.0, width = 1.0 }
heading_deg = 30
motion = { model = "static" }
"#,
    )
    .expect("write the scenario");
    let seen: Sensings = Arc::default();
    let mut registry = Registry::builtin();
    let log = seen.clone();
    registry
        .register_simple("seer", "stands and notes", move || Seer(log.clone()))
        .expect("a new name");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(scenario),
            ..Default::default()
        },
        registry: Arc::new(registry),
        out: Some(dir.join("run")),
        render: false,
        plan_timeout: None,
    })
    .expect("the run");
    let seen = seen.lock().expect("what it sensed");
    let (others, _) = seen.get(&0).expect("tick 0");
    let b = &others[..];
    assert_eq!(b.len(), 1, "{b:?}");
    let rect = mrsim::Shape::Polygon(mrsim::Polygon::rectangle(2.0, 1.0).expect("a rectangle"));
    assert_eq!(b[0].shape, rect);
    assert!((b[0].heading - 30f64.to_radians()).abs() < 1e-12);
    assert!((b[0].radius - 1.25f64.sqrt()).abs() < 1e-12);
    let text = std::fs::read_to_string(result.dir.join("scan.csv")).expect("scan.csv");
    let mut compared = 0;
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.splitn(3, ',').collect();
        let tick: u64 = cells[0].parse().expect("tick");
        if let Some((_, got)) = seen.get(&tick) {
            assert_eq!(cells[2], got, "tick {tick}");
            compared += 1;
        }
        // Beams -pi, -pi/2, 0, pi/2: the third meets the box's side.
        let ranges: Vec<&str> = cells[2].split(',').skip(3).collect();
        assert_eq!(ranges, ["inf", "inf", "2.000000", "inf"], "{line}");
    }
    assert!(compared >= 9, "{compared} ticks compared");
    let _ = std::fs::remove_dir_all(&dir);
}
