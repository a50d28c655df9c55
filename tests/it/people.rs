//! People end to end: a planner senses them as bodies of kind person, its
//! laser scan hits them, trajectory.csv names them `person`, and the
//! shipped crowd scene runs.

use crate::common::*;
use mrsim::{BodyKind, Command, InProcess, Observation, Planner, Registry, ScenarioSource, Vec2};
use std::sync::{Arc, Mutex};

/// What the planner saw at its first tick: each sensed body's id and
/// kind, and its scan's range along +x.
type Seen = Arc<Mutex<Option<(Vec<(u32, BodyKind)>, f64)>>>;

/// Stands still and notes what it senses at its first tick.
struct Looker(Seen);

impl Planner for Looker {
    fn plan(&mut self, obs: &Observation) -> Command {
        if let Ok(mut seen) = self.0.lock()
            && seen.is_none()
        {
            let kinds = obs.others.iter().map(|o| (o.id, o.kind)).collect();
            // The beam along +x (the holonomic robot's frame is the
            // world's).
            let first = obs.scan.map_or(f64::NAN, |s| {
                let k = (-s.angle_min / s.angle_increment).round() as usize;
                s.ranges[k]
            });
            *seen = Some((kinds, first));
        }
        Command::Velocity(Vec2::zeros())
    }
}

const SCENE: &str = r#"
[world]
dt = 0.1
duration = 1.0

[[robot]]
name = "looker"
start = [0.0, 0.0]
goal = [0.0, 0.0]
planner = "looker"
sensor = { kind = "lidar", beams = 4, fov_deg = 360, range = 8.0, record = true }

[[obstacle]]
name = "post"
start = [0.0, 5.0]
radius = 0.2

[[person]]
name = "ahead"
start = [2.0, 0.0]
goal = [2.0, 0.0]
radius = 0.3
"#;

#[test]
fn a_planner_senses_people_as_persons_its_scan_hits_them_and_the_trajectory_names_them() {
    let seen: Seen = Arc::default();
    let mut registry = Registry::builtin();
    let log = seen.clone();
    registry
        .register_simple("looker", "stands and looks", move || Looker(log.clone()))
        .expect("a new name");
    let out = fresh_dir("people-seen");
    let file = out.join("people.toml");
    std::fs::write(&file, SCENE).expect("the scene");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(file),
            ..Default::default()
        },
        registry: Arc::new(registry),
        out: Some(out.join("run")),
        render: false,
        plan_timeout: None,
    })
    .expect("the run");
    let (kinds, first) = seen.lock().expect("seen").clone().expect("a first tick");
    assert_eq!(kinds, vec![(1, BodyKind::Obstacle), (2, BodyKind::Person)]);
    // The beam along +x meets the person's disc 2 - 0.3 away.
    assert!((first - 1.7).abs() < 1e-6, "{first}");
    let rows = trajectory(&result.dir);
    let person = track(&rows, "ahead");
    assert!(!person.is_empty() && person.iter().all(|r| r.kind == "person"));
    assert!(track(&rows, "post").iter().all(|r| r.kind == "obstacle"));
    // A person whose goal is its start stays there.
    assert!(person.iter().all(|r| r.x == 2.0 && r.y == 0.0));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn the_shipped_crowd_scene_runs_with_its_people_in_the_trajectory() {
    let out = fresh_dir("people-crossing");
    let o = run(
        &root().join("scenarios/people/crossing.toml"),
        &out,
        &run_id("people-crossing"),
        &["--transport", "inproc", "--quiet", "--no-report"],
    );
    assert_ok(&o);
    let rows = trajectory(&out);
    for k in 0..8 {
        let t = track(&rows, &format!("p{k}"));
        assert!(
            !t.is_empty() && t.iter().all(|r| r.kind == "person"),
            "p{k}"
        );
    }
    // The people who walk across reach the other side.
    let p4 = track(&rows, "p4");
    let last = p4.last().expect("rows");
    assert!(
        (last.x + 2.0).hypot(last.y + 3.5) < 0.3,
        "p4 ends at {}, {}",
        last.x,
        last.y
    );
    let _ = std::fs::remove_dir_all(&out);
}
