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
        &run_id("ppl-crossing"),
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

/// A robot passing 0.15 m from a standing person, one driving into
/// another standing person, and two robots head-on into each other, all on
/// `homing` (which avoids nothing); the people do not see the robots.
const CLOSE: &str = r#"
[world]
dt = 0.1
duration = 6.0

[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 4.0
planner = "homing"

[[robot]]
name = "passer"
start = [-3.0, 0.0]
goal = [5.0, 0.0]

[[robot]]
name = "bumper"
start = [-3.0, 5.0]
goal = [5.0, 5.0]

[[robot]]
name = "r1"
start = [-3.0, 10.0]
goal = [3.0, 10.0]

[[robot]]
name = "r2"
start = [3.0, 10.0]
goal = [-3.0, 10.0]

[[person]]
name = "near"
start = [0.0, 0.75]
goal = [0.0, 0.75]
radius = 0.3
sees_robots = false

[[person]]
name = "hit"
start = [0.0, 5.0]
goal = [0.0, 5.0]
radius = 0.3
sees_robots = false
"#;

/// Seconds `robot` spent with its surface within `limit` of any person's,
/// from trajectory.csv (radii 0.3 each), and the smallest such gap, over
/// the ticks after the first.
fn person_gaps(rows: &[Row], robot: &str, limit: f64) -> (f64, f64) {
    let people: Vec<&Row> = rows.iter().filter(|r| r.kind == "person").collect();
    let (mut time, mut min) = (0.0, f64::INFINITY);
    let mut prev = None;
    for r in track(rows, robot) {
        let gap = people
            .iter()
            .filter(|p| p.tick == r.tick)
            .map(|p| (p.x - r.x).hypot(p.y - r.y) - 0.6)
            .fold(f64::INFINITY, f64::min);
        if let Some(t0) = prev {
            min = min.min(gap);
            if gap < limit {
                time += r.time - t0;
            }
        }
        prev = Some(r.time);
    }
    (time, min)
}

#[test]
fn metrics_count_a_robots_discomfort_and_contacts_with_people_apart_from_those_with_robots() {
    let out = fresh_dir("people-close");
    let file = out.join("close.toml");
    std::fs::write(&file, CLOSE).expect("the scene");
    let dir = out.join("run");
    let o = run(
        &file,
        &dir,
        &run_id("people-close"),
        &["--transport", "inproc", "--quiet"],
    );
    assert_ok(&o);
    let m = metrics(&dir);
    let rows = trajectory(&dir);
    let robot = |name: &str| &m["robots"][name];
    let f = |v: &serde_json::Value| v.as_f64().expect("a number");
    // The passer: within 0.2 m of `near` for a while, never touching.
    let (discomfort, min_gap) = person_gaps(&rows, "passer", 0.2);
    let passer = robot("passer");
    assert!(discomfort > 0.0 && min_gap > 0.0, "{discomfort} {min_gap}");
    assert!(
        (f(&passer["discomfort_time"]) - discomfort).abs() < 1e-9,
        "metrics {} trajectory {discomfort}: {m:#}",
        passer["discomfort_time"]
    );
    assert!(
        (f(&passer["person_min_clearance"]) - min_gap).abs() < 1e-5,
        "{m:#}"
    );
    assert_eq!(passer["person_collisions"], 0, "{m:#}");
    assert_eq!(passer["collisions"], 0, "{m:#}");
    // Its clearance to robots and obstacles leaves the people out: the
    // nearest robot is the bumper, 5 m off.
    assert!(f(&passer["min_clearance"]) > 4.0, "{m:#}");
    // Time within the intimate distance of a person is at least the
    // discomfort time, and the robots' proxemic times have no person in them.
    assert!(f(&passer["person_time_intimate"]) >= discomfort, "{m:#}");
    assert_eq!(f(&passer["time_intimate"]), 0.0, "{m:#}");
    // The bumper touched a person and nothing else; r1 and r2 each other.
    let bumper = robot("bumper");
    assert!(bumper["person_collisions"].as_u64() >= Some(1), "{m:#}");
    assert_eq!(bumper["collisions"], 0, "{m:#}");
    assert!(f(&bumper["person_min_clearance"]) < 0.0, "{m:#}");
    for r in ["r1", "r2"] {
        assert!(robot(r)["collisions"].as_u64() >= Some(1), "{m:#}");
        assert_eq!(robot(r)["person_collisions"], 0, "{m:#}");
    }
    assert_eq!(
        m["person_collisions_total"], bumper["person_collisions"],
        "{m:#}"
    );
    assert_eq!(m["collisions_total"], robot("r1")["collisions"], "{m:#}");
    let total: f64 = ["passer", "bumper", "r1", "r2"]
        .iter()
        .map(|r| f(&robot(r)["discomfort_time"]))
        .sum();
    assert!((f(&m["discomfort_time"]) - total).abs() < 1e-9, "{m:#}");
    // encounters.csv says what the other body was.
    let enc = std::fs::read_to_string(dir.join("encounters.csv")).expect("encounters.csv");
    let kind_of = |a: &str, b: &str| {
        enc.lines()
            .find(|l| l.starts_with(&format!("{a},{b},")))
            .and_then(|l| l.rsplit(',').next())
            .map(str::to_string)
    };
    assert_eq!(
        kind_of("passer", "near").as_deref(),
        Some("person"),
        "{enc}"
    );
    assert_eq!(kind_of("bumper", "hit").as_deref(), Some("person"), "{enc}");
    assert_eq!(kind_of("r1", "r2").as_deref(), Some("robot"), "{enc}");
    // The replay page has the people, at their trajectory's positions, in
    // their own colour.
    let page = std::fs::read_to_string(dir.join("replay.html")).expect("replay.html");
    let open = r#"<script id="mrsim-data" type="application/json">"#;
    let data = page
        .split_once(open)
        .and_then(|(_, rest)| rest.split_once("</script>"))
        .map(|(d, _)| d)
        .expect("the page's data");
    let data: serde_json::Value = serde_json::from_str(data).expect("the data is JSON");
    let people = data["people"].as_array().expect("people");
    let names: Vec<&str> = people.iter().filter_map(|p| p["name"].as_str()).collect();
    assert_eq!(names, ["near", "hit"]);
    let near0 = track(&rows, "near")[0];
    assert!((f(&people[0]["x"][0]) - near0.x).abs() < 1e-3);
    assert!((f(&people[0]["y"][0]) - near0.y).abs() < 1e-3);
    assert_eq!(data["personColor"], "#f4a460");
    let _ = std::fs::remove_dir_all(&out);
}
