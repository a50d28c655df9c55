//! Defaults and overrides: who wins, and where errors point.

use crate::common::*;
use mrsim_scenario::{ParamValue, ScenarioError, parse_with_overrides};

const GEN: &str =
    "\n[generate]\nkind = \"circle\"\ncount = 4\nradius = 3.0\ncenter = [0.0, -5.0]\n";

fn ov(src: &str, pairs: &[(&str, &str)]) -> Result<mrsim_scenario::Loaded, ScenarioError> {
    let pairs: Vec<(String, String)> = pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    parse_with_overrides(src, "t.toml", &pairs)
}

fn ok(src: &str, pairs: &[(&str, &str)]) -> mrsim_scenario::Loaded {
    ov(src, pairs).unwrap_or_else(|e| panic!("{e}"))
}

fn override_error(src: &str, pairs: &[(&str, &str)], key: &str) -> String {
    match ov(src, pairs) {
        Err(e @ ScenarioError::Override { .. }) => {
            assert!(
                matches!(&e, ScenarioError::Override { key: k, .. } if k == key),
                "{e}"
            );
            e.to_string()
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn built_in_defaults_apply_where_nothing_is_said() {
    let s = accept("[[robot]]\nname = \"a\"\nstart = [0, 0]\ngoal = [1, 1]\n").scenario;
    let w = &s.world;
    assert_eq!((w.dt, w.substeps, w.duration, w.seed), (0.1, 10, 60.0, 1));
    assert_eq!((w.deadline, w.stall_timeout), (1.0, 2.0));
    assert_eq!(w.mode, mrsim_scenario::Mode::Lockstep);
    assert_eq!(w.on_deadline_miss, mrsim_scenario::MissPolicy::Hold);
    assert_eq!(s.length_unit, mrsim_scenario::LengthUnit::M);
    assert_eq!(s.name, "t");
    let r = &s.robots[0];
    assert_eq!(
        (r.radius, r.mass, r.damping, r.max_speed, r.max_accel),
        (0.25, 1.0, 0.5, 1.0, 2.0)
    );
    assert_eq!(
        (r.velocity_lag, r.sensing_range, r.field_of_view_deg),
        (0.0, 1e9, 360.0)
    );
    assert_eq!(
        (r.goal_tolerance, r.goal_hold_ticks, r.position_noise),
        (0.1, 3, 0.0)
    );
    assert_eq!(r.velocity_source, mrsim_scenario::VelocitySource::Truth);
    assert_eq!(r.planner, "homing");
    assert!(r.params.is_empty() && r.path.is_empty() && r.boundary.is_none());
}

#[test]
fn a_robot_overrides_defaults_which_override_built_ins() {
    let src = with(
        BASE,
        "mass = 1.0",
        "mass = 3.0\ndamping = 0.0\nradius = 0.1\nplanner = \"vdf\"\nparams = { a = 1, b = 2 }",
    );
    let src = with(
        &src,
        "radius = 0.3",
        "radius = 0.3\nplanner = \"orca\"\nparams = { b = 3, c = true }",
    );
    let s = accept(&src).scenario;
    let (r0, r1) = (&s.robots[0], &s.robots[1]);
    assert_eq!(
        (r0.mass, r0.damping, r0.radius, r0.planner.as_str()),
        (3.0, 0.0, 0.1, "vdf")
    );
    assert_eq!(
        (r1.mass, r1.radius, r1.planner.as_str()),
        (3.0, 0.3, "orca")
    );
    assert_eq!(r0.params.len(), 2);
    assert_eq!(r1.params["a"], ParamValue::Number(1.0));
    assert_eq!(r1.params["b"], ParamValue::Number(3.0));
    assert_eq!(r1.params["c"], ParamValue::Bool(true));
}

#[test]
fn generate_keys_override_defaults_for_generated_robots() {
    let src = with(
        BASE,
        "mass = 1.0",
        "mass = 1.0\nplanner = \"vdf\"\nparams = { a = 1, b = 2 }\nradius = 0.2",
    );
    let src = format!("{src}{GEN}planner = \"orca\"\nparams = {{ b = 5 }}\nrobot_radius = 0.15\n");
    let s = accept(&src).scenario;
    let g = &s.robots[2];
    assert_eq!((g.planner.as_str(), g.radius), ("orca", 0.15));
    assert_eq!(g.params["a"], ParamValue::Number(1.0));
    assert_eq!(g.params["b"], ParamValue::Number(5.0));
    assert_eq!(s.robots[0].planner, "vdf");
}

#[test]
fn world_keys_can_be_overridden() {
    let s = ok(
        BASE,
        &[("world.dt", "0.05"), ("world.mode", "\"realtime\"")],
    )
    .scenario;
    assert_eq!(s.world.dt, 0.05);
    assert_eq!(s.world.mode, mrsim_scenario::Mode::Realtime);
}

#[test]
fn defaults_can_be_overridden_but_robots_still_win() {
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nfield_of_view_deg = 120",
    );
    let s = ok(&src, &[("defaults.field_of_view_deg", "90")]).scenario;
    assert_eq!(s.robots[0].field_of_view_deg, 90.0);
    assert_eq!(s.robots[1].field_of_view_deg, 120.0);
}

#[test]
fn a_robot_is_selected_by_name() {
    let s = ok(
        BASE,
        &[("robot.r0.params.horizon", "3"), ("robot.r1.radius", "0.4")],
    )
    .scenario;
    assert_eq!(s.robots[0].params["horizon"], ParamValue::Number(3.0));
    assert!(s.robots[1].params.is_empty());
    assert_eq!((s.robots[0].radius, s.robots[1].radius), (0.25, 0.4));
}

#[test]
fn a_star_selects_every_robot_generated_ones_included() {
    let src = format!("{BASE}{GEN}");
    let s = ok(&src, &[("robot.*.max_speed", "2.5")]).scenario;
    assert_eq!(s.robots.len(), 6);
    assert!(s.robots.iter().all(|r| r.max_speed == 2.5));
}

#[test]
fn a_generated_robot_is_selected_by_name() {
    let src = format!("{BASE}{GEN}");
    let s = ok(&src, &[("robot.g01.max_speed", "2.5")]).scenario;
    let fast: Vec<&str> = s
        .robots
        .iter()
        .filter(|r| r.max_speed == 2.5)
        .map(|r| r.name.as_str())
        .collect();
    assert_eq!(fast, ["g01"]);
}

#[test]
fn planner_sets_every_robots_planner_as_toml_or_as_a_bare_word() {
    let src = format!(
        "{}{GEN}planner = \"vdf\"\n",
        with(BASE, "radius = 0.3", "radius = 0.3\nplanner = \"dwa\"")
    );
    for value in ["orca", "\"orca\""] {
        let s = ok(&src, &[("planner", value)]).scenario;
        assert!(s.robots.iter().all(|r| r.planner == "orca"));
    }
}

#[test]
fn later_overrides_win() {
    let s = ok(BASE, &[("planner", "orca"), ("robot.r1.planner", "vdf")]).scenario;
    assert_eq!(
        (s.robots[0].planner.as_str(), s.robots[1].planner.as_str()),
        ("orca", "vdf")
    );
    let s = ok(BASE, &[("robot.r1.planner", "vdf"), ("planner", "orca")]).scenario;
    assert_eq!(s.robots[1].planner, "orca");
}

#[test]
fn obstacles_and_walls_and_top_level_keys_can_be_overridden() {
    let s = ok(
        BASE,
        &[
            ("obstacle.o1.radius", "1.5"),
            ("wall.0.segment", "[[-8, 9], [8, 9]]"),
            ("name", "\"renamed\""),
            ("length_unit", "cm"),
        ],
    )
    .scenario;
    assert_eq!(s.obstacles[0].radius, 1.5);
    assert_eq!(s.walls[0].segment, [[-8.0, 9.0], [8.0, 9.0]]);
    assert_eq!(s.name, "renamed");
    assert_eq!(s.length_unit, mrsim_scenario::LengthUnit::Cm);
}

#[test]
fn unknown_override_targets_are_refused() {
    override_error(BASE, &[("colour", "1")], "colour");
    override_error(BASE, &[("world.tick", "1")], "world.tick");
    override_error(BASE, &[("robot.nobody.radius", "1")], "robot.nobody.radius");
    override_error(
        BASE,
        &[("obstacle.nobody.radius", "1")],
        "obstacle.nobody.radius",
    );
    override_error(BASE, &[("robot.r0", "1")], "robot.r0");
    override_error(BASE, &[("robot.r0.wheels", "4")], "robot.r0.wheels");
    override_error(
        BASE,
        &[("wall.7.segment", "[[0, 0], [1, 1]]")],
        "wall.7.segment",
    );
    override_error(BASE, &[("world..dt", "1")], "world..dt");
}

#[test]
fn an_invalid_override_value_names_the_override() {
    let msg = override_error(BASE, &[("robot.*.radius", "-1")], "robot.*.radius");
    assert!(msg.contains("radius must be >= 0"), "{msg}");
    override_error(BASE, &[("world.dt", "[1, 2")], "world.dt");
    override_error(BASE, &[("world.dt", "\"fast\"")], "world.dt");
    let src = format!("{BASE}{GEN}");
    override_error(&src, &[("robot.g02.mass", "0")], "robot.g02.mass");
}

#[test]
fn error_at_points_at_the_key_the_robot_sets() {
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nplanner = \"nope\"\nparams = { alpha = 1 }",
    );
    let l = accept(&src);
    assert_eq!(
        l.error_at("robot.r1.planner", "unknown planner").line(),
        Some(line_of(&src, "\"nope\""))
    );
    assert_eq!(
        l.error_at("robot.r1.params.alpha", "unknown").line(),
        Some(line_of(&src, "alpha"))
    );
    let e = l.error_at(
        "robot.r1.params.alpha",
        "planner `x` has no parameter `alpha`",
    );
    assert!(
        e.to_string()
            .starts_with(&format!("t.toml:{}: robot `r1`", line_of(&src, "alpha"))),
        "{e}"
    );
}

#[test]
fn error_at_falls_back_to_defaults_then_to_the_robot_table() {
    let src = with(BASE, "mass = 1.0", "mass = 1.0\nplanner = \"fromdefaults\"");
    let l = accept(&src);
    assert_eq!(
        l.error_at("robot.r0.planner", "x").line(),
        Some(line_of(&src, "fromdefaults"))
    );
    let l = accept(BASE);
    assert_eq!(
        l.error_at("robot.r0.planner", "x").line(),
        Some(line_of(BASE, "[[robot]]\nname = \"r0\""))
    );
}

#[test]
fn error_at_a_generated_robot_points_at_the_generate_table() {
    let src = format!("{BASE}{GEN}planner = \"gp\"\n");
    let l = accept(&src);
    assert!(l.is_generated("g00") && !l.is_generated("r0"));
    assert_eq!(
        l.error_at("robot.g02.planner", "x").line(),
        Some(line_of(&src, "\"gp\""))
    );
    assert_eq!(
        l.error_at("robot.g02.params.k", "x").line(),
        Some(line_of(&src, "[generate]"))
    );
}

#[test]
fn error_at_an_overridden_value_names_the_override() {
    let l = ok(BASE, &[("planner", "zzz")]);
    match l.error_at("robot.r1.planner", "unknown planner `zzz`") {
        ScenarioError::Override { key, reason } => {
            assert_eq!(key, "planner");
            assert!(reason.contains("unknown planner"));
        }
        other => panic!("{other:?}"),
    }
    let src = format!("{BASE}{GEN}");
    let l = ok(&src, &[("robot.*.params.k", "1")]);
    assert!(matches!(
        l.error_at("robot.g03.params.k", "x"),
        ScenarioError::Override { .. }
    ));
}
