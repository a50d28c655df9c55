//! What the tests of cars' paths share.
#![allow(dead_code)]

use mrsim_route::{CarPose, Gear, drive::wrap};
use mrsim_shape::Pose;
use std::f64::consts::PI;

/// Checks that every step between consecutive poses is an arc (or a
/// straight) tangent to both headings, of radius at least `radius`, driven
/// in the later pose's gear: the chord bisects the two headings and
/// `2 sin(|dh| / 2) / chord <= 1 / radius`.
pub fn assert_drivable(poses: &[CarPose], radius: f64) {
    for w in poses.windows(2) {
        let (a, b) = (w[0], w[1]);
        let d = [b.position[0] - a.position[0], b.position[1] - a.position[1]];
        let chord = d[0].hypot(d[1]);
        let dh = wrap(b.heading - a.heading);
        if chord < 1e-9 {
            assert!(dh.abs() < 1e-9, "a turn on the spot: {a:?} -> {b:?}");
            continue;
        }
        let curvature = 2.0 * (dh.abs() / 2.0).sin() / chord;
        assert!(
            curvature <= (1.0 + 1e-9) / radius,
            "curvature {curvature} > 1/{radius}: {a:?} -> {b:?}"
        );
        let along = a.heading + dh / 2.0;
        let dir = d[1].atan2(d[0]);
        let want = match b.gear {
            Gear::Forward => along,
            Gear::Reverse => along + PI,
        };
        assert!(
            wrap(dir - want).abs() < 1e-6,
            "the step {a:?} -> {b:?} is not along the headings in {:?}",
            b.gear
        );
    }
}

/// Are two poses the same within `tol` (positions and heading)?
pub fn close(a: Pose, b: Pose, tol: f64) -> bool {
    (a.position[0] - b.position[0]).abs() < tol
        && (a.position[1] - b.position[1]).abs() < tol
        && wrap(a.heading - b.heading).abs() < tol
}

/// Euclidean distance.
pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A fixed stream of numbers in [0, 1) (a linear congruential generator).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
