//! Dubins and Reeds-Shepp paths: known lengths, every word's end, the
//! curvature of sampled paths, and Reeds-Shepp against Dubins.

mod common;

use common::{Lcg, assert_drivable, close, dist};
use mrsim_route::{CarPath, Gear, Piece, Steer, dubins, reeds_shepp};
use mrsim_shape::Pose;
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

/// A path's steering and gears, `L+R-L+` and so on.
fn spelling(p: &CarPath) -> String {
    p.pieces()
        .iter()
        .map(|q| {
            let c = match q.steer {
                Steer::Left => 'L',
                Steer::Straight => 'S',
                Steer::Right => 'R',
            };
            format!("{c}{}", if q.length < 0.0 { '-' } else { '+' })
        })
        .collect()
}

#[test]
fn dubins_known_lengths_a_straight_a_turn_a_u_turn_and_going_back() {
    let r = 1.5;
    let o = Pose::new([0.0, 0.0], 0.0);
    assert!((dubins::length(o, Pose::new([7.0, 0.0], 0.0), r) - 7.0).abs() < 1e-9);
    for a in [0.3, 1.0, PI / 2.0, 2.5] {
        let to = Pose::new([r * a.sin(), r * (1.0 - a.cos())], a);
        assert!((dubins::length(o, to, r) - r * a).abs() < 1e-9, "left {a}");
        let to = Pose::new([r * a.sin(), -r * (1.0 - a.cos())], -a);
        assert!((dubins::length(o, to, r) - r * a).abs() < 1e-9, "right {a}");
    }
    let u = Pose::new([0.0, 2.0 * r], PI);
    assert!((dubins::length(o, u, r) - PI * r).abs() < 1e-9);
    // Ten radii straight back: a half turn, the straight, a half turn.
    let back = Pose::new([-10.0 * r, 0.0], 0.0);
    assert!((dubins::length(o, back, r) - (TAU * r + 10.0 * r)).abs() < 1e-9);
}

#[test]
fn dubins_finds_all_six_words_and_each_ends_at_the_goal() {
    let mut rng = Lcg(7);
    let r = 0.8;
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..5000 {
        let from = Pose::new([0.0, 0.0], (rng.next() - 0.5) * TAU);
        let to = Pose::new(
            [(rng.next() - 0.5) * 8.0, (rng.next() - 0.5) * 8.0],
            (rng.next() - 0.5) * TAU,
        );
        for p in dubins::words(from, to, r) {
            assert!(close(p.end(), to, 1e-6), "{p:?}: {:?} vs {to:?}", p.end());
            assert_eq!(p.gear_changes(), 0);
            assert!(p.pieces().iter().all(|q| q.gear() == Gear::Forward));
            let s: String = spelling(&p).chars().filter(|c| c.is_alphabetic()).collect();
            seen.insert(s);
        }
    }
    // Pieces of no length are dropped, so shorter spellings show too; the
    // three-piece ones are the six words.
    let full: Vec<_> = seen.iter().filter(|s| s.len() == 3).collect();
    assert_eq!(full.len(), 6, "{seen:?}");
}

#[test]
fn reeds_shepp_candidates_are_the_48_words_and_each_ends_at_the_goal() {
    let mut rng = Lcg(11);
    let r = 1.3;
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..20000 {
        let from = Pose::new([0.3, -0.2], (rng.next() - 0.5) * TAU);
        let to = Pose::new(
            [(rng.next() - 0.5) * 10.0, (rng.next() - 0.5) * 10.0],
            (rng.next() - 0.5) * TAU,
        );
        let words = reeds_shepp::words(from, to, r);
        assert!(!words.is_empty());
        let best = reeds_shepp::length(from, to, r);
        for p in words {
            assert!(
                close(p.end(), to, 1e-6),
                "{}: {:?} vs {to:?}",
                spelling(&p),
                p.end()
            );
            assert!(p.length() >= best - 1e-12);
            assert!(p.gear_changes() <= 2, "{}", spelling(&p));
            seen.insert(spelling(&p));
        }
    }
    // Pieces of no length would drop out of a spelling, but random goals
    // never give one: every spelling is a whole word.
    assert_eq!(seen.len(), 48, "{seen:?}");
}

#[test]
fn reeds_shepp_known_lengths_a_straight_either_way_a_turn_and_a_u_turn() {
    let r = 2.0;
    let o = Pose::new([0.0, 0.0], 0.0);
    for d in [0.5, 3.0, 20.0] {
        assert!((reeds_shepp::length(o, Pose::new([d, 0.0], 0.0), r) - d).abs() < 1e-9);
        assert!((reeds_shepp::length(o, Pose::new([-d, 0.0], 0.0), r) - d).abs() < 1e-9);
    }
    for a in [0.2, 1.0, PI / 2.0, 2.8] {
        let left = Pose::new([r * a.sin(), r * (1.0 - a.cos())], a);
        assert!(
            (reeds_shepp::length(o, left, r) - r * a).abs() < 1e-9,
            "{a}"
        );
        // The same arc backwards: to the mirror image behind.
        let back = Pose::new([-r * a.sin(), r * (1.0 - a.cos())], -a);
        assert!(
            (reeds_shepp::length(o, back, r) - r * a).abs() < 1e-9,
            "{a}"
        );
        let p = reeds_shepp::shortest(o, back, r);
        assert_eq!(p.pieces().len(), 1);
        assert_eq!(p.pieces()[0].gear(), Gear::Reverse);
    }
    let u = Pose::new([0.0, 2.0 * r], PI);
    assert!((reeds_shepp::length(o, u, r) - PI * r).abs() < 1e-9);
    // Turning round on the spot is shorter backing and filling than any
    // forward loop, and needs cusps.
    let round = Pose::new([0.0, 0.0], PI);
    let turn = reeds_shepp::shortest(o, round, r);
    assert!(turn.gear_changes() >= 1, "{turn:?}");
    assert!(turn.length() < dubins::length(o, round, r) - r);
}

#[test]
fn sampled_paths_turn_no_tighter_than_the_radius_and_end_at_the_goal() {
    let r = 1.0;
    let from = Pose::new([1.0, 2.0], -0.3);
    for (to, h) in [
        ([1.5, 2.2], 0.0),
        ([0.0, 0.0], 2.0),
        ([1.0, 2.0], PI),
        ([4.0, 2.0], -3.0),
        ([1.5, 2.2], -0.3),
    ] {
        let to = Pose::new(to, h);
        for p in [
            reeds_shepp::shortest(from, to, r),
            dubins::shortest(from, to, r),
        ] {
            let poses = p.poses(0.03);
            assert_drivable(&poses, r);
            assert!(poses.windows(2).all(|w| w[1].s - w[0].s <= 0.03 + 1e-12));
            let last = poses.last().expect("poses").pose();
            assert!(close(last, to, 1e-6), "{last:?} vs {to:?}");
            assert!((poses.last().expect("poses").s - p.length()).abs() < 1e-9);
        }
    }
    // A small sideways shift needs reversing.
    let p = reeds_shepp::shortest(from, Pose::new([1.5, 2.2], -0.3), r);
    assert!(
        p.pieces().iter().any(|q| q.gear() == Gear::Reverse),
        "{p:?}"
    );
}

fn pose() -> impl Strategy<Value = Pose> {
    (-6.0..6.0f64, -6.0..6.0f64, -PI..PI).prop_map(|(x, y, h)| Pose::new([x, y], h))
}

proptest! {
    #[test]
    fn reeds_shepp_is_never_longer_than_dubins(a in pose(), b in pose(), r in 0.2..3.0f64) {
        let rs = reeds_shepp::shortest(a, b, r);
        let du = dubins::shortest(a, b, r);
        prop_assert!(rs.length() <= du.length() + 1e-9, "{} > {}", rs.length(), du.length());
        prop_assert!(close(rs.end(), b, 1e-6));
        prop_assert!(close(du.end(), b, 1e-6));
        prop_assert!(rs.length() >= dist(a.position, b.position) - 1e-9);
        assert_drivable(&rs.poses(0.1), r);
        assert_drivable(&du.poses(0.1), r);
    }

    #[test]
    fn reeds_shepp_is_as_long_both_ways_and_mirrored(a in pose(), b in pose(), r in 0.2..3.0f64) {
        let ab = reeds_shepp::length(a, b, r);
        prop_assert!((ab - reeds_shepp::length(b, a, r)).abs() < 1e-6);
        let m = |p: Pose| Pose::new([p.position[0], -p.position[1]], -p.heading);
        prop_assert!((ab - reeds_shepp::length(m(a), m(b), r)).abs() < 1e-6);
    }
}

#[test]
fn pieces_join_and_the_end_is_the_closed_form() {
    let r = 2.0;
    let p = CarPath::new(
        Pose::new([1.0, 1.0], 0.0),
        r,
        [
            Piece {
                steer: Steer::Left,
                length: PI,
            },
            Piece {
                steer: Steer::Left,
                length: PI,
            },
            Piece {
                steer: Steer::Straight,
                length: 0.0,
            },
            Piece {
                steer: Steer::Straight,
                length: -3.0,
            },
        ],
    );
    // Half a circle to the left (radius 2), then 3 back.
    assert_eq!(p.pieces().len(), 2);
    let e = p.end();
    assert!((e.position[0] - 4.0).abs() < 1e-12, "{e:?}");
    assert!((e.position[1] - 5.0).abs() < 1e-12, "{e:?}");
    assert!((e.heading - PI).abs() < 1e-12);
    assert_eq!(p.gear_changes(), 1);
    assert!((p.length() - (2.0 * PI + 3.0)).abs() < 1e-12);
    let poses = p.poses(0.1);
    assert_drivable(&poses, r);
    assert!(poses.windows(2).all(|w| w[1].s - w[0].s <= 0.1 + 1e-12));
    let last = poses.last().expect("poses");
    assert!((last.s - p.length()).abs() < 1e-12);
    assert_eq!(last.gear, Gear::Reverse);
}
