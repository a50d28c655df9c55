//! The contact geometry dwa's two searches share: when a moving disc
//! first touches a disc or a wall segment, and where the laser scan's
//! returns are.

use crate::{Observation, Segment, Vec2};

/// Smallest t >= 0 with |p + v t| <= r, for a point at `p` moving at `v`
/// relative to a disc of radius `r` at the origin; `None` if never. A point
/// already inside counts as a contact at 0 only while it moves inwards.
pub(super) fn time_to_disc(p: Vec2, v: Vec2, r: f64) -> Option<f64> {
    let c = p.norm_squared() - r * r;
    let b = p.dot(&v);
    if c <= 0.0 {
        return (b < 0.0).then_some(0.0);
    }
    let a = v.norm_squared();
    if b >= 0.0 || a <= f64::EPSILON {
        return None;
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    Some((-b - disc.sqrt()) / a)
}

/// Time until a disc of radius `r` at `p` moving at `v` first touches the
/// static segment `s`; `None` if never.
pub(super) fn time_to_segment(p: Vec2, v: Vec2, r: f64, s: &Segment) -> Option<f64> {
    let closest = s.closest_point(p);
    let gap = p - closest;
    if gap.norm() <= r {
        // Touching already: contact now only when moving into the wall.
        return (gap.dot(&v) < 0.0).then_some(0.0);
    }
    // The two round ends.
    let mut best = [s.a, s.b]
        .iter()
        .filter_map(|&e| time_to_disc(p - e, v, r))
        .fold(f64::INFINITY, f64::min);
    // The flat sides: the line through the segment, offset by r.
    let ab = s.b - s.a;
    let len = ab.norm();
    if len > f64::EPSILON {
        let n = Vec2::new(-ab.y, ab.x) / len;
        let dist = (p - s.a).dot(&n);
        let closing = -v.dot(&n) * dist.signum();
        if closing > 0.0 {
            let t = (dist.abs() - r) / closing;
            let q = p + v * t;
            let along = (q - s.a).dot(&ab) / (len * len);
            if (0.0..=1.0).contains(&along) {
                best = best.min(t);
            }
        }
    }
    best.is_finite().then_some(best)
}

/// The returns of the observation's scan (finite ranges) as points in the
/// robot's frame (x along its heading).
pub(super) fn scan_points<'a>(obs: &'a Observation) -> impl Iterator<Item = Vec2> + 'a {
    obs.scan.into_iter().flat_map(|s| {
        s.ranges.iter().enumerate().filter_map(move |(k, &r)| {
            let a = s.angle_min + s.angle_increment * k as f64;
            r.is_finite().then(|| Vec2::new(a.cos(), a.sin()) * r)
        })
    })
}
