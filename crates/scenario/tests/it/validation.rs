//! Every validation rule: refused, at the right line, with a reason.

use crate::common::*;
use mrsim_scenario::ScenarioError;

#[test]
fn the_base_scenario_is_valid() {
    let l = accept(BASE);
    assert_eq!(l.scenario.robots.len(), 2);
}

#[test]
fn a_syntax_error_names_line_and_column() {
    let src = with(BASE, "[world]", "[world");
    let e = refused_at(&src, "[world", "");
    match e {
        ScenarioError::Syntax { column, .. } => assert_eq!(column, 7),
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_unknown_top_level_key_is_refused_at_its_line() {
    let src = with(BASE, "description =", "colour = 1\ndescription =");
    refused_at(&src, "colour", "unknown field `colour`");
}

#[test]
fn an_unknown_world_key_is_refused_at_its_line() {
    let src = with(BASE, "substeps = 10", "substep = 10");
    let e = refused_at(&src, "substep =", "unknown field `substep`");
    assert!(e.to_string().contains("world"), "{e}");
}

#[test]
fn an_unknown_robot_key_is_refused_at_its_line_and_names_the_robot() {
    let src = with(BASE, "radius = 0.3", "radius = 0.3\ncolour = \"red\"");
    let e = refused_at(&src, "colour", "unknown field `colour`");
    assert!(e.to_string().contains("robot `r1`"), "{e}");
}

#[test]
fn an_unknown_defaults_key_is_refused_at_its_line() {
    let src = with(BASE, "mass = 1.0", "mas = 1.0");
    refused_at(&src, "mas =", "unknown field `mas`");
}

#[test]
fn an_unknown_motion_key_is_refused_at_its_line() {
    let src = with(
        BASE,
        "velocity = [1.0, 0.0] }",
        "velocity = [1.0, 0.0], speed2 = 1 }",
    );
    refused_at(&src, "speed2", "unknown field `speed2`");
}

#[test]
fn a_motion_key_of_another_model_is_refused() {
    let src = with(
        BASE,
        "velocity = [1.0, 0.0] }",
        "velocity = [1.0, 0.0], speed = 7 }",
    );
    refused_at(&src, "speed = 7", "`speed` does not apply");
}

#[test]
fn an_unknown_generate_key_is_refused_at_its_line() {
    let src =
        format!("{BASE}\n[generate]\nkind = \"circle\"\ncount = 4\nradius = 5.0\nshape = 1\n");
    refused_at(&src, "shape", "unknown field `shape`");
}

#[test]
fn an_unknown_wall_key_is_refused_at_its_line() {
    let src = with(
        BASE,
        "segment = [[-8.0, 8.0], [8.0, 8.0]]",
        "segment = [[-8.0, 8.0], [8.0, 8.0]]\nthick = 1",
    );
    refused_at(&src, "thick", "unknown field `thick`");
}

#[test]
fn a_robot_without_a_name_is_refused_at_its_table() {
    let src = with(BASE, "name = \"r1\"\n", "");
    refused_at(&src, "[[robot]]\nstart = [0.0, 3.0]", "missing `name`");
}

#[test]
fn a_robot_without_a_start_is_refused_at_its_table() {
    let src = with(BASE, "start = [0.0, 3.0]\n", "");
    refused_at(&src, "[[robot]]\nname = \"r1\"", "missing `start`");
}

#[test]
fn a_robot_without_a_goal_is_refused_at_its_table() {
    let src = with(BASE, "goal = [5.0, 0.0]\n", "");
    refused_at(&src, "[[robot]]\nname = \"r0\"", "missing `goal`");
}

#[test]
fn an_obstacle_without_a_start_is_refused_at_its_table() {
    let src = with(BASE, "start = [-5.0, -5.0]\n", "");
    refused_at(&src, "[[obstacle]]", "missing `start`");
}

#[test]
fn nan_is_refused_where_it_is_written() {
    let src = with(BASE, "radius = 0.3", "radius = nan");
    refused_at(&src, "radius = nan", "finite");
}

#[test]
fn infinity_is_refused_where_it_is_written() {
    let src = with(BASE, "dt = 0.1", "dt = inf");
    refused_at(&src, "dt = inf", "finite");
    let src = with(BASE, "start = [-5.0, -5.0]", "start = [-inf, -5.0]");
    refused_at(&src, "-inf", "finite");
}

#[test]
fn a_nan_parameter_is_refused_where_it_is_written() {
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nparams = { gain = nan }",
    );
    refused_at(&src, "gain = nan", "finite");
}

#[test]
fn a_negative_robot_radius_is_refused() {
    let src = with(BASE, "radius = 0.3", "radius = -1");
    let e = refused_at(&src, "radius = -1", "radius must be >= 0, got -1");
    assert_eq!(
        e.to_string(),
        format!(
            "t.toml:{}: robot `r1`: radius must be >= 0, got -1",
            line_of(&src, "radius = -1")
        )
    );
}

#[test]
fn a_negative_obstacle_radius_is_refused() {
    let src = with(BASE, "radius = 0.5", "radius = -0.5");
    refused_at(&src, "radius = -0.5", "obstacle `o1`: radius must be >= 0");
}

#[test]
fn a_negative_radius_in_defaults_is_refused_at_defaults() {
    let src = with(BASE, "mass = 1.0", "mass = 1.0\nradius = -2");
    refused_at(&src, "radius = -2", "defaults: radius must be >= 0");
}

#[test]
fn a_negative_generated_robot_radius_is_refused() {
    let src = format!(
        "{BASE}\n[generate]\nkind = \"circle\"\ncount = 4\nradius = 5.0\nrobot_radius = -0.1\n"
    );
    refused_at(&src, "robot_radius", "robot_radius must be >= 0");
}

#[test]
fn non_positive_quantities_are_refused() {
    for (old, new) in [
        ("mass = 1.0", "mass = 0"),
        ("mass = 1.0", "mass = -1"),
        ("dt = 0.1", "dt = 0"),
        ("dt = 0.1", "dt = -0.1"),
        ("duration = 30.0", "duration = 0"),
        ("max_speed = 1.0", "max_speed = 0"),
        ("max_accel = 2.0", "max_accel = -2"),
        ("goal_tolerance = 0.1", "goal_tolerance = 0"),
    ] {
        let src = with(BASE, old, new);
        refused_at(&src, new, "must be > 0");
    }
}

#[test]
fn zero_substeps_are_refused() {
    let src = with(BASE, "substeps = 10", "substeps = 0");
    refused_at(&src, "substeps = 0", "substeps must be >= 1");
}

#[test]
fn a_deadline_outside_the_tick_is_refused() {
    for bad in ["deadline = 0", "deadline = 1.5", "deadline = -0.5"] {
        let src = with(BASE, "deadline = 1.0", bad);
        refused_at(&src, bad, "deadline must be in (0, 1]");
    }
    accept(&with(BASE, "deadline = 1.0", "deadline = 0.25"));
}

#[test]
fn a_field_of_view_outside_0_360_is_refused() {
    for bad in ["field_of_view_deg = 0", "field_of_view_deg = 361"] {
        let src = with(BASE, "field_of_view_deg = 360", bad);
        refused_at(&src, bad, "field_of_view_deg must be in (0, 360]");
    }
    accept(&with(
        BASE,
        "field_of_view_deg = 360",
        "field_of_view_deg = 90",
    ));
}

#[test]
fn robots_starting_overlapped_are_refused_at_the_later_start() {
    // r0 has the built-in radius 0.25, r1 0.3: 0.5 apart overlaps.
    let src = with(BASE, "start = [0.0, 3.0]", "start = [0.0, 0.5]");
    refused_at(&src, "start = [0.0, 0.5]", "starts overlapping robot `r0`");
    // Just touching is not overlapping.
    accept(&with(BASE, "start = [0.0, 3.0]", "start = [0.0, 0.55]"));
}

#[test]
fn a_robot_starting_on_an_obstacle_is_refused() {
    let src = with(BASE, "start = [0.0, 3.0]", "start = [-5.0, -4.5]");
    refused_at(
        &src,
        "start = [-5.0, -4.5]",
        "starts overlapping obstacle `o1`",
    );
}

#[test]
fn a_robot_starting_on_a_wall_is_refused() {
    let src = with(BASE, "start = [0.0, 3.0]", "start = [0.0, 7.9]");
    refused_at(&src, "start = [0.0, 7.9]", "starts overlapping wall #1");
}

#[test]
fn duplicate_robot_names_are_refused() {
    let src = with(BASE, "name = \"r1\"", "name = \"r0\"\n# dup");
    refused_at(&src, "[[robot]]\nname = \"r0\"\n# dup", "duplicate name");
}

#[test]
fn a_robot_and_an_obstacle_share_one_namespace() {
    let src = with(BASE, "name = \"o1\"", "name = \"r1\"");
    refused_at(
        &src,
        "[[obstacle]]",
        "duplicate name: there is already a robot `r1`",
    );
}

#[test]
fn a_goal_outside_the_arena_is_refused() {
    let src = with(BASE, "goal = [5.0, 3.0]", "goal = [15.0, 3.0]");
    refused_at(&src, "goal = [15.0, 3.0]", "outside the arena");
}

#[test]
fn a_start_outside_the_arena_is_refused() {
    let src = with(BASE, "start = [0.0, 3.0]", "start = [0.0, -12.0]");
    refused_at(&src, "start = [0.0, -12.0]", "outside the arena");
    // The disc must fit: centre inside but rim through the wall.
    let src = with(BASE, "start = [0.0, 3.0]", "start = [0.0, -9.8]");
    refused_at(&src, "start = [0.0, -9.8]", "outside the arena");
}

#[test]
fn an_arena_with_min_not_below_max_is_refused() {
    let src = with(BASE, "max = [10.0, 10.0]", "max = [10.0, -10.0]");
    refused_at(&src, "arena =", "arena min must be < max");
}

#[test]
fn an_unknown_pursue_target_is_refused() {
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"intentional\", behavior = \"pursue\", target = \"ghost\", max_speed = 1.0, max_accel = 1.0 }",
    );
    refused_at(&src, "ghost", "unknown target `ghost`");
    accept(&src.replace("ghost", "r1"));
}

#[test]
fn a_pursuit_without_a_target_is_refused() {
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"intentional\", behavior = \"pursue\", max_speed = 1.0, max_accel = 1.0 }",
    );
    refused_at(&src, "behavior", "needs `target`");
}

#[test]
fn an_avoider_without_a_target_keeps_away_from_everyone_and_is_accepted() {
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"intentional\", behavior = \"avoid\", max_speed = 1.0, max_accel = 1.0 }",
    );
    accept(&src);
}

#[test]
fn a_boundary_without_a_path_is_refused() {
    let src = with(BASE, "radius = 0.3", "radius = 0.3\nboundary = 1.0");
    refused_at(&src, "boundary = 1.0", "boundary needs a path");
    accept(&with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nboundary = 1.0\npath = [[0, 3], [5, 3]]",
    ));
}

#[test]
fn a_path_of_one_point_is_refused() {
    let src = with(BASE, "radius = 0.3", "radius = 0.3\npath = [[0, 3]]");
    refused_at(&src, "path = ", "at least 2 points, got 1");
}

#[test]
fn waypoints_without_points_are_refused() {
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"waypoints\", points = [], speed = 1.0 }",
    );
    refused_at(&src, "points = []", "at least one point");
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"waypoints\", speed = 1.0 }",
    );
    refused_at(&src, "motion =", "needs `points`");
}

#[test]
fn waypoints_without_positive_speed_are_refused() {
    let src = with(
        BASE,
        "motion = { model = \"constant-velocity\", velocity = [1.0, 0.0] }",
        "motion = { model = \"waypoints\", points = [[0, -5]],\n  speed = 0.0 }",
    );
    refused_at(&src, "speed = 0.0", "speed must be > 0");
}

#[test]
fn an_unknown_motion_model_is_refused() {
    let src = with(BASE, "\"constant-velocity\"", "\"teleport\"");
    refused_at(&src, "teleport", "unknown motion model");
}

#[test]
fn a_scenario_without_robots_is_refused() {
    let src = "name = \"empty\"\n[world]\ndt = 0.1\n";
    let e = refuse(src);
    assert_eq!(e.line(), Some(1));
    assert!(e.to_string().contains("no robots"), "{e}");
}

#[test]
fn a_point_of_three_numbers_is_refused() {
    let src = with(BASE, "goal = [5.0, 3.0]", "goal = [5.0, 3.0, 1.0]");
    refused_at(&src, "goal = [5.0, 3.0, 1.0]", "a point [x, y]");
}

#[test]
fn a_wrong_type_is_refused_at_its_line() {
    let src = with(BASE, "radius = 0.3", "radius = \"big\"");
    refused_at(&src, "radius = \"big\"", "invalid type");
    let src = with(BASE, "dt = 0.1", "dt = 0.1\nmode = \"sometimes\"");
    refused_at(&src, "sometimes", "unknown variant");
}

#[test]
fn a_nested_table_as_a_parameter_is_refused() {
    let src = with(
        BASE,
        "radius = 0.3",
        "radius = 0.3\nparams = { k = { a = 1 } }",
    );
    refused_at(&src, "params", "a parameter must be");
}

#[test]
fn name_start_and_goal_cannot_be_defaults() {
    let src = with(BASE, "mass = 1.0", "mass = 1.0\ngoal = [1, 1]");
    refused_at(&src, "goal = [1, 1]", "cannot be a default");
}

#[test]
fn a_degenerate_wall_is_refused() {
    let src = with(
        BASE,
        "segment = [[-8.0, 8.0], [8.0, 8.0]]",
        "segment = [[1.0, 8.0], [1.0, 8.0]]",
    );
    refused_at(&src, "segment", "ends must differ");
}

#[test]
fn an_unknown_generate_kind_is_refused() {
    let src = format!("{BASE}\n[generate]\nkind = \"spiral\"\ncount = 4\nradius = 5.0\n");
    refused_at(&src, "spiral", "unknown kind");
}

#[test]
fn generated_robots_overlapping_are_refused_at_the_generate_table() {
    // 40 robots of radius 0.25 on a circle of radius 1 cannot fit.
    let src = format!(
        "{BASE}\n[generate]\nkind = \"circle\"\ncount = 40\nradius = 1.0\ncenter = [0, -6]\n"
    );
    refused_at(&src, "[generate]", "starts overlapping");
}

#[test]
fn the_io_error_names_the_path() {
    let e = mrsim_scenario::load(std::path::Path::new("/nonexistent/x.toml")).unwrap_err();
    assert!(matches!(e, ScenarioError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/x.toml"), "{e}");
    assert_eq!(e.line(), None);
}
