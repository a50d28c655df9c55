//! End-to-end tests of the papers' cases: each scenario in
//! scenarios/papers/ runs through the real binary (lockstep: one world and
//! one agent process per robot) and the outcome the paper reports, or the
//! outcome the scenario's description says our implementation gives, is
//! read back from trajectory.csv, events.jsonl and metrics.json.

use crate::common::*;
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

/// The paper (section 5.1, fig 3): "the robot moves back and forth six times
/// from t_16 to t_29" and then takes the obstacle's back track. Not
/// reproduced in number: at the file's max_speed (23.3 cm/s) our robot
/// reverses 4 times before crossing behind; six only at 23.7 cm/s (see
/// tests/it/papers_band.rs). The test asserts the 4 we get.
#[test]
fn ko_choi_case_2_moves_back_and_forth_then_passes_behind_the_obstacle() {
    let dir = run_paper("ko-choi-case-2");
    let c = ko_choi_crossing(&dir);
    assert!(c.offset < 0.0, "offset {}", c.offset);
    assert_eq!(c.reversals, 4, "reversals (the paper: about six)");
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
    // Case 5 touches o1 first at tick 14, the paper's t_14, and o1 is the
    // only body it collides with.
    let hits = robot_collisions_with(&case5, "o1");
    assert_eq!(
        hits.first().map(|h| h.0),
        Some(14),
        "case 5 hits o1 at {hits:?}"
    );
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

/// The largest change of the robot's heading from one tick to the next
/// (degrees) up to tick `until`: how abruptly it turns.
fn sharpest_turn(dir: &Path, until: u64) -> f64 {
    let rows = trajectory(dir);
    let heading: Vec<f64> = track(&rows, "robot")
        .into_iter()
        .filter(|r| r.tick <= until && norm(r.vx, r.vy) > 1e-6)
        .map(|r| r.vy.atan2(r.vx))
        .collect();
    heading
        .windows(2)
        .map(|w| {
            let d = (w[1] - w[0]).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d).to_degrees()
        })
        .fold(0.0, f64::max)
}

/// The paper (fig 7): beta = 150 makes the robot begin avoiding obstacle 1
/// at t_8, earlier than case 4, and its trajectory "changes more abruptly".
/// Not reproduced: ours starts avoiding at tick 13, one tick before case 4
/// (tick 14), not at t_8; and its sharpest turn (about 119 degrees in one
/// tick) is gentler than case 4's (about 155 degrees), not more abrupt. The
/// test asserts what we get.
#[test]
fn ko_choi_case_6_starts_avoiding_one_tick_earlier_than_case_4_and_turns_less_sharply() {
    let case4 = run_paper("ko-choi-case-4");
    let case6 = run_paper("ko-choi-case-6");
    let (t4, t6) = (starts_avoiding(&case4), starts_avoiding(&case6));
    assert_eq!(
        (t4, t6),
        (14, 13),
        "case 4 at tick {t4}, case 6 at tick {t6}"
    );
    let (a4, a6) = (sharpest_turn(&case4, 30), sharpest_turn(&case6, 30));
    assert!(
        a6 < a4 && a6 > 100.0,
        "sharpest turns: case 6 {a6} deg, case 4 {a4} deg"
    );
    assert_eq!(metrics(&case6)["collisions_total"], 0);
}

/// Runs case 7's scenario text with and without o3 (the last obstacle
/// block) and checks that the robot does not respond to o3 until o3 hits
/// it, at tick 40: before that tick its path stays within 0.1 cm of the
/// path without o3, while o3 closes from beyond eps_vd (40 cm) to a few cm.
///
/// The paper (fig 8) has the robot ignore o3 and then make "an unnecessary
/// detour after it passes away the obstacle 3 path". The detour is not
/// reproduced: our robot never passes o3's path unharmed, o3 hits it first
/// (tick 40), so there is no detour after to assert.
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
    assert_eq!(hit, 40, "{tag}: o3 hits at tick {hit}");
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

/// Strategy III settles (Chung et al. section 4, fig 4): with the goal test
/// asking for 100 s within 0.1 m (`goal_hold_ticks` 1000 at dt 0.1 s) the
/// robot counts as arrived only if it stays there that long, and every row
/// from its arrival to the end of the run (the 1000 ticks from the arrival
/// on, 99.9 s) is within 0.1 m of the goal. With the file's 3-tick hold the run would end 3 ticks
/// after arrival and "held" would be the goal test again: it first comes
/// within 0.1 m at about 115 s but leaves again; the 100 s hold starts at
/// 141.3 s.
#[test]
fn chung_strategy_3_settles_at_its_goal_and_stays_there_for_100_s() {
    let out = fresh_dir("chung-strategy-3-hold");
    let id = run_id("chung3hold");
    let file = root().join("scenarios/papers/chung-strategy-3.toml");
    let sets = [
        "--set",
        "defaults.goal_hold_ticks=1000",
        "--set",
        "world.duration=500",
        "--quiet",
        "--no-report",
    ];
    assert_ok(&run(&file, &out, &id, &sets));
    assert_clean(&id);
    let m = robot_metrics(&out, "robot");
    assert_eq!(m["reached_goal"], true, "{m:#}");
    let t = m["time_to_goal"].as_f64().expect("time_to_goal");
    let rows = trajectory(&out);
    let held = after(&rows, "robot", t);
    let span = held.last().expect("rows after arrival").time - t;
    // 1000 ticks counted from the arrival's own tick: 99.9 s of rows after it.
    assert!(span >= 99.9 - 1e-6, "held for {span} s only");
    for r in held {
        assert!(
            norm(r.x - 10.0, r.y) <= 0.1,
            "{} m at {} s",
            norm(r.x - 10.0, r.y),
            r.time
        );
    }
    assert_eq!(metrics(&out)["collisions_total"], 0);
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

/// Peak speed of the robot, its largest tick-to-tick velocity change, and
/// that change over the median of the ten changes around it (how much the
/// largest change stands out from its neighbours: a jump).
fn hydro_speeds(dir: &Path) -> (f64, f64, f64) {
    let rows = trajectory(dir);
    let robot = track(&rows, "robot");
    let peak = robot.iter().map(|r| norm(r.vx, r.vy)).fold(0.0, f64::max);
    let dv: Vec<f64> = robot
        .windows(2)
        .map(|w| norm(w[1].vx - w[0].vx, w[1].vy - w[0].vy))
        .collect();
    let (k, jump) = dv
        .iter()
        .copied()
        .enumerate()
        .fold((0, 0.0), |a, (i, x)| if x > a.1 { (i, x) } else { a });
    let mut around: Vec<f64> = dv[k.saturating_sub(5)..k]
        .iter()
        .chain(dv.get(k + 1..(k + 6).min(dv.len())).unwrap_or(&[]))
        .copied()
        .collect();
    around.sort_by(f64::total_cmp);
    let median = around[around.len() / 2];
    (peak, jump, jump / median)
}

/// Sugiyama et al. figs 15-20. The paper: with the ellipse "the maximum
/// velocity of the new method is a half maximum velocity of our previous
/// method" (the circle), and with the new correction function b_j the
/// velocity "has no discontinuous point at all time" where the binary b_j
/// has one at the maximum-velocity point.
///
/// The half is not reproduced: our ellipse's peak is 0.72 of the circle's
/// (0.722 against 1.002 m/s binary, 1.011 smooth); the test asserts the
/// ratio we get (0.70-0.74). The smooth correction's claim holds as the
/// paper makes it: a jump is the largest tick-to-tick velocity change
/// standing out from the median of the ten around it by more than 25 %;
/// binary has one with both shapes (1.54 and 4.95 times), smooth with
/// neither (1.11 and 1.03), and its largest change is smaller too.
#[test]
fn hydro_variants_reach_the_goal_the_ellipse_lowers_the_peak_and_smooth_b_has_no_jump() {
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
            s.insert((shape, correction), hydro_speeds(&dir));
        }
    }
    for c in ["binary", "smooth"] {
        let ratio = s[&("ellipse", c)].0 / s[&("circle", c)].0;
        assert!((0.70..0.74).contains(&ratio), "{c}: ratio {ratio} {s:?}");
    }
    for shape in ["circle", "ellipse"] {
        let (b, sm) = (s[&(shape, "binary")], s[&(shape, "smooth")]);
        assert!(b.2 > 1.25, "{shape}: binary has no jump: {s:?}");
        assert!(sm.2 < 1.25, "{shape}: smooth has a jump: {s:?}");
        assert!(sm.1 < b.1, "{shape}: {s:?}");
    }
}
