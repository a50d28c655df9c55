use super::*;
use proptest::prelude::*;
use std::f64::consts::FRAC_PI_2;

fn rect(l: f64, w: f64) -> Shape {
    Shape::Polygon(Polygon::rectangle(l, w).unwrap())
}

fn close(a: f64, b: f64) {
    assert!((a - b).abs() < 1e-12, "{a} != {b}");
}

#[test]
fn rectangles_side_by_side_are_apart_by_the_gap_between_their_sides() {
    // 0.9 x 0.6 at the origin and at (0, 0.8): long sides 0.8 - 0.6 = 0.2
    // apart, though their circumscribed discs (0.541 each) overlap by 0.28.
    let a = rect(0.9, 0.6);
    let g = gap(
        &a,
        Pose::new([0.0, 0.0], 0.0),
        &a,
        Pose::new([0.0, 0.8], 0.0),
    );
    close(g, 0.2);
    assert!(0.8 - 2.0 * a.circumradius() < 0.0);
}

#[test]
fn a_rectangle_turned_a_quarter_meets_another_with_its_short_side() {
    // A 2 x 1 turned by 90 degrees reaches 1 along x; the other's end is at
    // x = 3 - 1 = 2: gap 1.
    let a = rect(2.0, 1.0);
    let g = gap(
        &a,
        Pose::new([0.0, 0.0], FRAC_PI_2),
        &a,
        Pose::new([3.0, 0.0], 0.0),
    );
    close(g, 3.0 - 0.5 - 1.0);
}

#[test]
fn corner_to_corner_the_gap_is_the_distance_between_the_corners() {
    // Unit squares at (0, 0) and (2, 2): corners (0.5, 0.5) and (1.5, 1.5).
    let a = rect(1.0, 1.0);
    let g = gap(&a, Pose::default(), &a, Pose::new([2.0, 2.0], 0.0));
    close(g, 2f64.sqrt());
}

#[test]
fn a_diamond_points_its_corner_at_a_square_side() {
    // A unit square turned 45 degrees reaches sqrt(2)/2 along x; the other
    // square's side is at 2 - 0.5 = 1.5.
    let a = rect(1.0, 1.0);
    let g = gap(
        &a,
        Pose::new([0.0, 0.0], std::f64::consts::FRAC_PI_4),
        &a,
        Pose::new([2.0, 0.0], 0.0),
    );
    close(g, 1.5 - 0.5f64.sqrt());
}

#[test]
fn overlapping_rectangles_measure_minus_the_depth_of_their_overlap() {
    // Two 2 x 1 at x = 0 and x = 1.5 along their length: they overlap by
    // 0.5 along x (and by 1 along y): the gap is -0.5.
    let a = rect(2.0, 1.0);
    let g = gap(&a, Pose::default(), &a, Pose::new([1.5, 0.2], 0.0));
    close(g, -0.5);
}

#[test]
fn a_disc_beside_a_rectangle_is_apart_by_centre_to_side_less_radius() {
    let r = rect(2.0, 1.0);
    let d = Shape::disc(0.25);
    close(
        gap(&d, Pose::new([0.0, 1.0], 0.0), &r, Pose::default()),
        0.25,
    );
    // Beyond a corner: the distance to the corner.
    let g = gap(&r, Pose::default(), &d, Pose::new([4.0, 4.5], 0.0));
    close(g, (9.0f64 + 16.0).sqrt() - 0.25);
    // Its centre inside: minus the distance to the nearest side and the
    // radius.
    close(
        gap(&d, Pose::new([0.0, 0.3], 0.0), &r, Pose::default()),
        -0.2 - 0.25,
    );
}

#[test]
fn two_discs_keep_the_gap_mrsim_always_measured() {
    let (a, b) = (Shape::disc(0.3), Shape::disc(0.2));
    let (pa, pb): ([f64; 2], [f64; 2]) = ([0.1, 0.7], [1.3, -0.4]);
    let dx = pa[0] - pb[0];
    let dy = pa[1] - pb[1];
    let old = (dx * dx + dy * dy).sqrt() - 0.3 - 0.2;
    assert_eq!(
        gap(&a, Pose::new(pa, 1.0), &b, Pose::new(pb, 2.0)).to_bits(),
        old.to_bits()
    );
}

#[test]
fn a_wall_through_a_rectangle_reaches_into_it_by_its_depth() {
    let r = rect(2.0, 1.0);
    // A wall along y = 0.8: 0.3 beyond the top side.
    close(
        gap_to_segment(&r, Pose::default(), [[-5.0, 0.8], [5.0, 0.8]]),
        0.3,
    );
    // Along y = 0.4: 0.1 into it (the top side must move down by 0.1).
    close(
        gap_to_segment(&r, Pose::default(), [[-5.0, 0.4], [5.0, 0.4]]),
        -0.1,
    );
    // A disc keeps the distance to its centre less its radius.
    let d = Shape::disc(0.5);
    close(
        gap_to_segment(&d, Pose::default(), [[-5.0, 0.8], [5.0, 0.8]]),
        0.3,
    );
}

#[test]
fn a_rectangle_closing_on_another_touches_when_the_gap_is_covered() {
    // 2 x 1 rectangles end to end 3 apart along x: gap 1; closing at 0.5
    // m/s they touch after 2 s. Sideways by 1.2 they pass: never.
    let a = rect(2.0, 1.0);
    let t = time_to_contact(
        &a,
        Pose::default(),
        &a,
        Pose::new([3.0, 0.0], 0.0),
        [-0.5, 0.0],
        0.0,
    );
    assert!((t - 2.0).abs() < 1e-6, "{t}");
    let t = time_to_contact(
        &a,
        Pose::default(),
        &a,
        Pose::new([3.0, 1.2], 0.0),
        [-0.5, 0.0],
        0.0,
    );
    assert_eq!(t, f64::INFINITY);
    let t = time_to_contact(
        &a,
        Pose::default(),
        &a,
        Pose::new([3.0, 0.0], 0.0),
        [0.5, 0.0],
        0.0,
    );
    assert_eq!(t, f64::INFINITY);
}

#[test]
fn non_convex_and_clockwise_polygons_are_refused() {
    let arrow = [[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]];
    assert_eq!(Polygon::new(&arrow), Err(PolygonError::NotConvex(3)));
    let star: Vec<P2> = (0..5)
        .map(|i| {
            let a = i as f64 * 4.0 * std::f64::consts::PI / 5.0;
            [a.cos(), a.sin()]
        })
        .collect();
    assert!(matches!(
        Polygon::new(&star),
        Err(PolygonError::NotConvex(_))
    ));
    let line = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]];
    assert!(matches!(
        Polygon::new(&line),
        Err(PolygonError::NotConvex(_))
    ));
    assert_eq!(
        Polygon::new(&[[0.0, 0.0], [1.0, 0.0]]),
        Err(PolygonError::Count(2))
    );
    assert!(Polygon::rectangle(0.0, 1.0).is_err());
}

fn arb_shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        (0.0..1.0f64).prop_map(Shape::disc),
        (0.05..2.0f64, 0.05..2.0f64).prop_map(|(l, w)| rect(l, w)),
        // A regular polygon of 3 to 8 sides, stretched, off centre.
        (3usize..=8, 0.1..1.5f64, 0.3..1.0f64, -0.3..0.3f64).prop_map(|(n, r, k, c)| {
            let pts: Vec<P2> = (0..n)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / n as f64;
                    [c + r * a.cos(), k * r * a.sin()]
                })
                .collect();
            Shape::Polygon(Polygon::new(&pts).unwrap())
        }),
    ]
}

fn arb_pose() -> impl Strategy<Value = Pose> {
    (-3.0..3.0f64, -3.0..3.0f64, -4.0..4.0f64).prop_map(|(x, y, h)| Pose::new([x, y], h))
}

proptest! {
    #[test]
    fn the_gap_is_the_same_either_way_round(a in arb_shape(), pa in arb_pose(), b in arb_shape(), pb in arb_pose()) {
        let (x, y) = (gap(&a, pa, &b, pb), gap(&b, pb, &a, pa));
        prop_assert!((x - y).abs() < 1e-9, "{} {}", x, y);
    }

    #[test]
    fn shapes_placed_once_give_the_same_gap(a in arb_shape(), pa in arb_pose(), b in arb_shape(), pb in arb_pose()) {
        let placed = placed_gap(&Placement::of(&a, pa), &Placement::of(&b, pb));
        prop_assert_eq!(placed.to_bits(), gap(&a, pa, &b, pb).to_bits());
    }

    #[test]
    fn the_true_gap_is_never_below_the_circumscribed_discs_gap(a in arb_shape(), pa in arb_pose(), b in arb_shape(), pb in arb_pose()) {
        let discs = gap(&Shape::disc(a.circumradius()), pa, &Shape::disc(b.circumradius()), pb);
        prop_assert!(gap(&a, pa, &b, pb) >= discs - 1e-9);
    }

    #[test]
    fn moving_apart_by_the_gap_leaves_them_touching(a in arb_shape(), pa in arb_pose(), b in arb_shape(), pb in arb_pose()) {
        // Moving b away along the line of centres by d changes the gap by
        // at most d (the gap is 1-Lipschitz in translation).
        let g = gap(&a, pa, &b, pb);
        let d = [pb.position[0] - pa.position[0], pb.position[1] - pa.position[1]];
        let n = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-9);
        let moved = Pose::new([pb.position[0] + 0.1 * d[0] / n, pb.position[1] + 0.1 * d[1] / n], pb.heading);
        prop_assert!(gap(&a, pa, &b, moved) <= g + 0.1 + 1e-9);
    }
}

#[test]
fn a_turned_rectangle_sliding_onto_another_touches_where_its_gap_closes() {
    // b, turned 45 degrees and off the axis, slides along -x and then
    // along a slant onto a: at the time given the gap is closed, just
    // before it is open, and conservative advancement of the gap agrees.
    let (a, b) = (rect(2.0, 1.0), rect(1.0, 0.6));
    let pb = Pose::new([4.0, 0.7], std::f64::consts::FRAC_PI_4);
    for v in [[-1.0, 0.0], [-0.8, -0.3], [-0.5, 0.05]] {
        let t = time_to_contact(&a, Pose::default(), &b, pb, v, 0.0);
        assert!(t.is_finite() && t > 0.0, "{v:?}: {t}");
        let at = |t: f64| {
            gap(
                &a,
                Pose::default(),
                &b,
                Pose::new([4.0 + v[0] * t, 0.7 + v[1] * t], pb.heading),
            )
        };
        assert!(at(t).abs() < 1e-9, "{v:?}: gap {} at {t}", at(t));
        assert!(at(t - 1e-6) > 0.0);
        let mut s = 0.0;
        for _ in 0..200 {
            s += at(s) / (v[0] * v[0] + v[1] * v[1]).sqrt();
        }
        assert!((s - t).abs() < 1e-8, "{v:?}: advanced to {s}, exact {t}");
    }
    // Moving away, or passing above: never.
    let away = time_to_contact(&a, Pose::default(), &b, pb, [1.0, 0.0], 0.0);
    assert_eq!(away, f64::INFINITY);
    let above = time_to_contact(
        &a,
        Pose::default(),
        &b,
        Pose::new([4.0, 1.5], 0.7),
        [-1.0, 0.0],
        0.0,
    );
    assert_eq!(above, f64::INFINITY);
}
