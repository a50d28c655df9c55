//! Dubins paths: the shortest way between two poses for a car that only
//! drives forwards and turns no tighter than R.
//!
//! L. E. Dubins (1957) showed that such a path is made of at most three
//! pieces, arcs of radius R (C) and straights (S), of one of six words:
//! LSL, RSR, RSL, LSR, RLR, LRL (for CCC the middle arc longer than pi R).
//! Each word's lengths have a closed form in the goal's position and both
//! headings in the frame that puts the start at the origin and the goal on
//! the x axis at distance d (scaled by 1/R), the start heading `alpha` and
//! the goal heading `beta` measured from the line between them: the
//! formulas of A. M. Shkel & V. Lumelsky, "Classification of the Dubins
//! set", Robotics and Autonomous Systems 34, 2001 (section 3), as OMPL's
//! `DubinsStateSpace` writes them (`dubinsLSL` ... `dubinsLRL`, and its
//! `mod2pi` that takes angles within 1e-7 below 0 or within 5e-7 below
//! 2 pi as 0, so that a pure turn is not a full circle). The shortest
//! feasible word is the path.

use crate::drive::{CarPath, Piece, Steer};
use mrsim_shape::Pose;
use std::f64::consts::TAU;

const EPS: f64 = 1e-6;
const ZERO: f64 = -1e-7;

/// An angle in [0, 2 pi) (OMPL's `mod2pi` of its Dubins space).
fn mod2pi(x: f64) -> f64 {
    if x < 0.0 && x > ZERO {
        return 0.0;
    }
    let xm = x - TAU * (x / TAU).floor();
    if TAU - xm < 0.5 * EPS { 0.0 } else { xm }
}

/// A word and its three lengths in radii.
#[derive(Debug, Clone, Copy)]
struct Word {
    steer: [Steer; 3],
    len: [f64; 3],
}

impl Word {
    fn length(&self) -> f64 {
        self.len.iter().sum()
    }
}

use Steer::{Left as L, Right as R, Straight as S};

/// Every feasible word for the normalised problem `(d, alpha, beta)`,
/// in OMPL's order: LSL, RSR, RSL, LSR, RLR, LRL.
fn candidates(d: f64, alpha: f64, beta: f64) -> impl Iterator<Item = Word> {
    let (sa, ca) = alpha.sin_cos();
    let (sb, cb) = beta.sin_cos();
    let w = |steer, len| Some(Word { steer, len });
    // LSL.
    let lsl = {
        let tmp = 2.0 + d * d - 2.0 * (ca * cb + sa * sb - d * (sa - sb));
        if tmp >= ZERO {
            let theta = (cb - ca).atan2(d + sa - sb);
            w(
                [L, S, L],
                [
                    mod2pi(theta - alpha),
                    tmp.max(0.0).sqrt(),
                    mod2pi(beta - theta),
                ],
            )
        } else {
            None
        }
    };
    // RSR.
    let rsr = {
        let tmp = 2.0 + d * d - 2.0 * (ca * cb + sa * sb - d * (sb - sa));
        if tmp >= ZERO {
            let theta = (ca - cb).atan2(d - sa + sb);
            w(
                [R, S, R],
                [
                    mod2pi(alpha - theta),
                    tmp.max(0.0).sqrt(),
                    mod2pi(theta - beta),
                ],
            )
        } else {
            None
        }
    };
    // RSL.
    let rsl = {
        let tmp = d * d - 2.0 + 2.0 * (ca * cb + sa * sb - d * (sa + sb));
        if tmp >= ZERO {
            let p = tmp.max(0.0).sqrt();
            let theta = (ca + cb).atan2(d - sa - sb) - 2f64.atan2(p);
            w([R, S, L], [mod2pi(alpha - theta), p, mod2pi(beta - theta)])
        } else {
            None
        }
    };
    // LSR.
    let lsr = {
        let tmp = -2.0 + d * d + 2.0 * (ca * cb + sa * sb + d * (sa + sb));
        if tmp >= ZERO {
            let p = tmp.max(0.0).sqrt();
            let theta = (-ca - cb).atan2(d + sa + sb) - (-2f64).atan2(p);
            w([L, S, R], [mod2pi(theta - alpha), p, mod2pi(theta - beta)])
        } else {
            None
        }
    };
    // RLR.
    let rlr = {
        let tmp = 0.125 * (6.0 - d * d + 2.0 * (ca * cb + sa * sb + d * (sa - sb)));
        if tmp.abs() < 1.0 {
            let p = TAU - tmp.acos();
            let theta = (ca - cb).atan2(d - sa + sb);
            let t = mod2pi(alpha - theta + 0.5 * p);
            w([R, L, R], [t, p, mod2pi(alpha - beta - t + p)])
        } else {
            None
        }
    };
    // LRL.
    let lrl = {
        let tmp = 0.125 * (6.0 - d * d + 2.0 * (ca * cb + sa * sb - d * (sa - sb)));
        if tmp.abs() < 1.0 {
            let p = TAU - tmp.acos();
            let theta = (cb - ca).atan2(d + sa - sb);
            let t = mod2pi(theta - alpha + 0.5 * p);
            w([L, R, L], [t, p, mod2pi(beta - alpha - t + p)])
        } else {
            None
        }
    };
    [lsl, rsr, rsl, lsr, rlr, lrl].into_iter().flatten()
}

/// The normalised problem of going from `from` to `to` at radius `radius`:
/// `(d, alpha, beta)` as in the module documentation.
fn normalise(from: Pose, to: Pose, radius: f64) -> (f64, f64, f64) {
    let dx = to.position[0] - from.position[0];
    let dy = to.position[1] - from.position[1];
    let d = dx.hypot(dy) / radius;
    let th = dy.atan2(dx);
    (d, mod2pi(from.heading - th), mod2pi(to.heading - th))
}

/// The shortest word, in radii (a pose onto itself: no pieces).
fn best(d: f64, alpha: f64, beta: f64) -> Option<Word> {
    if d < EPS && (alpha - beta).abs() < EPS {
        return Some(Word {
            steer: [L, S, L],
            len: [0.0, d, 0.0],
        });
    }
    let mut best: Option<Word> = None;
    for w in candidates(d, alpha, beta) {
        if best.is_none_or(|b| w.length() < b.length()) {
            best = Some(w);
        }
    }
    best
}

/// The length of the shortest forward-only path from `from` to `to` for a
/// car turning no tighter than `radius`.
pub fn length(from: Pose, to: Pose, radius: f64) -> f64 {
    let (d, a, b) = normalise(from, to, radius);
    best(d, a, b).map_or(f64::INFINITY, |w| w.length() * radius)
}

/// The shortest forward-only path from `from` to `to` for a car turning no
/// tighter than `radius` (> 0).
///
/// ```
/// use mrsim_route::dubins;
/// use mrsim_shape::Pose;
/// // A U-turn: half a circle.
/// let p = dubins::shortest(Pose::new([0.0, 0.0], 0.0), Pose::new([0.0, 4.0], std::f64::consts::PI), 2.0);
/// assert!((p.length() - 2.0 * std::f64::consts::PI).abs() < 1e-9);
/// ```
pub fn shortest(from: Pose, to: Pose, radius: f64) -> CarPath {
    let (d, a, b) = normalise(from, to, radius);
    // Some word is always feasible (LSL or RSR whenever the goal is far,
    // and one of the six for every pose: Dubins' theorem); a pose the
    // formulas fail on (NaN input) yields the empty path.
    let pieces = best(d, a, b).into_iter().flat_map(|w| {
        (0..3).map(move |k| Piece {
            steer: w.steer[k],
            length: w.len[k] * radius,
        })
    });
    CarPath::new(from, radius, pieces)
}

/// Every feasible word of the six from `from` to `to` at `radius`, as a
/// path (the shortest is [`shortest`]'s).
pub fn words(from: Pose, to: Pose, radius: f64) -> Vec<CarPath> {
    let (d, a, b) = normalise(from, to, radius);
    candidates(d, a, b)
        .map(|w| {
            CarPath::new(
                from,
                radius,
                (0..3).map(|k| Piece {
                    steer: w.steer[k],
                    length: w.len[k] * radius,
                }),
            )
        })
        .collect()
}
