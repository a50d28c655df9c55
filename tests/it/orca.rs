//! End-to-end tests of the baseline planners through the real binary: a
//! world process and one agent process per robot, in lockstep.

use crate::common::*;

/// RVO2's Circle at 32 agents (scenarios/bench/circle-32.toml): every robot
/// reaches its antipode, no contact starts, no overlap in the trajectory.
#[test]
fn orca_circle_of_32_in_lockstep_brings_every_robot_home_without_a_collision() {
    let scenario = root().join("scenarios/bench/circle-32.toml");
    let out = fresh_dir("orca32");
    let id = run_id("orca32");
    assert_ok(&run(&scenario, &out, &id, &[]));
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_eq!(m["collisions_total"], 0, "{m:#}");
    let robots = m["robots"].as_object().expect("robots");
    assert_eq!(robots.len(), 32);
    for (name, r) in robots {
        assert_eq!(r["reached_goal"], true, "{name}");
        assert_eq!(r["collisions"], 0, "{name}");
        let clearance = r["min_clearance"].as_f64().expect("min_clearance");
        assert!(clearance > -1e-3, "{name} overlapped by {clearance}");
    }
    // All at their goals at once at the end (RVO2's reachedGoal).
    let scen: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("scenario.json")).expect("scenario.json"),
    )
    .expect("scenario.json parses");
    let rows = trajectory(&out);
    let last = rows.iter().map(|r| r.tick).max().expect("rows");
    for spec in scen["robots"].as_array().expect("robots") {
        let name = spec["name"].as_str().expect("name");
        let goal = &spec["goal"];
        let (gx, gy) = (
            goal[0].as_f64().unwrap_or(f64::NAN),
            goal[1].as_f64().unwrap_or(f64::NAN),
        );
        let end = track(&rows, name)
            .into_iter()
            .find(|r| r.tick == last)
            .expect("a row at the last tick");
        let d = (end.x - gx).hypot(end.y - gy);
        assert!(d <= 1.5 + 1e-6, "{name} ends {d} from its goal");
    }
    assert_clean(&id);
}

/// Two robots crossing at right angles (B one metre further back), each
/// planner in turn, through the world: both arrive, no contact.
#[test]
fn dwa_and_social_force_robots_cross_through_the_world_without_a_collision() {
    for (planner, max_accel) in [("dwa", 2.0), ("social-force", 10.0)] {
        let dir = fresh_dir("cross2");
        let scenario = dir.join("cross.toml");
        std::fs::write(
            &scenario,
            format!(
                "name = \"cross-{planner}\"\n\
                 [world]\ndt = 0.1\nsubsteps = 10\nduration = 40.0\nmode = \"lockstep\"\n\
                 [defaults]\nplanner = \"{planner}\"\nradius = 0.3\nmass = 1.0\nmax_speed = 1.0\n\
                 max_accel = {max_accel}\ngoal_tolerance = 0.2\n\
                 [[robot]]\nname = \"a\"\nstart = [-5.0, 0.0]\ngoal = [5.0, 0.0]\n\
                 [[robot]]\nname = \"b\"\nstart = [0.0, -6.0]\ngoal = [0.0, 5.0]\n"
            ),
        )
        .expect("write scenario");
        let out = dir.join("out");
        let id = run_id("cross2");
        assert_ok(&run(&scenario, &out, &id, &[]));
        let m = metrics(&out);
        assert_eq!(m["success_rate"], 1.0, "{planner}: {m:#}");
        assert_eq!(m["collisions_total"], 0, "{planner}: {m:#}");
        for r in m["robots"].as_object().expect("robots").values() {
            assert!(
                r["min_clearance"].as_f64().unwrap_or(-1.0) > 0.0,
                "{planner}: {m:#}"
            );
        }
        assert_clean(&id);
    }
}
