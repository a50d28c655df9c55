//! Robots that arrive in maps: the shipped office scene of TurtleBot3-like
//! differential drives with `route = "shortest"` and dwa from the scan, the
//! same with dwa on true states and with orca; two robots started touching
//! get apart and arrive; two passing close keep their padding; two
//! meeting exactly head-on pass and arrive; robots crossing a corridor
//! both ways from the scan keep right and arrive; the route
//! is written and drawn; unreachable goals, a look-ahead at the goal
//! tolerance, a scan planner without a scanner and a lane without a route
//! are refused with the file, the line and why (exit 2); routes with a lane
//! keep to opposite sides of a corridor; two robots swapping through a
//! one-robot door give way and arrive; an orca unicycle alone passes a
//! door as wide as the disc orca sees it as.

use crate::common::*;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Runs `scenario` in lockstep in-process with `extra` arguments; returns
/// the run folder.
fn run_lockstep(scenario: &Path, tag: &str, extra: &[&str]) -> PathBuf {
    let out = fresh_dir(tag).join("out");
    let mut args = vec!["--mode", "lockstep", "--transport", "inproc"];
    args.extend_from_slice(extra);
    let o = run(scenario, &out, &run_id(tag), &args);
    assert_ok(&o);
    out
}

/// What a run of robots swapping places came to: the share of goals
/// reached, robot-robot contacts, and the deepest any robot went into a
/// map wall (negative clearance, from trajectory.csv).
struct Outcome {
    success: f64,
    robot_contacts: usize,
    robots: usize,
    deepest: f64,
}

fn outcome(scenario: &Path, out: &Path) -> Outcome {
    let s = mrsim_scenario::load(scenario).expect("scenario").scenario;
    let m = metrics(out);
    let names: BTreeSet<String> = s.robots.iter().map(|r| r.name.clone()).collect();
    let robot_contacts = events(out)
        .iter()
        .filter(|e| e["type"] == "collision")
        .filter(|e| {
            [&e["a"], &e["b"]]
                .iter()
                .all(|n| n.as_str().is_some_and(|n| names.contains(n)))
        })
        .count();
    let walls: Vec<[[f64; 2]; 2]> = s.walls.iter().map(|w| w.segment).collect();
    // trajectory.csv with its theta column (unicycles): body, x, y.
    let text = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory.csv");
    let radius: std::collections::BTreeMap<&str, f64> = s
        .robots
        .iter()
        .map(|r| (r.name.as_str(), r.radius))
        .collect();
    let mut deepest = f64::INFINITY;
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let Some(r) = radius.get(f[2]) else { continue };
        let p = [f[4].parse().expect("x"), f[5].parse().expect("y")];
        for w in &walls {
            deepest = deepest.min(segment_distance(p, *w) - r);
        }
    }
    Outcome {
        success: m["success_rate"].as_f64().expect("success_rate"),
        robot_contacts,
        robots: s.robots.len(),
        deepest,
    }
}

/// The bar for robots swapping places in a map: 90 % of the goals,
/// never more than 1 mm into a wall, at most one contact per ten robots.
fn assert_arrived(o: &Outcome, what: &str) {
    assert!(o.success >= 0.9, "{what}: success {}", o.success);
    assert!(o.deepest >= -1e-3, "{what}: {} m into a wall", -o.deepest);
    assert!(
        o.robot_contacts * 10 <= o.robots,
        "{what}: {} robot-robot contacts among {} robots",
        o.robot_contacts,
        o.robots
    );
}

fn office_turtlebots() -> PathBuf {
    root().join("scenarios/maps/office-turtlebots.toml")
}

#[test]
fn turtlebots_with_dwa_from_the_scan_reach_their_goals_across_the_office_by_their_routes() {
    let scenario = office_turtlebots();
    let out = run_lockstep(&scenario, "tb-scan", &[]);
    assert_arrived(&outcome(&scenario, &out), "dwa, scan");
    // The routes are in the run folder, start to goal, and drawn.
    let routes = std::fs::read_to_string(out.join("routes.csv")).expect("routes.csv");
    assert!(routes.starts_with("robot,seq,x,y\n"));
    assert!(routes.lines().any(|l| l.starts_with("tb-a,0,-7.5,5.5")));
    let page = std::fs::read_to_string(out.join("replay.html")).expect("replay.html");
    assert!(page.contains("\"route\":[["));
    // spl measures each robot's path against its route, not against the
    // straight line through the walls: l / max(p, l), l the route's length.
    let mut length: std::collections::BTreeMap<&str, (f64, Option<[f64; 2]>)> = Default::default();
    for line in routes.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let p = [
            f[2].parse::<f64>().expect("x"),
            f[3].parse::<f64>().expect("y"),
        ];
        let e = length.entry(f[0]).or_insert((0.0, None));
        if let Some(q) = e.1 {
            e.0 += (p[0] - q[0]).hypot(p[1] - q[1]);
        }
        e.1 = Some(p);
    }
    let m = metrics(&out);
    let mut mean = 0.0;
    for (name, (l, _)) in &length {
        let r = &m["robots"][*name];
        let p = r["path_length"].as_f64().expect("path_length");
        let want = if r["reached_goal"] == true {
            l / l.max(p)
        } else {
            0.0
        };
        let spl = r["spl"].as_f64().expect("spl");
        assert!((spl - want).abs() < 1e-9, "{name}: spl {spl}, l {l}, p {p}");
        mean += spl / length.len() as f64;
    }
    let run_spl = m["spl"].as_f64().expect("spl");
    assert!(
        (run_spl - mean).abs() < 1e-9,
        "run spl {run_spl}, mean {mean}"
    );
}

#[test]
fn turtlebots_with_dwa_on_true_states_reach_their_goals_across_the_office() {
    let scenario = office_turtlebots();
    let out = run_lockstep(
        &scenario,
        "tb-truth",
        &["--set", "robot.*.params.obstacles=truth"],
    );
    assert_arrived(&outcome(&scenario, &out), "dwa, truth");
}

#[test]
fn turtlebots_with_orca_reach_their_goals_across_the_office() {
    let scenario = office_turtlebots();
    let dir = fresh_dir("tb-orca-src");
    let file = dir.join("orca.toml");
    let src = std::fs::read_to_string(&scenario)
        .unwrap()
        .replace(
            "planner = \"dwa\"\nparams = { obstacles = \"scan\" }",
            "planner = \"orca\"",
        )
        .replace(
            "file = \"office.yaml\"",
            &format!(
                "file = {:?}",
                root()
                    .join("scenarios/maps/office.yaml")
                    .display()
                    .to_string()
            ),
        );
    std::fs::write(&file, src).unwrap();
    let out = run_lockstep(&file, "tb-orca", &[]);
    assert_arrived(&outcome(&file, &out), "orca");
}

/// Writes `src` as a scenario in a fresh folder.
fn scenario_file(tag: &str, src: &str) -> PathBuf {
    let dir = fresh_dir(tag);
    let file = dir.join("s.toml");
    std::fs::write(&file, src).unwrap();
    file
}

#[test]
fn two_differential_drives_started_touching_get_apart_and_arrive() {
    // Face to face, discs touching (0.6 mm apart, radius 0.105),
    // each with its goal behind the other.
    for obstacles in ["truth", "scan"] {
        let src = format!(
            "[world]\nduration = 60.0\narena = {{ min = [-3.0, -3.0], max = [3.0, 3.0] }}\n\
             [defaults]\nplanner = \"dwa\"\nparams = {{ obstacles = \"{obstacles}\" }}\n\
             kinematics = \"unicycle\"\nradius = 0.105\nmax_speed = 0.22\nmax_accel = 2.5\n\
             max_angular_speed = 2.84\nmax_angular_accel = 3.2\ngoal_tolerance = 0.1\n\
             sensor = {{ kind = \"lidar\", beams = 360, range = 3.5 }}\n\
             [[robot]]\nname = \"a\"\nstart = [-0.1053, 0.0]\ngoal = [2.0, 0.0]\n\
             [[robot]]\nname = \"b\"\nstart = [0.1053, 0.0]\ngoal = [-2.0, 0.0]\n"
        );
        let file = scenario_file(&format!("touch-{obstacles}"), &src);
        let out = run_lockstep(&file, &format!("tch-{obstacles}"), &[]);
        let m = metrics(&out);
        for r in ["a", "b"] {
            assert_eq!(
                m["robots"][r]["reached_goal"], true,
                "{obstacles}: {r}: {m:#}"
            );
        }
    }
}

#[test]
fn two_differential_drives_grazing_past_each_other_keep_the_padding() {
    // Pioneer-like, head-on on lines 0.5 m apart: going straight, their
    // discs (radius 0.25) would just touch. dwa keeps its padding (a
    // quarter of the radius, 0.0625 m) from the other, from true states
    // and from the scan alike, and both arrive.
    for obstacles in ["truth", "scan"] {
        let src = format!(
            "[world]\nduration = 40.0\narena = {{ min = [-4.0, -3.0], max = [4.0, 3.0] }}\n\
             [defaults]\nplanner = \"dwa\"\nparams = {{ obstacles = \"{obstacles}\" }}\n\
             kinematics = \"unicycle\"\nradius = 0.25\nmax_speed = 0.6\nmax_accel = 1.0\n\
             max_angular_speed = 1.8\nmax_angular_accel = 3.0\ngoal_tolerance = 0.2\n\
             sensor = {{ kind = \"lidar\", beams = 180, range = 8.0 }}\n\
             [[robot]]\nname = \"a\"\nstart = [-3.0, 0.25]\ngoal = [3.0, 0.25]\n\
             [[robot]]\nname = \"b\"\nstart = [3.0, -0.25]\ngoal = [-3.0, -0.25]\n"
        );
        let file = scenario_file(&format!("graze-{obstacles}"), &src);
        let out = run_lockstep(&file, &format!("grz-{obstacles}"), &[]);
        let m = metrics(&out);
        for r in ["a", "b"] {
            assert_eq!(
                m["robots"][r]["reached_goal"], true,
                "{obstacles}: {r}: {m:#}"
            );
        }
        // Per tick, the two centres (trajectory.csv: tick, time, body,
        // kind, x, y, ...).
        let text = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory.csv");
        let mut at: std::collections::BTreeMap<u64, [Option<[f64; 2]>; 2]> = Default::default();
        for line in text.lines().skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            let k = ["a", "b"].iter().position(|n| *n == f[2]);
            if let Some(k) = k {
                let p = [f[4].parse().expect("x"), f[5].parse().expect("y")];
                at.entry(f[0].parse().expect("tick")).or_default()[k] = Some(p);
            }
        }
        let gap = at
            .values()
            .filter_map(|[a, b]| Some((a.as_ref()?, b.as_ref()?)))
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) - 0.5)
            .fold(f64::INFINITY, f64::min);
        assert!(gap >= 0.0625, "{obstacles}: the discs came within {gap}");
    }
}

#[test]
fn two_differential_drives_meeting_exactly_head_on_pass_and_arrive() {
    // On one line, each with its goal where the other starts: the scene is
    // its own mirror image, and without a rule each swerves to the side
    // the other does, or both stop face to face. From the scan and from
    // true states, TurtleBot3-like and Pioneer-like, both arrive untouched.
    let limits = [
        (
            "tb3",
            "radius = 0.105\nmax_speed = 0.22\nmax_accel = 2.5\nmax_angular_speed = 2.84\n\
             max_angular_accel = 3.2\ngoal_tolerance = 0.1\n\
             sensor = { kind = \"lidar\", beams = 360, range = 3.5 }\n",
        ),
        (
            "pio",
            "radius = 0.25\nmax_speed = 0.6\nmax_accel = 1.0\nmax_angular_speed = 1.8\n\
             max_angular_accel = 3.0\ngoal_tolerance = 0.2\n\
             sensor = { kind = \"lidar\", beams = 180, range = 8.0 }\n",
        ),
    ];
    for obstacles in ["truth", "scan"] {
        for (robot, limits) in limits {
            let src = format!(
                "[world]\nduration = 60.0\narena = {{ min = [-4.0, -3.0], max = [4.0, 3.0] }}\n\
                 [defaults]\nplanner = \"dwa\"\nparams = {{ obstacles = \"{obstacles}\" }}\n\
                 kinematics = \"unicycle\"\n{limits}\
                 [[robot]]\nname = \"a\"\nstart = [-3.0, 0.0]\ngoal = [3.0, 0.0]\n\
                 [[robot]]\nname = \"b\"\nstart = [3.0, 0.0]\ngoal = [-3.0, 0.0]\n"
            );
            let tag = format!("headon-{obstacles}-{robot}");
            let file = scenario_file(&tag, &src);
            let out = run_lockstep(&file, &format!("ho-{}-{robot}", &obstacles[..1]), &[]);
            let m = metrics(&out);
            for r in ["a", "b"] {
                assert_eq!(m["robots"][r]["reached_goal"], true, "{tag}: {r}: {m:#}");
                assert_eq!(m["robots"][r]["collisions"], 0, "{tag}: {r}: {m:#}");
            }
        }
    }
}

#[test]
fn pioneers_crossing_a_corridor_both_ways_from_the_scan_keep_right_and_all_arrive() {
    // Two halls joined by a corridor 1.85 m wide and 8 m long (room for
    // three Pioneers abreast); four Pioneer-like robots cross it each way
    // by their routes, all of which run down its middle, with dwa from the
    // scan. Meeting there, each keeping to the middle or swerving its own
    // way, they stood face to face and none arrived; keeping right when
    // something that is not a wall is in the way, all arrive untouched.
    let walls = [
        ([-4.0, 0.925], [4.0, 0.925]),
        ([-4.0, -0.925], [4.0, -0.925]),
        ([-4.0, 0.925], [-4.0, 3.0]),
        ([-4.0, -0.925], [-4.0, -3.0]),
        ([4.0, 0.925], [4.0, 3.0]),
        ([4.0, -0.925], [4.0, -3.0]),
        ([-8.0, -3.0], [-4.0, -3.0]),
        ([-8.0, 3.0], [-4.0, 3.0]),
        ([4.0, -3.0], [8.0, -3.0]),
        ([4.0, 3.0], [8.0, 3.0]),
        ([-8.0, -3.0], [-8.0, 3.0]),
        ([8.0, -3.0], [8.0, 3.0]),
    ];
    let robots = [
        ([-5.0, 1.1], [5.0, -1.1]),
        ([-5.0, 2.2], [5.0, -2.2]),
        ([-5.0, -1.1], [6.2, -1.1]),
        ([-7.2, -1.1], [6.2, 1.1]),
        ([6.2, -1.1], [-7.2, 2.2]),
        ([6.2, 0.0], [-5.0, 2.2]),
        ([5.0, 0.0], [-7.2, 0.0]),
        ([5.0, -1.1], [-5.0, -2.2]),
    ];
    let mut src = String::from("[world]\nduration = 90.0\n");
    for (a, b) in walls {
        src += &format!("[[wall]]\nsegment = [{a:?}, {b:?}]\n");
    }
    src += "[defaults]\nplanner = \"dwa\"\nparams = { obstacles = \"scan\" }\n\
            route = \"shortest\"\nkinematics = \"unicycle\"\nradius = 0.25\n\
            max_speed = 0.6\nmax_accel = 1.0\nmax_angular_speed = 1.8\n\
            max_angular_accel = 3.0\ngoal_tolerance = 0.2\n\
            sensor = { kind = \"lidar\", beams = 180, range = 8.0 }\n";
    for (k, (start, goal)) in robots.iter().enumerate() {
        src += &format!("[[robot]]\nname = \"r{k}\"\nstart = {start:?}\ngoal = {goal:?}\n");
    }
    let file = scenario_file("corridor-crossing", &src);
    let out = run_lockstep(&file, "xcor", &[]);
    let o = outcome(&file, &out);
    assert_eq!(o.success, 1.0, "goals reached: {}", o.success);
    assert_eq!(o.robot_contacts, 0);
    assert!(o.deepest >= -1e-3, "{} m into a wall", -o.deepest);
}

/// Runs `mrsim run` on `src` and expects a refusal: exit 2, nothing run,
/// stderr naming the file and line and holding each of `words`.
fn refused(tag: &str, src: &str, line: usize, words: &[&str]) {
    let file = scenario_file(tag, src);
    let err = run_refused(&file);
    let at = format!("{}:{line}", file.display());
    assert!(err.contains(&at), "{tag}: no {at} in: {err}");
    for w in words {
        assert!(err.contains(w), "{tag}: no `{w}` in: {err}");
    }
}

#[test]
fn a_goal_no_route_reaches_is_refused_with_the_widest_gap() {
    // A wall across the arena with a 0.3 m gap: a 0.4 m disc cannot pass.
    let src = "[world]\narena = { min = [-3.0, -3.0], max = [3.0, 3.0] }\n\
               [[wall]]\nsegment = [[0.0, -3.0], [0.0, -0.15]]\n\
               [[wall]]\nsegment = [[0.0, 0.15], [0.0, 3.0]]\n\
               [[robot]]\nname = \"r\"\nradius = 0.2\nroute = \"shortest\"\nstart = [-2.0, 0.0]\n\
               goal = [2.0, 0.0]\n";
    refused(
        "unreachable",
        src,
        12,
        &[
            "robot `r`",
            "cannot be reached",
            "radius 0.2",
            "clearance of 0.1",
        ],
    );
}

#[test]
fn a_lookahead_not_below_the_goal_tolerance_is_refused_with_the_reason() {
    let src = "[[robot]]\nname = \"r\"\nkinematics = \"unicycle\"\ngoal_tolerance = 0.1\n\
               lookahead = 0.2\nstart = [0.0, 0.0]\ngoal = [2.0, 0.0]\n";
    refused(
        "lookahead",
        src,
        5,
        &["lookahead 0.2 must be below goal_tolerance 0.1"],
    );
}

#[test]
fn a_unicycle_without_a_lookahead_gets_half_its_tolerance() {
    let src = "[[robot]]\nname = \"r\"\nkinematics = \"unicycle\"\ngoal_tolerance = 0.1\n\
               start = [0.0, 0.0]\ngoal = [2.0, 0.0]\n";
    let l = mrsim_scenario::parse(src, "s.toml").expect("valid");
    assert_eq!(l.scenario.robots[0].lookahead, 0.05);
}

#[test]
fn dwa_from_the_scan_without_a_scanner_is_refused() {
    let src = "[[robot]]\nname = \"r\"\nplanner = \"dwa\"\nparams = { obstacles = \"scan\" }\n\
               start = [0.0, 0.0]\ngoal = [2.0, 0.0]\n";
    refused("noscan", src, 4, &["no scanner", "sensor"]);
}

#[test]
fn a_lane_without_a_route_is_refused() {
    let src = "[[robot]]\nname = \"r\"\nlane = \"right\"\nstart = [0.0, 0.0]\ngoal = [2.0, 0.0]\n";
    refused("lanenoroute", src, 3, &["lane needs route = \"shortest\""]);
}

#[test]
fn routes_with_a_lane_keep_opposite_sides_of_a_corridor_and_without_one_share_its_middle() {
    // A corridor 1.9 m wide along x; two Pioneer-like robots swap its ends.
    // routes.csv: robot, seq, x, y. Each route's points other than its
    // ends, and how far they lie off the middle line (y = 0).
    let inner = |lane: &str| {
        let src = format!(
            "[world]\nduration = 0.2\narena = {{ min = [-7.0, -1.0], max = [7.0, 1.0] }}\n\
             [[wall]]\nsegment = [[-7.0, -0.95], [7.0, -0.95]]\n\
             [[wall]]\nsegment = [[-7.0, 0.95], [7.0, 0.95]]\n\
             [defaults]\nplanner = \"dwa\"\nroute = \"shortest\"\nlane = \"{lane}\"\n\
             kinematics = \"unicycle\"\nradius = 0.25\nmax_speed = 0.6\ngoal_tolerance = 0.2\n\
             [[robot]]\nname = \"e\"\nstart = [-6.0, 0.0]\ngoal = [6.0, 0.0]\n\
             [[robot]]\nname = \"w\"\nstart = [6.0, 0.0]\ngoal = [-6.0, 0.0]\n"
        );
        let file = scenario_file(&format!("lane-{lane}"), &src);
        let out = run_lockstep(&file, &format!("ln-{lane}"), &["--no-report"]);
        let text = std::fs::read_to_string(out.join("routes.csv")).expect("routes.csv");
        let mut by: std::collections::BTreeMap<String, Vec<[f64; 2]>> = Default::default();
        for line in text.lines().skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            by.entry(f[0].to_string())
                .or_default()
                .push([f[2].parse().expect("x"), f[3].parse().expect("y")]);
        }
        by.into_iter()
            .map(|(r, pts)| {
                assert_eq!(pts.first().map(|p| p[1]), Some(0.0), "{lane} {r}: {pts:?}");
                assert_eq!(pts.last().map(|p| p[1]), Some(0.0), "{lane} {r}: {pts:?}");
                (r, pts[1..pts.len() - 1].to_vec())
            })
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    // Keeping right: eastwards to -y, westwards to +y, by a radius and a
    // half (0.375) along the corridor, leaving 0.5 (radius + margin) to the
    // wall.
    let right = inner("right");
    for (r, sign) in [("e", -1.0), ("w", 1.0)] {
        let pts = &right[r];
        assert!(!pts.is_empty(), "{r}: {pts:?}");
        for p in pts {
            assert!(sign * p[1] > 0.3 && sign * p[1] < 0.376, "{r}: {pts:?}");
        }
    }
    // Without: both down the middle.
    for pts in inner("none").values() {
        assert!(pts.iter().all(|p| p[1].abs() < 1e-9), "{pts:?}");
    }
}

#[test]
fn two_differential_drives_swapping_through_a_one_robot_door_give_way_and_arrive() {
    // A corridor (1.85 m wide) with a room below it behind a 1 m door:
    // Pioneer-like robots, one leaving the room for the corridor's far
    // end and one coming the other way into the room (from 2 m along the
    // corridor, so that both reach the door together), meet at the door,
    // which orca's robots (each seen as radius + lookahead, 0.35 m) pass
    // only one at a time. Without a rule both stop facing each other in
    // it; the one of the lower id gives way (`route_yields`), into the
    // room off the other's way, and both arrive untouched. dwa on true
    // states goes through the same route layer and arrives too.
    let walls = [
        [[-5.0, 0.0], [-0.5, 0.0]],
        [[0.5, 0.0], [5.0, 0.0]],
        [[-5.0, 1.85], [5.0, 1.85]],
        [[-5.0, 0.0], [-5.0, 1.85]],
        [[5.0, 0.0], [5.0, 1.85]],
        [[-2.0, 0.0], [-2.0, -4.0]],
        [[2.0, 0.0], [2.0, -4.0]],
        [[-2.0, -4.0], [2.0, -4.0]],
    ];
    let walls: String = walls
        .iter()
        .map(|[a, b]| {
            format!(
                "[[wall]]\nsegment = [[{}, {}], [{}, {}]]\n",
                a[0], a[1], b[0], b[1]
            )
        })
        .collect();
    for (planner, params) in [
        ("orca", ""),
        ("dwa", "params = { obstacles = \"truth\" }\n"),
    ] {
        let src = format!(
            "[world]\nduration = 120.0\n\
             [defaults]\nplanner = \"{planner}\"\n{params}route = \"shortest\"\n\
             kinematics = \"unicycle\"\nradius = 0.25\nmax_speed = 0.6\nmax_accel = 1.0\n\
             max_angular_speed = 1.8\nmax_angular_accel = 3.0\ngoal_tolerance = 0.2\n\
             sensor = {{ kind = \"lidar\", beams = 180, range = 8.0 }}\n{walls}\
             [[robot]]\nname = \"a\"\nstart = [0.0, -2.5]\ngoal = [4.0, 0.9]\n\
             [[robot]]\nname = \"b\"\nstart = [2.0, 0.9]\ngoal = [0.0, -2.5]\n"
        );
        let tag = format!("door-{planner}");
        let file = scenario_file(&tag, &src);
        let out = run_lockstep(&file, &tag, &[]);
        let m = metrics(&out);
        for r in ["a", "b"] {
            assert_eq!(m["robots"][r]["reached_goal"], true, "{tag}: {r}: {m:#}");
            assert_eq!(m["robots"][r]["collisions"], 0, "{tag}: {r}: {m:#}");
        }
        if planner == "orca" {
            // diagnostics.csv: tick, time, robot, name, value.
            let text =
                std::fs::read_to_string(out.join("diagnostics.csv")).expect("diagnostics.csv");
            let gave_way = text.lines().skip(1).any(|l| {
                let f: Vec<&str> = l.split(',').collect();
                f[2] == "a" && f[3] == "route_yield" && f[4] == "1"
            });
            assert!(gave_way, "{tag}: a never gave way");
        }
    }
}

#[test]
fn an_orca_pioneer_alone_passes_a_door_exactly_as_wide_as_its_enlarged_disc() {
    // A wall across the arena with a 0.70 m door, as the Willow Garage
    // map's doorways are: exactly twice the 0.35 m disc orca sees a
    // Pioneer driven through its look-ahead point as (radius 0.25 +
    // lookahead 0.1). Against walls orca keeps the real disc off them
    // (half the look-ahead more while driving along one), so the robot
    // goes through the door, untouched, instead of creeping to a stop in
    // it.
    let src = "[world]\nduration = 60.0\narena = { min = [-4.0, -3.0], max = [4.0, 3.0] }\n\
               [defaults]\nplanner = \"orca\"\nroute = \"shortest\"\n\
               kinematics = \"unicycle\"\nradius = 0.25\nmax_speed = 0.6\nmax_accel = 1.0\n\
               max_angular_speed = 1.8\nmax_angular_accel = 3.0\ngoal_tolerance = 0.2\n\
               [[wall]]\nsegment = [[-4.0, 0.0], [-0.35, 0.0]]\n\
               [[wall]]\nsegment = [[0.35, 0.0], [4.0, 0.0]]\n\
               [[robot]]\nname = \"a\"\nstart = [-2.0, -2.0]\ngoal = [2.0, 2.0]\n";
    let file = scenario_file("door-alone", src);
    let out = run_lockstep(&file, "door-alone", &[]);
    let m = metrics(&out);
    assert_eq!(m["robots"]["a"]["reached_goal"], true, "{m:#}");
    assert_eq!(m["robots"]["a"]["collisions"], 0, "{m:#}");
    let o = outcome(&file, &out);
    assert!(o.deepest >= 0.0, "{} m into a wall", -o.deepest);
}
