//! The `shape` key of robots, `[defaults]` and obstacles: rectangles and
//! convex polygons read, their circumscribed radius computed, bad shapes
//! refused at their line, and starts checked by the true shapes.

use crate::common::*;
use mrsim_scenario::ShapeSpec;

/// Two robots with `a` and `b` as their extra lines, `r1` at `at`.
fn two(a: &str, b: &str, at: [f64; 2]) -> String {
    format!(
        "[world]\nduration = 5.0\n\n\
         [[robot]]\nname = \"r0\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n{a}\n\n\
         [[robot]]\nname = \"r1\"\nstart = [{}, {}]\ngoal = [5.0, {}]\n{b}\n",
        at[0], at[1], at[1]
    )
}

const AGV: &str = "shape = { kind = \"rectangle\", length = 0.9, width = 0.6 }";

#[test]
fn a_rectangle_is_read_with_its_circumscribed_radius() {
    let l = accept(&two(AGV, "", [0.0, 3.0]));
    let r = &l.scenario.robots[0];
    assert_eq!(
        r.shape,
        ShapeSpec::Rectangle {
            length: 0.9,
            width: 0.6
        }
    );
    assert!((r.radius - (0.45f64.powi(2) + 0.3f64.powi(2)).sqrt()).abs() < 1e-12);
    // The other robot keeps the disc of the built-in radius.
    assert_eq!(l.scenario.robots[1].shape, ShapeSpec::Disc);
    assert_eq!(l.scenario.robots[1].radius, 0.25);
}

#[test]
fn rectangles_side_by_side_start_though_their_circumscribed_discs_overlap() {
    // 0.7 apart across their width of 0.6: a gap of 0.1, discs of 0.54.
    let l = accept(&two(AGV, AGV, [0.0, 0.7]));
    assert_eq!(l.scenario.robots.len(), 2);
    // 0.5 apart they overlap by 0.1, refused at the second start.
    let src = two(AGV, AGV, [0.0, 0.5]);
    refused_at(
        &src,
        "start = [0, 0.5]",
        "starts overlapping robot `r0`: their shapes overlap by 0.1000",
    );
}

#[test]
fn defaults_give_every_robot_a_shape_and_a_polygon_is_read_as_given() {
    let src = "[defaults]\nshape = { kind = \"polygon\", points = [[-0.3, -0.2], [0.4, 0.0], [-0.3, 0.2]] }\n\n\
               [[robot]]\nname = \"a\"\nstart = [0.0, 0.0]\ngoal = [1.0, 0.0]\n\n\
               [[robot]]\nname = \"b\"\nstart = [0.0, 1.0]\ngoal = [1.0, 1.0]\n";
    let l = accept(src);
    for r in &l.scenario.robots {
        assert!(matches!(&r.shape, ShapeSpec::Polygon { points } if points.len() == 3));
        assert!((r.radius - 0.4).abs() < 1e-12);
    }
}

#[test]
fn bad_shapes_are_refused_at_their_line() {
    let src = two(
        "shape = { kind = \"polygon\", points = [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]] }",
        "",
        [0.0, 3.0],
    );
    refused_at(&src, "kind = \"polygon\"", "clockwise");
    let src = two(
        "shape = { kind = \"polygon\", points = [[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]] }",
        "",
        [0.0, 3.0],
    );
    refused_at(&src, "kind = \"polygon\"", "not convex at point 3");
    let src = two(
        "shape = { kind = \"rectangle\", length = 0.9 }",
        "",
        [0.0, 3.0],
    );
    refused_at(&src, "kind = \"rectangle\"", "needs `width`");
    let src = two(
        "shape = { kind = \"rectangle\", length = 0.9, width = -1 }",
        "",
        [0.0, 3.0],
    );
    refused_at(&src, "kind = \"rectangle\"", "shape width must be > 0");
    let src = two("shape = { kind = \"disc\", length = 1.0 }", "", [0.0, 3.0]);
    refused_at(
        &src,
        "kind = \"disc\"",
        "`length` does not apply to shape kind `disc`",
    );
    let src = two("shape = { kind = \"star\" }", "", [0.0, 3.0]);
    refused_at(&src, "kind = \"star\"", "unknown shape kind `star`");
    let src = two(&format!("radius = 0.5\n{AGV}"), "", [0.0, 3.0]);
    refused_at(&src, "radius = 0.5", "radius is the size of a disc");
}

#[test]
fn an_obstacle_takes_a_shape_and_a_heading_and_a_robot_may_not_start_inside_it() {
    let shelf = "[[obstacle]]\nname = \"shelf\"\nstart = [2.0, 0.0]\nheading_deg = 90\n\
                 shape = { kind = \"rectangle\", length = 3.0, width = 0.4 }\n";
    // Turned a quarter, the 3 m shelf spans y in [-1.5, 1.5] at x = 2:
    // a robot at (2, 1.2) starts inside it, one at (1.5, 1.2) beside it.
    let src = format!("{}{shelf}", two("", "", [1.5, 1.2]));
    let l = accept(&src);
    let o = &l.scenario.obstacles[0];
    assert!((o.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert!((o.radius - (1.5f64.powi(2) + 0.2f64.powi(2)).sqrt()).abs() < 1e-12);
    let src = format!("{}{shelf}", two("", "", [2.0, 1.2]));
    refused_at(
        &src,
        "start = [2, 1.2]",
        "starts overlapping obstacle `shelf`",
    );
}

#[test]
fn a_rectangle_against_a_wall_is_checked_by_its_corners() {
    // A unicycle faces its goal: this one, going +y, is 0.9 long along y.
    let wall = "[[wall]]\nsegment = [[-2.0, 0.5], [2.0, 0.5]]\n";
    let r =
        "kinematics = \"unicycle\"\nshape = { kind = \"rectangle\", length = 0.9, width = 0.6 }";
    let src =
        format!("[[robot]]\nname = \"r\"\nstart = [0.0, 0.0]\ngoal = [0.0, -3.0]\n{r}\n\n{wall}");
    // Facing -y its end reaches y = 0.45 < 0.5: it starts.
    accept(&src);
    let src =
        format!("[[robot]]\nname = \"r\"\nstart = [0.0, 0.1]\ngoal = [0.0, -3.0]\n{r}\n\n{wall}");
    refused_at(&src, "start = [0.0, 0.1]", "starts overlapping wall #1");
}
