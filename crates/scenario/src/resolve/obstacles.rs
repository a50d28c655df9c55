//! `[[obstacle]]` tables and their motion models (static, constant-velocity,
//! waypoints, random, intentional): which keys each model takes, which it
//! needs, and their defaults.

use crate::checks::{Rule, builtin, check, opt, point, points, shape};
use crate::error::Fail;
use crate::raw::{RawMotion, RawObstacle, S};
use crate::types::*;
use std::ops::Range;

const MODELS: &str = "static | constant-velocity | waypoints | random | intentional";

fn resolve_motion(m: &S<RawMotion>, what: &str) -> Result<Motion, Fail> {
    let raw = m.get_ref();
    let Some(model) = &raw.model else {
        return Err(Fail::new(
            Some(m.span()),
            what,
            format!("motion needs a `model`: {MODELS}"),
        ));
    };
    let allowed: &[&str] = match model.get_ref().as_str() {
        "static" => &[],
        "constant-velocity" => &["velocity"],
        "waypoints" => &["points", "speed", "loop"],
        "random" => &[
            "distribution",
            "accel_sigma",
            "alpha1",
            "beta1",
            "max_speed",
        ],
        "intentional" => &[
            "behavior",
            "target",
            "goal",
            "points",
            "max_speed",
            "max_accel",
            "alpha2",
            "beta2",
        ],
        other => {
            return Err(Fail::new(
                Some(model.span()),
                what,
                format!("unknown motion model `{other}`; expected {MODELS}"),
            ));
        }
    };
    only_keys_of(present(raw), allowed, "motion model", model, what)?;
    let need = |key: &str| {
        Fail::new(
            Some(m.span()),
            what,
            format!("motion model `{}` needs `{key}`", model.get_ref()),
        )
    };
    let req = |v: &Option<S<f64>>, key: &str, rule: Rule| match v {
        Some(v) => check(v, key, rule, what),
        None => Err(need(key)),
    };
    Ok(match model.get_ref().as_str() {
        "static" => Motion::Static,
        "constant-velocity" => Motion::ConstantVelocity {
            velocity: point(
                raw.velocity.as_ref().ok_or_else(|| need("velocity"))?,
                "velocity",
                what,
            )?,
        },
        "waypoints" => {
            let pts = raw.points.as_ref().ok_or_else(|| need("points"))?;
            let points = points(pts, "points", what)?;
            if points.is_empty() {
                return Err(Fail::new(
                    Some(pts.span()),
                    what,
                    "waypoints needs at least one point",
                ));
            }
            Motion::Waypoints {
                points,
                speed: req(&raw.speed, "speed", Rule::Pos)?,
                r#loop: raw.looped.as_ref().is_some_and(|l| *l.get_ref()),
            }
        }
        "random" => {
            let distribution = match &raw.distribution {
                Some(d) if d.get_ref() == "gaussian" || d.get_ref() == "uniform" => {
                    d.get_ref().clone()
                }
                Some(d) => {
                    return Err(Fail::new(
                        Some(d.span()),
                        what,
                        format!(
                            "unknown distribution `{}`; expected gaussian | uniform",
                            d.get_ref()
                        ),
                    ));
                }
                None => "gaussian".to_string(),
            };
            Motion::Random {
                distribution,
                accel_sigma: req(&raw.accel_sigma, "accel_sigma", Rule::NonNeg)?,
                alpha1: opt(&raw.alpha1, "alpha1", Rule::Finite, what, 0.0)?,
                beta1: opt(&raw.beta1, "beta1", Rule::Finite, what, 1.0)?,
                max_speed: req(&raw.max_speed, "max_speed", Rule::Pos)?,
            }
        }
        _ => {
            let Some(behavior) = &raw.behavior else {
                return Err(need("behavior"));
            };
            let b = behavior.get_ref().as_str();
            match b {
                "pursue" | "avoid" => {
                    // `avoid` without a target keeps away from every other body.
                    if b == "pursue" && raw.target.is_none() {
                        return Err(need("target"));
                    }
                    for (key, v) in [
                        ("goal", raw.goal.as_ref().map(|g| g.span())),
                        ("points", raw.points.as_ref().map(|p| p.span())),
                    ] {
                        if let Some(span) = v {
                            return Err(Fail::new(
                                Some(span),
                                what,
                                format!("`{key}` applies to behavior `goal`, not `{b}`"),
                            ));
                        }
                    }
                }
                "goal" => {
                    if raw.goal.is_none() && raw.points.is_none() {
                        return Err(need("goal` or `points"));
                    }
                    if let Some(t) = &raw.target {
                        return Err(Fail::new(
                            Some(t.span()),
                            what,
                            "`target` applies to behavior `pursue` or `avoid`, not `goal`",
                        ));
                    }
                }
                other => {
                    return Err(Fail::new(
                        Some(behavior.span()),
                        what,
                        format!("unknown behavior `{other}`; expected pursue | avoid | goal"),
                    ));
                }
            }
            Motion::Intentional {
                behavior: b.to_string(),
                target: raw.target.as_ref().map(|t| t.get_ref().clone()),
                goal: raw
                    .goal
                    .as_ref()
                    .map(|g| point(g, "goal", what))
                    .transpose()?,
                points: raw
                    .points
                    .as_ref()
                    .map_or(Ok(Vec::new()), |p| points(p, "points", what))?,
                max_speed: req(&raw.max_speed, "max_speed", Rule::Pos)?,
                max_accel: req(&raw.max_accel, "max_accel", Rule::Pos)?,
                alpha2: opt(&raw.alpha2, "alpha2", Rule::Finite, what, 0.5)?,
                beta2: opt(&raw.beta2, "beta2", Rule::Finite, what, 0.5)?,
            }
        }
    })
}

/// The keys a motion table has, with their spans.
/// Refuses the first of `present` (keys written, with their spans) that
/// `allowed`, the keys of `model` (a `kind` such as "motion model"), does
/// not take.
pub(super) fn only_keys_of(
    present: Vec<(&'static str, Range<usize>)>,
    allowed: &[&str],
    kind: &str,
    model: &S<String>,
    what: &str,
) -> Result<(), Fail> {
    match present.into_iter().find(|(key, _)| !allowed.contains(key)) {
        None => Ok(()),
        Some((key, span)) => Err(Fail::new(
            Some(span),
            what,
            format!(
                "`{key}` does not apply to {kind} `{}` (it takes: {})",
                model.get_ref(),
                if allowed.is_empty() {
                    "nothing".to_string()
                } else {
                    allowed.join(", ")
                }
            ),
        )),
    }
}

fn present(m: &RawMotion) -> Vec<(&'static str, Range<usize>)> {
    fn s<T>(v: &Option<S<T>>) -> Option<Range<usize>> {
        v.as_ref().map(|v| v.span())
    }
    [
        ("velocity", s(&m.velocity)),
        ("points", s(&m.points)),
        ("speed", s(&m.speed)),
        ("loop", s(&m.looped)),
        ("distribution", s(&m.distribution)),
        ("accel_sigma", s(&m.accel_sigma)),
        ("alpha1", s(&m.alpha1)),
        ("beta1", s(&m.beta1)),
        ("max_speed", s(&m.max_speed)),
        ("behavior", s(&m.behavior)),
        ("target", s(&m.target)),
        ("goal", s(&m.goal)),
        ("max_accel", s(&m.max_accel)),
        ("alpha2", s(&m.alpha2)),
        ("beta2", s(&m.beta2)),
    ]
    .into_iter()
    .filter_map(|(k, v)| v.map(|v| (k, v)))
    .collect()
}

pub(super) fn resolve_obstacle(o: &S<RawObstacle>, index: usize) -> Result<ObstacleSpec, Fail> {
    let raw = o.get_ref();
    let anon = format!("obstacle #{}", index + 1);
    let Some(name) = &raw.name else {
        return Err(Fail::new(Some(o.span()), anon, "missing `name`"));
    };
    if name.get_ref().trim().is_empty() {
        return Err(Fail::new(Some(name.span()), anon, "name must not be empty"));
    }
    let what = format!("obstacle `{}`", name.get_ref());
    let Some(start) = &raw.start else {
        return Err(Fail::new(Some(o.span()), what, "missing `start`"));
    };
    let radius = opt(
        &raw.radius,
        "radius",
        Rule::NonNeg,
        &what,
        builtin::OBSTACLE_RADIUS,
    )?;
    let body = match &raw.shape {
        Some(v) => shape(v, &what)?,
        None => ShapeSpec::Disc,
    };
    let radius = match (&body, &raw.radius) {
        (ShapeSpec::Disc, _) => radius,
        (_, Some(r)) => {
            return Err(Fail::new(
                Some(r.span()),
                what,
                "radius is the size of a disc; a rectangle or polygon is sized by its own \
                 keys (its circumscribed radius is computed): leave radius out",
            ));
        }
        (_, None) => body.shape(radius).circumradius(),
    };
    let heading = opt(&raw.heading_deg, "heading_deg", Rule::Finite, &what, 0.0)?.to_radians();
    Ok(ObstacleSpec {
        name: name.get_ref().clone(),
        start: point(start, "start", &what)?,
        radius,
        shape: body,
        heading,
        motion: match &raw.motion {
            Some(m) => resolve_motion(m, &what)?,
            None => Motion::Static,
        },
    })
}
