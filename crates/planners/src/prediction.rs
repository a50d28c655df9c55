//! Obstacle motion prediction: Zhu & Loh, "Modeling and Control Strategies
//! for Dynamical Obstacle Avoidance by Mobile Robots", section 3.2, shared by
//! the `trajectory-guided` and `free-space` planners.
//!
//! Every sensed body (robot or obstacle) is predicted over the horizon by one
//! of three approaches, chosen per planner with `prediction`:
//!
//! - `"anticipation"` (default), eq (3.1): constant velocity,
//!   `s(t0 + t) = s(t0) + v(t0) t`.
//! - `"extended"`, eq (3.2) with the paper's N = 3 example: the anticipated
//!   velocity is a function of the last three observed velocities. "Taking
//!   two equal velocities among the three as the anticipated velocity; if all
//!   three are different, then take the current one or the average of the
//!   three" ([`vote`]). Which of the two fallbacks is a parameter,
//!   `extended_fallback = "current" | "average"` (default `"current"`).
//!   The paper's velocities come from pixel disparities, so "equal" is exact
//!   there; ours are real numbers, so two velocities are equal when they
//!   differ by at most `vote_tolerance` (scenario length per second, default
//!   1e-6: equal up to rounding; raise it to the noise level when positions
//!   are noisy). With fewer than three observations of a body its current
//!   velocity is used (eq 3.1). The history is per body id and lives in the
//!   planner ([`ExtendedAnticipation`]); a body that leaves the view is
//!   forgotten.
//! - `"probabilistic"`, eqs (3.3)-(3.5): the body's acceleration is a 2-D
//!   isotropic Gaussian around its observed acceleration (zero when the
//!   velocity source is the truth) with standard deviation `accel_sigma` per
//!   axis (scenario length per s², default 0.5: the paper gives no value).
//!   The paper's "simplified version" is used: the acceleration changes at
//!   t0 and then stays constant, so the body's centre at t0 + t is Gaussian
//!   with mean `s + v t + a t²/2` and standard deviation
//!   `sigma(t) = accel_sigma t²/2`. Eq (3.3) then reads: the probability that
//!   a point is occupied by the body is the probability of the accelerations
//!   that bring the body's disc over it, i.e. the Gaussian mass of a disc
//!   ([`disc_probability`]). Several bodies combine by the maximum, eq (3.5),
//!   not by eq (3.4)'s product. A point counts as occupied when that
//!   probability is at least `occupancy_threshold` (default 0.1; the paper
//!   gives none).
//!
//! A consequence of thresholding an occupancy probability that the paper
//! does not discuss: as `sigma(t)` grows, the occupied region first grows
//! beyond the body's disc, then shrinks and vanishes once the probability
//! is spread so thin that it is under the threshold everywhere (for
//! `sigma > R / sqrt(2 threshold)`, R the combined radius). Far in the
//! horizon a very uncertain body is therefore ignored; this is what
//! eqs (3.3)-(3.5) with a threshold give, and it is tested as such.

use std::collections::BTreeMap;

use crate::{ParamError, ParamReader, Params, Sensed, Vec2};

/// Which approach of section 3.2 predicts the bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PredictionKind {
    /// Eq (3.1), constant velocity.
    Anticipation,
    /// Eq (3.2), velocity voted from the last three.
    Extended,
    /// Eqs (3.3)-(3.5), Gaussian acceleration.
    Probabilistic,
}

/// What [`vote`] takes when the three velocities are all different.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtendedFallback {
    /// The current (latest) velocity.
    Current,
    /// The average of the three.
    Average,
}

/// Eq (3.2) with N = 3: the anticipated velocity from the current, previous
/// and oldest observed velocities.
pub fn vote(
    current: Vec2,
    previous: Vec2,
    oldest: Vec2,
    tolerance: f64,
    fallback: ExtendedFallback,
) -> Vec2 {
    let equal = |a: Vec2, b: Vec2| (a - b).norm() <= tolerance;
    // Case: two of the three are equal -> that velocity (the mean of the
    // pair, which is the velocity itself when they are exactly equal). The
    // pairs are tried newest first.
    if equal(current, previous) {
        return (current + previous) * 0.5;
    }
    if equal(current, oldest) {
        return (current + oldest) * 0.5;
    }
    if equal(previous, oldest) {
        return (previous + oldest) * 0.5;
    }
    // Case: all three different -> the current one, or the average.
    match fallback {
        ExtendedFallback::Current => current,
        ExtendedFallback::Average => (current + previous + oldest) / 3.0,
    }
}

/// Standard normal error function, Abramowitz & Stegun 7.1.26 (absolute
/// error below 1.5e-7).
fn erf(x: f64) -> f64 {
    let s = x.signum();
    let x = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    s * (1.0 - poly * (-x * x).exp())
}

/// Probability that a 2-D isotropic Gaussian point (standard deviation
/// `sigma` per axis) whose mean is at distance `d` from a point lies within
/// `r` of that point: the occupancy of eq (3.3) for a disc of radius `r`.
/// With `sigma = 0` it is 1 inside the disc and 0 outside.
///
/// Computed as the 1-D integral, along the line through the mean, of the
/// Gaussian across the line times the chord's mass
/// `erf(sqrt(r² - u²) / (sigma sqrt 2))`, over the part of the disc within
/// 8 sigma of the mean, with `u = r sin(theta)` (which removes the square
/// root's infinite slope at the rim) and Simpson's rule (error about 1e-3).
pub fn disc_probability(d: f64, r: f64, sigma: f64) -> f64 {
    if r <= 0.0 {
        return 0.0;
    }
    if sigma <= 1e-12 * r {
        return if d <= r { 1.0 } else { 0.0 };
    }
    let lo = (-r).max(d - 8.0 * sigma);
    let hi = r.min(d + 8.0 * sigma);
    if lo >= hi {
        return 0.0;
    }
    let (th_lo, th_hi) = (
        (lo / r).clamp(-1.0, 1.0).asin(),
        (hi / r).clamp(-1.0, 1.0).asin(),
    );
    const N: usize = 64;
    let h = (th_hi - th_lo) / N as f64;
    let inv = r / (sigma * (2.0 * std::f64::consts::PI).sqrt());
    let s2 = sigma * std::f64::consts::SQRT_2;
    let f = |theta: f64| {
        let (sin, cos) = theta.sin_cos();
        let chord = r * cos.max(0.0);
        let z = (r * sin - d) / sigma;
        inv * cos.max(0.0) * (-0.5 * z * z).exp() * erf(chord / s2)
    };
    let mut sum = f(th_lo) + f(th_hi);
    for i in 1..N {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(th_lo + h * i as f64);
    }
    (sum * h / 3.0).clamp(0.0, 1.0)
}

/// One body's predicted disc at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Predicted {
    /// Predicted (mean) centre.
    pub center: Vec2,
    /// Standard deviation of the centre per axis (0 = certain).
    pub sigma: f64,
    /// The body's radius.
    pub radius: f64,
}

impl Predicted {
    /// Probability that the body overlaps a disc of radius `extra` at `x`
    /// (eq 3.3; 0 or 1 when `sigma = 0`).
    pub fn occupancy(&self, x: Vec2, extra: f64) -> f64 {
        disc_probability((x - self.center).norm(), self.radius + extra, self.sigma)
    }

    /// Distance from the centre beyond which the occupancy of a disc of
    /// radius `extra` is certainly below `threshold`; `None` when it is
    /// below `threshold` everywhere. Bounds used: the Gaussian's tail
    /// `P <= exp(-(d - R)² / (2 sigma²))` and its peak density
    /// `P <= R² / (2 sigma²)`, R = radius + extra.
    pub fn reach(&self, extra: f64, threshold: f64) -> Option<f64> {
        let r = self.radius + extra;
        if self.sigma <= 1e-12 * r {
            return (r > 0.0 || threshold <= 0.0).then_some(r);
        }
        let threshold = threshold.max(1e-12);
        if r * r / (2.0 * self.sigma * self.sigma) < threshold {
            return None;
        }
        Some(r + self.sigma * (2.0 * (1.0 / threshold).ln()).max(0.0).sqrt())
    }

    /// Whether a disc of radius `extra` at `x` is occupied: occupancy at
    /// least `threshold`.
    pub fn occupied(&self, x: Vec2, extra: f64, threshold: f64) -> bool {
        let d = (x - self.center).norm();
        let r = self.radius + extra;
        if self.sigma <= 1e-12 * r {
            return d <= r;
        }
        // Quick accept: the Gaussian's mass within r - d of the mean alone.
        if d < r && 1.0 - (-(r - d) * (r - d) / (2.0 * self.sigma * self.sigma)).exp() >= threshold
        {
            return true;
        }
        match self.reach(extra, threshold) {
            Some(reach) if d <= reach => disc_probability(d, r, self.sigma) >= threshold,
            _ => false,
        }
    }
}

/// A body's predicted motion over the horizon, from the observation at t0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// Position at t0.
    pub position: Vec2,
    /// Anticipated velocity.
    pub velocity: Vec2,
    /// Mean acceleration (probabilistic prediction only; zero otherwise).
    pub acceleration: Vec2,
    /// Standard deviation of the acceleration per axis (0 = certain).
    pub accel_sigma: f64,
    /// Radius.
    pub radius: f64,
}

impl Motion {
    /// The predicted disc `t` seconds after the observation.
    pub fn at(&self, t: f64) -> Predicted {
        let half_t2 = 0.5 * t * t;
        Predicted {
            center: self.position + self.velocity * t + self.acceleration * half_t2,
            sigma: self.accel_sigma * half_t2,
            radius: self.radius,
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct VelocityHistory {
    time: f64,
    /// Newest first.
    velocities: [Vec2; 3],
    len: usize,
}

/// Eq (3.2)'s state: the last three observed velocities of every body in
/// view, keyed by body id.
#[derive(Debug, Clone)]
pub struct ExtendedAnticipation {
    /// What to take when the three velocities are all different.
    pub fallback: ExtendedFallback,
    /// Two velocities closer than this are equal.
    pub tolerance: f64,
    history: BTreeMap<u32, VelocityHistory>,
}

impl ExtendedAnticipation {
    /// No history yet.
    pub fn new(fallback: ExtendedFallback, tolerance: f64) -> Self {
        Self {
            fallback,
            tolerance,
            history: BTreeMap::new(),
        }
    }

    /// Records the velocities of `others` observed at `time`. A second call
    /// with the same time replaces that time's velocities instead of adding
    /// a sample; bodies not in `others` are forgotten.
    pub fn observe(&mut self, time: f64, others: &[Sensed]) {
        self.history
            .retain(|id, _| others.iter().any(|o| o.id == *id));
        for o in others {
            let h = self.history.entry(o.id).or_insert(VelocityHistory {
                time,
                velocities: [o.velocity; 3],
                len: 0,
            });
            if h.len > 0 && time <= h.time {
                h.velocities[0] = o.velocity;
                continue;
            }
            h.velocities = [o.velocity, h.velocities[0], h.velocities[1]];
            h.len = (h.len + 1).min(3);
            h.time = time;
        }
    }

    /// The anticipated velocity of `body` (eq 3.2), or its current velocity
    /// while fewer than three are known.
    pub fn velocity(&self, body: &Sensed) -> Vec2 {
        match self.history.get(&body.id) {
            Some(h) if h.len == 3 => {
                let [c, p, o] = h.velocities;
                vote(c, p, o, self.tolerance, self.fallback)
            }
            _ => body.velocity,
        }
    }
}

/// The prediction a planner uses, with its state and parameters.
#[derive(Debug, Clone)]
pub enum Prediction {
    /// Eq (3.1).
    Anticipation,
    /// Eq (3.2), with its per-body history.
    Extended(ExtendedAnticipation),
    /// Eqs (3.3)-(3.5).
    Probabilistic {
        /// Standard deviation of the acceleration per axis.
        accel_sigma: f64,
    },
}

/// The keys [`Prediction::read`] knows.
const PREDICTION_CHOICES: &[&str] = &["anticipation", "extended", "probabilistic"];

impl Prediction {
    /// Reads `prediction`, `accel_sigma`, `occupancy_threshold`,
    /// `extended_fallback` and `vote_tolerance`; returns the prediction and
    /// the occupancy threshold. A key that belongs to another prediction
    /// than the one chosen is refused (it would have no effect).
    pub fn read(r: &mut ParamReader, params: &Params) -> Result<(Self, f64), ParamError> {
        let kind = r.choice("prediction", PREDICTION_CHOICES, "anticipation")?;
        let accel_sigma = r.non_negative("accel_sigma", 0.5)?;
        let threshold = r.positive("occupancy_threshold", 0.1)?;
        if threshold > 1.0 {
            return Err(r.invalid(
                "occupancy_threshold",
                format!("is a probability, must be <= 1, got {threshold}"),
            ));
        }
        let fallback = match r.choice("extended_fallback", &["current", "average"], "current")? {
            "average" => ExtendedFallback::Average,
            _ => ExtendedFallback::Current,
        };
        let tolerance = r.non_negative("vote_tolerance", 1e-6)?;
        let only = |key: &'static str, wanted: &str| -> Result<(), ParamError> {
            if params.contains_key(key) && kind != wanted {
                return Err(r.invalid(
                    key,
                    format!("only applies to prediction = \"{wanted}\", not \"{kind}\""),
                ));
            }
            Ok(())
        };
        only("accel_sigma", "probabilistic")?;
        only("occupancy_threshold", "probabilistic")?;
        only("extended_fallback", "extended")?;
        only("vote_tolerance", "extended")?;
        let prediction = match kind {
            "extended" => Prediction::Extended(ExtendedAnticipation::new(fallback, tolerance)),
            "probabilistic" => Prediction::Probabilistic { accel_sigma },
            _ => Prediction::Anticipation,
        };
        Ok((prediction, threshold))
    }

    /// Which approach this is.
    pub fn kind(&self) -> PredictionKind {
        match self {
            Prediction::Anticipation => PredictionKind::Anticipation,
            Prediction::Extended(_) => PredictionKind::Extended,
            Prediction::Probabilistic { .. } => PredictionKind::Probabilistic,
        }
    }

    /// Updates the state with this tick's observation (extended only).
    pub fn observe(&mut self, time: f64, others: &[Sensed]) {
        if let Prediction::Extended(e) = self {
            e.observe(time, others);
        }
    }

    /// `body`'s predicted motion from now on.
    pub fn motion(&self, body: &Sensed) -> Motion {
        let (velocity, acceleration, accel_sigma) = match self {
            // Eq (3.1): constant velocity.
            Prediction::Anticipation => (body.velocity, Vec2::zeros(), 0.0),
            // Eq (3.2): constant anticipated velocity.
            Prediction::Extended(e) => (e.velocity(body), Vec2::zeros(), 0.0),
            // Eq (3.3), simplified version: Gaussian acceleration held
            // from t0.
            Prediction::Probabilistic { accel_sigma } => {
                (body.velocity, body.acceleration, *accel_sigma)
            }
        };
        Motion {
            position: body.position,
            velocity,
            acceleration,
            accel_sigma,
            radius: body.radius,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ParamValue;
    use crate::testkit::obstacle;

    fn body(id: u32, position: Vec2, velocity: Vec2) -> Sensed {
        obstacle(id, position, velocity, 0.5)
    }

    fn v(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    #[test]
    fn anticipation_moves_the_body_at_constant_velocity() {
        let p = Prediction::Anticipation;
        let m = p.motion(&body(1, v(1.0, 2.0), v(3.0, -1.0)));
        let at = m.at(2.0);
        assert!((at.center - v(7.0, 0.0)).norm() < 1e-12);
        assert_eq!(at.sigma, 0.0);
        assert!(at.occupied(v(7.4, 0.0), 0.0, 0.1));
        assert!(!at.occupied(v(7.6, 0.0), 0.0, 0.1));
    }

    #[test]
    fn vote_takes_two_equal_velocities_whichever_pair() {
        let a = v(1.0, 0.0);
        let b = v(0.0, 1.0);
        let c = v(-1.0, -1.0);
        let cur = ExtendedFallback::Current;
        assert_eq!(vote(a, a, b, 1e-9, cur), a);
        assert_eq!(vote(a, b, a, 1e-9, cur), a);
        assert_eq!(vote(b, a, a, 1e-9, cur), a);
        assert_eq!(vote(c, c, c, 1e-9, cur), c);
    }

    #[test]
    fn vote_falls_back_to_current_or_average_when_all_differ() {
        let a = v(3.0, 0.0);
        let b = v(0.0, 3.0);
        let c = v(0.0, 0.0);
        assert_eq!(vote(a, b, c, 1e-9, ExtendedFallback::Current), a);
        assert!((vote(a, b, c, 1e-9, ExtendedFallback::Average) - v(1.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn vote_tolerance_decides_what_is_equal() {
        let a = v(1.0, 0.0);
        let a2 = v(1.0, 0.01);
        let b = v(5.0, 0.0);
        assert_eq!(vote(b, a, a2, 1e-3, ExtendedFallback::Current), b);
        let voted = vote(b, a, a2, 0.05, ExtendedFallback::Current);
        assert!((voted - v(1.0, 0.005)).norm() < 1e-12);
    }

    #[test]
    fn extended_prediction_ignores_a_one_tick_velocity_blip() {
        let mut e =
            Prediction::Extended(ExtendedAnticipation::new(ExtendedFallback::Current, 1e-6));
        let steady = v(1.0, 0.0);
        let blip = v(-4.0, 2.0);
        e.observe(0.0, &[body(3, v(0.0, 0.0), steady)]);
        // Fewer than three samples: the current velocity.
        assert_eq!(e.motion(&body(3, v(0.0, 0.0), steady)).velocity, steady);
        e.observe(0.1, &[body(3, v(0.1, 0.0), steady)]);
        let now = body(3, v(0.2, 0.0), blip);
        e.observe(0.2, &[now]);
        // Two of the last three equal: the blip is voted down.
        assert_eq!(e.motion(&now).velocity, steady);
        // Observing again at the same time replaces, does not add.
        e.observe(0.2, &[now]);
        assert_eq!(e.motion(&now).velocity, steady);
        // A body out of view is forgotten.
        e.observe(0.3, &[]);
        assert_eq!(e.motion(&now).velocity, blip);
    }

    #[test]
    fn disc_probability_at_the_centre_is_the_rayleigh_law() {
        for &(r, s) in &[(0.5f64, 0.1f64), (0.5, 0.5), (0.5, 2.0), (3.0, 0.2)] {
            let exact = 1.0 - (-(r * r) / (2.0 * s * s)).exp();
            let p = disc_probability(0.0, r, s);
            assert!((p - exact).abs() < 1e-3, "r {r} s {s}: {p} vs {exact}");
        }
    }

    #[test]
    fn disc_probability_tends_to_the_disc_as_sigma_vanishes() {
        assert!(disc_probability(0.9, 1.0, 1e-3) > 0.999);
        assert!(disc_probability(1.1, 1.0, 1e-3) < 1e-6);
        // On the boundary, half the mass is inside.
        assert!((disc_probability(1.0, 1.0, 1e-3) - 0.5).abs() < 0.01);
        assert_eq!(disc_probability(1.0, 1.0, 0.0), 1.0);
    }

    #[test]
    fn probabilistic_mean_follows_the_observed_acceleration_and_spreads_as_t_squared() {
        let p = Prediction::Probabilistic { accel_sigma: 2.0 };
        let mut b = body(1, v(0.0, 0.0), v(1.0, 0.0));
        b.acceleration = v(0.0, 2.0);
        let at = p.motion(&b).at(1.0);
        assert!((at.center - v(1.0, 1.0)).norm() < 1e-12);
        assert!((at.sigma - 1.0).abs() < 1e-12);
        assert!((p.motion(&b).at(2.0).sigma - 4.0).abs() < 1e-12);
    }

    #[test]
    fn probabilistic_occupancy_first_spreads_then_fades_below_the_threshold() {
        let p = Prediction::Probabilistic { accel_sigma: 1.0 };
        let m = p.motion(&body(1, v(0.0, 0.0), v(0.0, 0.0)));
        let thr = 0.1;
        // Just outside the disc: free when certain, occupied once uncertain.
        let x = v(0.6, 0.0);
        assert!(!m.at(0.0).occupied(x, 0.0, thr));
        assert!(m.at(0.8).occupied(x, 0.0, thr));
        // Much later the mass is spread thin: under the threshold everywhere.
        let late = m.at(3.0);
        assert!(late.reach(0.0, thr).is_none());
        assert!(!late.occupied(v(0.0, 0.0), 0.0, thr));
    }

    #[test]
    fn reach_bounds_where_occupancy_can_reach_the_threshold() {
        let pr = Predicted {
            center: v(0.0, 0.0),
            sigma: 0.3,
            radius: 0.5,
        };
        let reach = pr.reach(0.2, 0.1).unwrap();
        let beyond = disc_probability(reach + 1e-6, 0.7, 0.3);
        assert!(beyond < 0.1, "{beyond}");
    }

    #[test]
    fn keys_of_another_prediction_are_refused() {
        let mut params = Params::new();
        params.insert("accel_sigma".into(), ParamValue::Number(1.0));
        let mut r = ParamReader::new("t", &params);
        assert!(Prediction::read(&mut r, &params).is_err());
        params.insert(
            "prediction".into(),
            ParamValue::Text("probabilistic".into()),
        );
        let mut r = ParamReader::new("t", &params);
        let (p, thr) = Prediction::read(&mut r, &params).unwrap();
        assert_eq!(p.kind(), PredictionKind::Probabilistic);
        assert_eq!(thr, 0.1);
        r.finish().unwrap();
    }
}
