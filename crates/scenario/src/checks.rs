//! The checks every part of resolving shares: the built-in robot defaults,
//! number and point checks that point their errors at the offending value,
//! and the TOML error conversion. A leaf beside `resolve` and `generate`,
//! which both use it: it uses neither.

use crate::error::Fail;
use crate::raw::{P, Pt, RawShape, S};
use crate::types::ShapeSpec;

/// Built-in robot defaults (metres).
pub(crate) mod builtin {
    pub const RADIUS: f64 = 0.25;
    pub const MASS: f64 = 1.0;
    pub const DAMPING: f64 = 0.5;
    pub const MAX_SPEED: f64 = 1.0;
    pub const MAX_ACCEL: f64 = 2.0;
    pub const VELOCITY_LAG: f64 = 0.0;
    pub const SENSING_RANGE: f64 = 1e9;
    pub const FIELD_OF_VIEW_DEG: f64 = 360.0;
    pub const GOAL_TOLERANCE: f64 = 0.1;
    pub const GOAL_HOLD_TICKS: u32 = 3;
    pub const POSITION_NOISE: f64 = 0.0;
    pub const PLANNER: &str = "homing";
    pub const OBSTACLE_RADIUS: f64 = 0.25;
}

/// A check on a number.
#[derive(Clone, Copy)]
pub(crate) enum Rule {
    /// Any finite number.
    Finite,
    /// >= 0.
    NonNeg,
    /// > 0.
    Pos,
    /// In (0, 1].
    Fraction,
    /// In (0, 360].
    Degrees,
    /// In (0, 90), exclusive (a steering angle).
    Acute,
    /// In (0, 180] (a tolerance on a heading).
    HalfTurn,
}

/// Checks a number; the error points at it.
pub(crate) fn check(v: &S<f64>, key: &str, rule: Rule, what: &str) -> Result<f64, Fail> {
    let x = *v.get_ref();
    let bad = |reason: String| Err(Fail::new(Some(v.span()), what, reason));
    if !x.is_finite() {
        return bad(format!("{key} must be a finite number, got {x}"));
    }
    match rule {
        Rule::Finite => Ok(x),
        Rule::NonNeg if x < 0.0 => bad(format!("{key} must be >= 0, got {x}")),
        Rule::Pos if x <= 0.0 => bad(format!("{key} must be > 0, got {x}")),
        Rule::Fraction if !(x > 0.0 && x <= 1.0) => {
            bad(format!("{key} must be in (0, 1], got {x}"))
        }
        Rule::Degrees if !(x > 0.0 && x <= 360.0) => {
            bad(format!("{key} must be in (0, 360], got {x}"))
        }
        Rule::Acute if !(x > 0.0 && x < 90.0) => {
            bad(format!("{key} must be in (0, 90) degrees, got {x}"))
        }
        Rule::HalfTurn if !(x > 0.0 && x <= 180.0) => {
            bad(format!("{key} must be in (0, 180] degrees, got {x}"))
        }
        _ => Ok(x),
    }
}

pub(crate) fn opt(
    v: &Option<S<f64>>,
    key: &str,
    rule: Rule,
    what: &str,
    default: f64,
) -> Result<f64, Fail> {
    v.as_ref()
        .map_or(Ok(default), |v| check(v, key, rule, what))
}

/// Checks that a point is finite.
pub(crate) fn point(v: &S<Pt>, key: &str, what: &str) -> Result<P, Fail> {
    let p = v.get_ref().0;
    if p.iter().all(|x| x.is_finite()) {
        Ok(p)
    } else {
        Err(Fail::new(
            Some(v.span()),
            what,
            format!("{key} must be finite numbers, got [{}, {}]", p[0], p[1]),
        ))
    }
}

pub(crate) fn points(v: &S<Vec<Pt>>, key: &str, what: &str) -> Result<Vec<P>, Fail> {
    for Pt(p) in v.get_ref() {
        if !p.iter().all(|x| x.is_finite()) {
            return Err(Fail::new(
                Some(v.span()),
                what,
                format!("{key} must be finite numbers, got [{}, {}]", p[0], p[1]),
            ));
        }
    }
    Ok(v.get_ref().iter().map(|p| p.0).collect())
}

/// Turns a TOML deserialization error into a `Fail`.
pub(crate) fn de_fail(e: toml::de::Error, what: &str) -> Fail {
    Fail::new(e.span(), what, e.message().to_string())
}

/// A `shape` table: `kind` disc (no other key), rectangle (`length`,
/// `width`, both > 0) or polygon (`points`, convex, counter-clockwise, 3 to
/// [`mrsim_shape::MAX_VERTICES`]); the error points at the key at fault.
pub(crate) fn shape(v: &S<RawShape>, what: &str) -> Result<ShapeSpec, Fail> {
    const KINDS: &str = "disc | rectangle | polygon";
    let raw = v.get_ref();
    let Some(kind) = &raw.kind else {
        return Err(Fail::new(
            Some(v.span()),
            what,
            format!("shape needs a `kind`: {KINDS}"),
        ));
    };
    let allowed: &[&str] = match kind.get_ref().as_str() {
        "disc" => &[],
        "rectangle" => &["length", "width"],
        "polygon" => &["points"],
        other => {
            return Err(Fail::new(
                Some(kind.span()),
                what,
                format!("unknown shape kind `{other}`; expected {KINDS}"),
            ));
        }
    };
    let present = [
        ("length", raw.length.as_ref().map(|x| x.span())),
        ("width", raw.width.as_ref().map(|x| x.span())),
        ("points", raw.points.as_ref().map(|x| x.span())),
    ];
    for (key, span) in present {
        if let Some(span) = span
            && !allowed.contains(&key)
        {
            let takes = if allowed.is_empty() {
                "nothing: its size is the body's `radius`".to_string()
            } else {
                allowed.join(", ")
            };
            return Err(Fail::new(
                Some(span),
                what,
                format!(
                    "`{key}` does not apply to shape kind `{}` (it takes {takes})",
                    kind.get_ref()
                ),
            ));
        }
    }
    let need = |key: &str| {
        Fail::new(
            Some(v.span()),
            what,
            format!("shape kind `{}` needs `{key}`", kind.get_ref()),
        )
    };
    Ok(match kind.get_ref().as_str() {
        "rectangle" => {
            let length = raw.length.as_ref().ok_or_else(|| need("length"))?;
            let width = raw.width.as_ref().ok_or_else(|| need("width"))?;
            ShapeSpec::Rectangle {
                length: check(length, "shape length", Rule::Pos, what)?,
                width: check(width, "shape width", Rule::Pos, what)?,
            }
        }
        "polygon" => {
            let p = raw.points.as_ref().ok_or_else(|| need("points"))?;
            let pts = points(p, "shape points", what)?;
            mrsim_shape::Polygon::new(&pts)
                .map_err(|e| Fail::new(Some(p.span()), what, format!("shape points: {e}")))?;
            ShapeSpec::Polygon { points: pts }
        }
        _ => ShapeSpec::Disc,
    })
}
