//! The laser scan end to end: what a planner gets in its observation is,
//! range for range, what the world writes to scan.csv (one scanner,
//! `mrsim-lidar`, on both sides, with the same noise stream).

mod common;
use common::*;
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
