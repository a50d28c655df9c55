//! Reeds-Shepp paths: the shortest way between two poses for a car that
//! drives forwards and backwards and turns no tighter than R.
//!
//! J. A. Reeds & L. A. Shepp, "Optimal paths for a car that goes both
//! forwards and backwards", Pacific J. Math. 145(2), 1990, showed that such
//! a path is one of 48 words of at most five pieces, arcs of radius R (C)
//! and straights (S), with at most two cusps (`|`, a change of gear); their
//! table lists them in nine families: C|C|C, CC|C, C|CC, CSC,
//! CC<sub>u</sub>|C<sub>u</sub>C, C|C<sub>u</sub>C<sub>u</sub>|C,
//! C|C<sub>pi/2</sub>SC, CSC<sub>pi/2</sub>|C and
//! C|C<sub>pi/2</sub>SC<sub>pi/2</sub>|C (4 + 4 + 4 + 8 + 4 + 4 + 8 + 8 + 4 =
//! 48). Section 8 gives closed forms for one base word of each family in
//! the start's frame scaled by 1/R (goal at `(x, y)`, heading `phi`); the
//! other words of a family are the base word under three symmetries
//! (section 7): *timeflip* (`(-x, y, -phi)`, every piece driven the other
//! way), *reflect* (`(x, -y, -phi)`, left and right swapped) and
//! *backwards* (the goal's frame seen from the goal, the pieces in reverse
//! order).
//!
//! This follows OMPL's `ReedsSheppStateSpace` (ompl/base/spaces/src/
//! ReedsSheppStateSpace.cpp) formula by formula: `LpSpLp` (8.1), `LpSpRp`
//! (8.2), `LpRmL` (8.3/8.4, with OMPL's correction of the paper's typo),
//! `LpRupLumRm` (8.7), `LpRumLumRp` (8.8), `LpRmSmLm` (8.9), `LpRmSmRm`
//! (8.10) and `LpRmSLmRp` (8.11, corrected), each under the symmetries as
//! OMPL applies them in `CSC`, `CCC`, `CCCC`, `CCSC` and `CCSCC`: 48 words,
//! the shortest feasible one the path. Its 18 path types are
//! [`TYPES`]; a word's lengths are in radii, signed (`p`: forwards, `m`:
//! backwards, `u` the CCCC families' shared arc).

use crate::drive::{CarPath, Piece, Steer};
use mrsim_shape::Pose;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// What counts as zero in the formulas' sign tests (OMPL's `ZERO`).
const ZERO: f64 = 10.0 * f64::EPSILON;

use Steer::{Left as L, Right as R, Straight as S};

/// OMPL's `reedsSheppPathType`: the 18 sequences of steering the 48 words
/// use (with the signs of their lengths).
pub const TYPES: [&[Steer]; 18] = [
    &[L, R, L],
    &[R, L, R],
    &[L, R, L, R],
    &[R, L, R, L],
    &[L, R, S, L],
    &[R, L, S, R],
    &[L, S, R, L],
    &[R, S, L, R],
    &[L, R, S, R],
    &[R, L, S, L],
    &[R, S, R, L],
    &[L, S, L, R],
    &[L, S, R],
    &[R, S, L],
    &[L, S, L],
    &[R, S, R],
    &[L, R, S, L, R],
    &[R, L, S, R, L],
];

/// A word: a path type of [`TYPES`] and its signed lengths in radii.
#[derive(Debug, Clone, Copy)]
struct Word {
    kind: usize,
    len: [f64; 5],
}

impl Word {
    fn new(kind: usize, lens: &[f64]) -> Self {
        let mut len = [0.0; 5];
        len[..lens.len()].copy_from_slice(lens);
        Self { kind, len }
    }

    fn length(&self) -> f64 {
        self.len.iter().map(|l| l.abs()).sum()
    }

    /// The pieces, at radius `r`.
    fn pieces(&self, r: f64) -> impl Iterator<Item = Piece> + '_ {
        TYPES[self.kind]
            .iter()
            .zip(self.len)
            .map(move |(&steer, l)| Piece {
                steer,
                length: l * r,
            })
    }
}

/// An angle in [-pi, pi] (OMPL's `mod2pi` of its Reeds-Shepp space).
fn mod2pi(x: f64) -> f64 {
    let v = x % TAU;
    if v < -PI {
        v + TAU
    } else if v > PI {
        v - TAU
    } else {
        v
    }
}

fn polar(x: f64, y: f64) -> (f64, f64) {
    (x.hypot(y), y.atan2(x))
}

fn tau_omega(u: f64, v: f64, xi: f64, eta: f64, phi: f64) -> (f64, f64) {
    let delta = mod2pi(u - v);
    let a = u.sin() - delta.sin();
    let b = u.cos() - delta.cos() - 1.0;
    let t1 = (eta * a - xi * b).atan2(xi * a + eta * b);
    let t2 = 2.0 * (delta.cos() - v.cos() - u.cos()) + 3.0;
    let tau = if t2 < 0.0 {
        mod2pi(t1 + PI)
    } else {
        mod2pi(t1)
    };
    (tau, mod2pi(tau - u + v - phi))
}

/// Formula 8.1: L+ S+ L+.
fn lp_sp_lp(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let (u, t) = polar(x - sp, y - 1.0 + cp);
    if t >= -ZERO {
        let v = mod2pi(phi - t);
        if v >= -ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formula 8.2: L+ S+ R+.
fn lp_sp_rp(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let (u1, t1) = polar(x + sp, y - 1.0 - cp);
    let u1 = u1 * u1;
    if u1 >= 4.0 {
        let u = (u1 - 4.0).sqrt();
        let theta = 2f64.atan2(u);
        let t = mod2pi(t1 + theta);
        let v = mod2pi(t - phi);
        if t >= -ZERO && v >= -ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formulas 8.3 and 8.4: L+ R- L (the last arc of either sign).
fn lp_rm_l(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let (u1, theta) = polar(x - sp, y - 1.0 + cp);
    if u1 <= 4.0 {
        let u = -2.0 * (0.25 * u1).asin();
        let t = mod2pi(theta + 0.5 * u + PI);
        let v = mod2pi(phi - t + u);
        if t >= -ZERO && u <= ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formula 8.7: L+ R+u L-u R-.
fn lp_rup_lum_rm(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let xi = x + sp;
    let eta = y - 1.0 - cp;
    let rho = 0.25 * (2.0 + xi.hypot(eta));
    if rho <= 1.0 {
        let u = rho.acos();
        let (t, v) = tau_omega(u, -u, xi, eta, phi);
        if t >= -ZERO && v <= ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formula 8.8: L+ R-u L-u R+.
fn lp_rum_lum_rp(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let xi = x + sp;
    let eta = y - 1.0 - cp;
    let rho = (20.0 - xi * xi - eta * eta) / 16.0;
    if (0.0..=1.0).contains(&rho) {
        let u = -rho.acos();
        if u >= -FRAC_PI_2 {
            let (t, v) = tau_omega(u, u, xi, eta, phi);
            if t >= -ZERO && v >= -ZERO {
                return Some([t, u, v]);
            }
        }
    }
    None
}

/// Formula 8.9: L+ R-pi/2 S- L-.
fn lp_rm_sm_lm(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let (rho, theta) = polar(x - sp, y - 1.0 + cp);
    if rho >= 2.0 {
        let r = (rho * rho - 4.0).sqrt();
        let u = 2.0 - r;
        let t = mod2pi(theta + r.atan2(-2.0));
        let v = mod2pi(phi - FRAC_PI_2 - t);
        if t >= -ZERO && u <= ZERO && v <= ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formula 8.10: L+ R-pi/2 S- R-.
fn lp_rm_sm_rm(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let xi = x + sp;
    let eta = y - 1.0 - cp;
    let (rho, theta) = polar(-eta, xi);
    if rho >= 2.0 {
        let t = theta;
        let u = 2.0 - rho;
        let v = mod2pi(t + FRAC_PI_2 - phi);
        if t >= -ZERO && u <= ZERO && v <= ZERO {
            return Some([t, u, v]);
        }
    }
    None
}

/// Formula 8.11: L+ R-pi/2 S- L-pi/2 R+.
fn lp_rm_s_lm_rp(x: f64, y: f64, phi: f64, sp: f64, cp: f64) -> Option<[f64; 3]> {
    let xi = x + sp;
    let eta = y - 1.0 - cp;
    let (rho, _) = polar(xi, eta);
    if rho >= 2.0 {
        let u = 4.0 - (rho * rho - 4.0).sqrt();
        if u <= ZERO {
            let t = mod2pi(((4.0 - u) * xi - 2.0 * eta).atan2(-2.0 * xi + (u - 4.0) * eta));
            let v = mod2pi(t - phi);
            if t >= -ZERO && v >= -ZERO {
                return Some([t, u, v]);
            }
        }
    }
    None
}

/// A formula of section 8: the base word's lengths for a goal `(x, y, phi)`
/// (and phi's sine and cosine).
type Formula = fn(f64, f64, f64, f64, f64) -> Option<[f64; 3]>;

/// Every feasible word of the 48 for the goal `(x, y, phi)` in the start's
/// frame scaled by 1/R, in OMPL's order (its `CSC`, `CCC`, `CCCC`, `CCSC`,
/// `CCSCC`), handed to `f`.
fn candidates(x: f64, y: f64, phi: f64, f: &mut dyn FnMut(Word)) {
    // The four symmetries of a base formula (section 7): the goal as each
    // sees it, whether left and right swap (the type after the base's),
    // and whether the lengths change sign.
    let (sp, cp) = phi.sin_cos();
    let four = |x: f64, y: f64| {
        [
            (x, y, phi, sp, 0, 1.0),
            (-x, y, -phi, -sp, 0, -1.0),
            (x, -y, -phi, -sp, 1, 1.0),
            (-x, -y, phi, sp, 1, -1.0),
        ]
    };
    // The goal's frame seen from the goal: the path driven the other way.
    let (xb, yb) = (x * cp + y * sp, x * sp - y * cp);
    let family = |formula: Formula,
                  kind: usize,
                  backwards: bool,
                  lens: &dyn Fn([f64; 3]) -> Vec<f64>,
                  f: &mut dyn FnMut(Word)| {
        let (bx, by) = if backwards { (xb, yb) } else { (x, y) };
        for (gx, gy, gphi, gs, swap, sign) in four(bx, by) {
            if let Some(tuv) = formula(gx, gy, gphi, gs, cp) {
                let mut l = lens(tuv);
                if backwards {
                    l.reverse();
                }
                for v in &mut l {
                    *v *= sign;
                }
                f(Word::new(kind + swap, &l));
            }
        }
    };
    let tuv = |[t, u, v]: [f64; 3]| vec![t, u, v];
    // CSC: L+S+L+ (types 14, 15), L+S+R+ (12, 13).
    family(lp_sp_lp, 14, false, &tuv, f);
    family(lp_sp_rp, 12, false, &tuv, f);
    // CCC: C|C|C and C|CC, then CC|C (and C|C|C again) backwards.
    family(lp_rm_l, 0, false, &tuv, f);
    family(lp_rm_l, 0, true, &tuv, f);
    // CCCC.
    family(lp_rup_lum_rm, 2, false, &|[t, u, v]| vec![t, u, -u, v], f);
    family(lp_rum_lum_rp, 2, false, &|[t, u, v]| vec![t, u, u, v], f);
    // CCSC and, backwards, CSCC.
    let ccsc = |[t, u, v]: [f64; 3]| vec![t, -FRAC_PI_2, u, v];
    family(lp_rm_sm_lm, 4, false, &ccsc, f);
    family(lp_rm_sm_rm, 8, false, &ccsc, f);
    family(lp_rm_sm_lm, 6, true, &ccsc, f);
    family(lp_rm_sm_rm, 10, true, &ccsc, f);
    // CCSCC.
    family(
        lp_rm_s_lm_rp,
        16,
        false,
        &|[t, u, v]| vec![t, -FRAC_PI_2, u, -FRAC_PI_2, v],
        f,
    );
}

/// The goal in the start's frame, scaled by 1/R.
fn normalise(from: Pose, to: Pose, radius: f64) -> (f64, f64, f64) {
    let dx = to.position[0] - from.position[0];
    let dy = to.position[1] - from.position[1];
    let (s, c) = from.heading.sin_cos();
    let x = (c * dx + s * dy) / radius;
    let y = (-s * dx + c * dy) / radius;
    (x, y, to.heading - from.heading)
}

/// The shortest word (the first of equal ones, as OMPL keeps it).
fn best(x: f64, y: f64, phi: f64) -> Option<Word> {
    let mut best: Option<Word> = None;
    candidates(x, y, phi, &mut |w| {
        if best.is_none_or(|b| w.length() < b.length()) {
            best = Some(w);
        }
    });
    best
}

/// The length of the shortest path from `from` to `to` for a car turning
/// no tighter than `radius`, forwards and backwards.
pub fn length(from: Pose, to: Pose, radius: f64) -> f64 {
    let (x, y, phi) = normalise(from, to, radius);
    best(x, y, phi).map_or(f64::INFINITY, |w| w.length() * radius)
}

/// The shortest path from `from` to `to` for a car turning no tighter
/// than `radius` (> 0), forwards and backwards.
///
/// ```
/// use mrsim_route::{reeds_shepp, Gear};
/// use mrsim_shape::Pose;
/// // Three metres straight back.
/// let p = reeds_shepp::shortest(Pose::new([0.0, 0.0], 0.0), Pose::new([-3.0, 0.0], 0.0), 2.0);
/// assert!((p.length() - 3.0).abs() < 1e-9);
/// assert_eq!(p.pieces()[0].gear(), Gear::Reverse);
/// ```
pub fn shortest(from: Pose, to: Pose, radius: f64) -> CarPath {
    let (x, y, phi) = normalise(from, to, radius);
    match best(x, y, phi) {
        Some(w) => CarPath::new(from, radius, w.pieces(radius)),
        // Some word is feasible for every finite goal (Reeds & Shepp's
        // theorem); NaN input gets the empty path.
        None => CarPath::new(from, radius, []),
    }
}

/// Every feasible word of the 48 from `from` to `to` at `radius`, as a
/// path, in OMPL's order (the shortest is [`shortest`]'s, the first of
/// equals).
pub fn words(from: Pose, to: Pose, radius: f64) -> Vec<CarPath> {
    let (x, y, phi) = normalise(from, to, radius);
    let mut out = Vec::new();
    candidates(x, y, phi, &mut |w| {
        out.push(CarPath::new(from, radius, w.pieces(radius)))
    });
    out
}
