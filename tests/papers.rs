//! End-to-end tests of the papers' cases: each scenario in
//! scenarios/papers/ runs through the real binary (lockstep: one world and
//! one agent process per robot) and the outcome the paper reports, or the
//! outcome the scenario's description says our implementation gives, is
//! read back from trajectory.csv, events.jsonl and metrics.json.

mod common;
use common::*;
use std::path::{Path, PathBuf};

/// Runs `scenarios/papers/NAME.toml` and returns its run folder.
fn run_paper(name: &str) -> PathBuf {
    run_file(&root().join(format!("scenarios/papers/{name}.toml")), name)
}

/// Runs a scenario file in a fresh folder, asserting a clean exit.
fn run_file(file: &Path, tag: &str) -> PathBuf {
    let out = fresh_dir(tag);
    let short: String = tag.chars().filter(|c| *c != '-').take(10).collect();
    let id = run_id(&short);
    assert_ok(&run(file, &out, &id, &["--quiet"]));
    assert_clean(&id);
    out
}

fn norm(x: f64, y: f64) -> f64 {
    x.hypot(y)
}

/// Ko & Choi cases 1-3: where the robot first crosses the obstacle's line
/// (its offset along the obstacle's motion from the obstacle's centre, > 0
/// in front of it), the reversals of its along-track velocity before that,
/// and the smallest centre distance minus the obstacle's radius over the run.
struct Crossing {
    offset: f64,
    reversals: usize,
    min_gap: f64,
}

fn ko_choi_crossing(dir: &Path) -> Crossing {
    let rows = trajectory(dir);
    let (robot, obstacle) = (track(&rows, "robot"), track(&rows, "obstacle"));
    assert_eq!(robot.len(), obstacle.len());
    let o = obstacle[0];
    let d = {
        let n = norm(o.vx, o.vy);
        (o.vx / n, o.vy / n)
    };
    let n = (-d.1, d.0);
    let track_dir = (80.0 / norm(80.0, -42.0), -42.0 / norm(80.0, -42.0));
    let mut offset = f64::NAN;
    let mut reversals = 0;
    let mut min_gap = f64::INFINITY;
    let (mut side_prev, mut along_prev) = (f64::NAN, 0.0);
    for (r, o) in robot.iter().zip(&obstacle) {
        assert_eq!(r.tick, o.tick);
        let rel = (r.x - o.x, r.y - o.y);
        min_gap = min_gap.min(norm(rel.0, rel.1) - 5.0);
        if offset.is_nan() {
            let side = rel.0 * n.0 + rel.1 * n.1;
            if side_prev.is_finite() && side * side_prev < 0.0 {
                offset = rel.0 * d.0 + rel.1 * d.1;
            } else {
                let along = r.vx * track_dir.0 + r.vy * track_dir.1;
                if along != 0.0 {
                    if along * along_prev < 0.0 {
                        reversals += 1;
                    }
                    along_prev = along;
                }
            }
            side_prev = side;
        }
    }
    assert!(
        offset.is_finite(),
        "the robot never crossed the obstacle's line"
    );
    Crossing {
        offset,
        reversals,
        min_gap,
    }
}

fn robot_metrics(dir: &Path, robot: &str) -> serde_json::Value {
    metrics(dir)["robots"][robot].clone()
}

#[test]
fn ko_choi_case_1_goes_ahead_of_the_obstacle_without_touching_it() {
    let dir = run_paper("ko-choi-case-1");
    let c = ko_choi_crossing(&dir);
    assert!(c.offset > 0.0, "offset {}", c.offset);
    assert!(c.min_gap > 0.0, "gap {}", c.min_gap);
    assert_eq!(metrics(&dir)["collisions_total"], 0);
    // As printed the model never settles (the description says so).
    assert_eq!(robot_metrics(&dir, "robot")["reached_goal"], false);
}

#[test]
fn ko_choi_case_2_moves_back_and_forth_then_passes_behind_the_obstacle() {
    let dir = run_paper("ko-choi-case-2");
    let c = ko_choi_crossing(&dir);
    assert!(c.offset < 0.0, "offset {}", c.offset);
    assert!(c.reversals >= 2, "reversals {}", c.reversals);
    // No overlap at any tick and no contact in any substep (the closest
    // tick-sampled gap is about 0.6 cm).
    assert!(c.min_gap > 0.0, "gap {}", c.min_gap);
    assert_eq!(metrics(&dir)["collisions_total"], 0);
    assert_eq!(robot_metrics(&dir, "robot")["reached_goal"], false);
}

#[test]
fn ko_choi_case_3_detours_behind_the_obstacle_without_reversing() {
    let dir = run_paper("ko-choi-case-3");
    let c = ko_choi_crossing(&dir);
    assert!(c.offset < 0.0, "offset {}", c.offset);
    assert_eq!(c.reversals, 0);
    // No overlap at any tick and no contact in any substep.
    assert!(c.min_gap > 0.0, "gap {}", c.min_gap);
    assert_eq!(metrics(&dir)["collisions_total"], 0);
    assert_eq!(robot_metrics(&dir, "robot")["reached_goal"], false);
}

/// Ko & Choi cases 4-7: the first tick at which the robot's velocity points
/// more than 5 degrees away from the straight line to its goal, (180, 70).
/// With no obstacle the robot accelerates straight at the goal, so this is
/// when it starts avoiding.
fn starts_avoiding(dir: &Path) -> u64 {
    let rows = trajectory(dir);
    track(&rows, "robot")
        .into_iter()
        .find(|r| {
            let (gx, gy) = (180.0 - r.x, 70.0 - r.y);
            let s = norm(r.vx, r.vy);
            s > 1e-6 && (r.vx * gx + r.vy * gy) / (s * norm(gx, gy)) < 5f64.to_radians().cos()
        })
        .map(|r| r.tick)
        .expect("the robot never turns away from its goal line")
}

/// The robot's collision events with `body`: (tick, surface gap).
fn robot_collisions_with(dir: &Path, body: &str) -> Vec<(u64, f64)> {
    events(dir)
        .iter()
        .filter(|e| e["type"] == "collision")
        .filter(|e| (e["a"] == "robot" && e["b"] == body) || (e["a"] == body && e["b"] == "robot"))
        .map(|e| {
            (
                e["tick"].as_u64().expect("tick"),
                e["gap"].as_f64().expect("gap"),
            )
        })
        .collect()
}

#[test]
fn ko_choi_case_5_collides_with_obstacle_1_where_case_4_avoids_every_obstacle() {
    let case4 = run_paper("ko-choi-case-4");
    let case5 = run_paper("ko-choi-case-5");
    assert_eq!(metrics(&case4)["collisions_total"], 0);
    assert!(events(&case4).iter().all(|e| e["type"] != "collision"));
    // Case 5 touches o1 (a surface gap within the world's 1 mm), and o1 is
    // the only body it collides with.
    let hits = robot_collisions_with(&case5, "o1");
    assert!(!hits.is_empty(), "case 5 misses o1");
    assert!(hits.iter().all(|&(_, gap)| gap <= 0.1), "{hits:?}");
    let m5 = metrics(&case5);
    assert_eq!(m5["collisions_total"].as_u64(), Some(hits.len() as u64));
    assert_eq!(m5["robots"]["robot"]["collisions"], m5["collisions_total"]);
    // Case 4 passes o1 at a positive gap at every tick and never touches.
    let rows = trajectory(&case4);
    let (r, o) = (track(&rows, "robot"), track(&rows, "o1"));
    let closest4 = r
        .iter()
        .zip(&o)
        .map(|(r, o)| norm(r.x - o.x, r.y - o.y) - 2.0)
        .fold(f64::INFINITY, f64::min);
    assert!(closest4 > 0.1, "case 4 comes {closest4} cm from o1");
}

#[test]
fn ko_choi_case_6_starts_avoiding_earlier_than_case_4() {
    let case4 = run_paper("ko-choi-case-4");
    let case6 = run_paper("ko-choi-case-6");
    let (t4, t6) = (starts_avoiding(&case4), starts_avoiding(&case6));
    assert!(t6 < t4, "case 6 at tick {t6}, case 4 at tick {t4}");
    assert_eq!(metrics(&case6)["collisions_total"], 0);
}

/// Runs case 7's scenario text with and without o3 (the last obstacle
/// block) and checks that the robot does not respond to o3 until o3 hits
/// it: before the tick of the hit its path stays within 0.1 cm of the path
/// without o3, while o3 closes from beyond eps_vd (40 cm) to a few cm.
fn ko_choi_case_7_ignores_obstacle_3(text: &str, tag: &str) {
    let start = text.find("[[obstacle]]\nname = \"o3\"").expect("o3 block");
    assert!(
        !text[start + 1..].contains("[[obstacle]]"),
        "o3 is not last"
    );
    let dir = fresh_dir(tag);
    let (with, without) = (dir.join("with-o3.toml"), dir.join("without-o3.toml"));
    std::fs::write(&with, text).expect("write");
    std::fs::write(&without, &text[..start]).expect("write");
    let with_o3 = run_file(&with, tag);
    let no_o3 = run_file(&without, &format!("{tag}-no-o3"));
    let hit = robot_collisions_with(&with_o3, "o3")
        .first()
        .map(|&(tick, _)| tick)
        .expect("case 7 runs into o3");
    let rows = trajectory(&with_o3);
    let rows0 = trajectory(&no_o3);
    let (a, b) = (track(&rows, "robot"), track(&rows0, "robot"));
    for (r, r0) in a.iter().zip(&b).take_while(|(r, _)| r.tick < hit) {
        let dev = norm(r.x - r0.x, r.y - r0.y);
        assert!(
            dev < 0.1,
            "{tag}: responds by {dev} cm at tick {} (o3 hits at {hit})",
            r.tick
        );
    }
    let o3 = track(&rows, "o3");
    let gap = |t: usize| norm(a[t].x - o3[t].x, a[t].y - o3[t].y) - 2.0;
    let hit = hit as usize;
    assert!(
        gap(hit - 10) > 40.0 && gap(hit - 1) < 5.0,
        "{tag}: gaps {} and {}",
        gap(hit - 10),
        gap(hit - 1)
    );
}

#[test]
fn ko_choi_case_7_does_not_respond_to_obstacle_3_until_it_is_hit() {
    let file = root().join("scenarios/papers/ko-choi-case-7.toml");
    let text = std::fs::read_to_string(&file).expect("case 7");
    ko_choi_case_7_ignores_obstacle_3(&text, "ko-choi-case-7");
}

#[test]
fn khatib_the_limit_of_case_7_does_not_respond_to_obstacle_3_either() {
    let file = root().join("scenarios/papers/ko-choi-case-7.toml");
    let text = std::fs::read_to_string(&file).expect("case 7");
    let vdf = "planner = \"vdf\"\nparams = { alpha = 100000000.0, beta = 100000000.0, eta = 1e4, zeta = 2.0, eps_vd = 40.0 }";
    let khatib = "planner = \"khatib\"\nparams = { eta = 1e4, zeta = 2.0, eps_d = 40.0 }";
    assert!(text.contains(vdf), "case 7's robot block changed");
    ko_choi_case_7_ignores_obstacle_3(&text.replace(vdf, khatib), "ko-choi-case-7-khatib");
}

/// Robot rows at or after `t0` seconds.
fn after<'a>(rows: &'a [Row], body: &str, t0: f64) -> Vec<&'a Row> {
    track(rows, body)
        .into_iter()
        .filter(|r| r.time >= t0)
        .collect()
}

#[test]
fn chung_strategy_2_keeps_swinging_through_its_goal() {
    let dir = run_paper("chung-strategy-2");
    let rows = trajectory(&dir);
    let late = after(&rows, "robot", 200.0);
    assert!(late.len() > 100, "the run ended before 200 s");
    let max_d = late
        .iter()
        .map(|r| norm(r.x - 10.0, r.y))
        .fold(0.0, f64::max);
    let crossings = late
        .windows(2)
        .filter(|w| (w[0].x - 10.0) * (w[1].x - 10.0) < 0.0)
        .count();
    assert!(max_d > 1.0, "max distance {max_d}");
    assert!(crossings >= 3, "{crossings} crossings of x = 10");
    assert_eq!(metrics(&dir)["collisions_total"], 0);
    assert_eq!(robot_metrics(&dir, "robot")["reached_goal"], false);
}

#[test]
fn chung_strategy_3_settles_at_its_goal() {
    // The run ends once every robot has held its goal (the crossers arrive
    // at 20 s, this robot at about 115 s), so the test checks the arrival
    // and every tick after it rather than a window after 200 s.
    let dir = run_paper("chung-strategy-3");
    let m = robot_metrics(&dir, "robot");
    assert_eq!(m["reached_goal"], true);
    let t = m["time_to_goal"].as_f64().expect("time_to_goal");
    let rows = trajectory(&dir);
    let held = after(&rows, "robot", t);
    assert!(held.len() >= 3);
    for r in held {
        assert!(
            norm(r.x - 10.0, r.y) <= 0.1,
            "{} m at {} s",
            norm(r.x - 10.0, r.y),
            r.time
        );
    }
    assert_eq!(metrics(&dir)["collisions_total"], 0);
}

#[test]
fn chung_homing_oscillation_falls_as_alpha_grows() {
    let dir = run_paper("chung-homing-fig1");
    let rows = trajectory(&dir);
    let amp = |robot: &str, y: f64| {
        after(&rows, robot, 30.0)
            .iter()
            .map(|r| {
                assert!((r.y - y).abs() < 1e-3);
                (r.x - 10.0).abs()
            })
            .fold(0.0, f64::max)
    };
    let (a001, a01, a1) = (
        amp("alpha-0.01", 0.0),
        amp("alpha-0.1", 3.0),
        amp("alpha-1", 6.0),
    );
    assert!(a001 > a01 && a01 > a1 && a1 > 0.1, "{a001} {a01} {a1}");
}

/// Peak speed and largest tick-to-tick velocity change of the robot.
fn hydro_speeds(dir: &Path) -> (f64, f64) {
    let rows = trajectory(dir);
    let robot = track(&rows, "robot");
    let peak = robot.iter().map(|r| norm(r.vx, r.vy)).fold(0.0, f64::max);
    let jump = robot
        .windows(2)
        .map(|w| norm(w[1].vx - w[0].vx, w[1].vy - w[0].vy))
        .fold(0.0, f64::max);
    (peak, jump)
}

#[test]
fn hydro_variants_reach_the_goal_and_the_ellipse_and_smooth_correction_calm_the_speed() {
    let mut s = std::collections::BTreeMap::new();
    for shape in ["circle", "ellipse"] {
        for correction in ["binary", "smooth"] {
            let name = format!("hydro-{shape}-{correction}");
            let dir = run_paper(&name);
            let m = metrics(&dir);
            assert_eq!(m["collisions_total"], 0, "{name}");
            let r = &m["robots"]["robot"];
            assert_eq!(r["reached_goal"], true, "{name}");
            assert!(
                r["min_clearance"].as_f64().expect("clearance") > 0.0,
                "{name}"
            );
            let (peak, jump) = hydro_speeds(&dir);
            eprintln!("{name}: peak speed {peak:.3} m/s, max tick-to-tick change {jump:.4} m/s");
            s.insert((shape, correction), (peak, jump));
        }
    }
    for c in ["binary", "smooth"] {
        assert!(s[&("ellipse", c)].0 < s[&("circle", c)].0, "{c}: {s:?}");
    }
    for shape in ["circle", "ellipse"] {
        assert!(
            s[&(shape, "smooth")].1 < s[&(shape, "binary")].1,
            "{shape}: {s:?}"
        );
    }
}
