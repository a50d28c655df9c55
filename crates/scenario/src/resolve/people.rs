//! `[[person]]` tables: a person's route (a `goal`, or `waypoints` and
//! `cyclic`), its disc and speed, whether it sees robots, its behaviour,
//! its group and its crowd model (`motion`), with their defaults.

use crate::checks::{Rule, check, opt, point, points};
use crate::error::Fail;
use crate::raw::{RawBehavior, RawBehaviorTable, RawPerson, RawPersonMotion, S};
use crate::types::*;
use std::ops::Range;

const MODELS: &str = "orca | social-force";
const BEHAVIORS: &str = "regular | impassive | surprised | scared | curious | threatening";

/// A person's radius when the file gives none (CrowdNav's humans).
pub(crate) const PERSON_RADIUS: f64 = 0.3;
/// A person's preferred speed when the file gives none, m/s (CrowdNav's
/// humans).
pub(crate) const PERSON_SPEED: f64 = 1.0;

fn resolve_motion(m: &S<RawPersonMotion>, what: &str) -> Result<PersonMotion, Fail> {
    let raw = m.get_ref();
    let Some(model) = &raw.model else {
        return Err(Fail::new(
            Some(m.span()),
            what,
            format!("motion needs a `model`: {MODELS}"),
        ));
    };
    let allowed: &[&str] = match model.get_ref().as_str() {
        "orca" => &[
            "neighbor_dist",
            "max_neighbors",
            "time_horizon",
            "time_horizon_obst",
            "radius_margin",
        ],
        "social-force" => &[
            "relaxation_time",
            "force_desired",
            "force_social",
            "force_obstacle",
            "sigma_obstacle",
            "force_group_gaze",
            "force_group_coherence",
            "force_group_repulsion",
            "group_overlap",
            "robot_scale",
            "neighbor_dist",
        ],
        other => {
            return Err(Fail::new(
                Some(model.span()),
                what,
                format!("unknown crowd model `{other}`; expected {MODELS}"),
            ));
        }
    };
    super::obstacles::only_keys_of(present(raw), allowed, "crowd model", model, what)?;
    if model.get_ref() == "social-force" {
        let d = SocialForceParams::default();
        let f = |v: &Option<S<f64>>, key: &str, rule: Rule, default: f64| {
            opt(v, key, rule, what, default)
        };
        return Ok(PersonMotion::SocialForce(SocialForceParams {
            relaxation_time: f(
                &raw.relaxation_time,
                "relaxation_time",
                Rule::Pos,
                d.relaxation_time,
            )?,
            force_desired: f(
                &raw.force_desired,
                "force_desired",
                Rule::NonNeg,
                d.force_desired,
            )?,
            force_social: f(
                &raw.force_social,
                "force_social",
                Rule::NonNeg,
                d.force_social,
            )?,
            force_obstacle: f(
                &raw.force_obstacle,
                "force_obstacle",
                Rule::NonNeg,
                d.force_obstacle,
            )?,
            sigma_obstacle: f(
                &raw.sigma_obstacle,
                "sigma_obstacle",
                Rule::Pos,
                d.sigma_obstacle,
            )?,
            force_group_gaze: f(
                &raw.force_group_gaze,
                "force_group_gaze",
                Rule::NonNeg,
                d.force_group_gaze,
            )?,
            force_group_coherence: f(
                &raw.force_group_coherence,
                "force_group_coherence",
                Rule::NonNeg,
                d.force_group_coherence,
            )?,
            force_group_repulsion: f(
                &raw.force_group_repulsion,
                "force_group_repulsion",
                Rule::NonNeg,
                d.force_group_repulsion,
            )?,
            group_overlap: f(
                &raw.group_overlap,
                "group_overlap",
                Rule::NonNeg,
                d.group_overlap,
            )?,
            robot_scale: f(&raw.robot_scale, "robot_scale", Rule::Pos, d.robot_scale)?,
            neighbor_dist: f(
                &raw.neighbor_dist,
                "neighbor_dist",
                Rule::NonNeg,
                d.neighbor_dist,
            )?,
        }));
    }
    let (neighbor_dist, max_neighbors, time_horizon, time_horizon_obst, radius_margin) =
        (10.0, 10, 5.0, 5.0, 0.0);
    let max_neighbors = match &raw.max_neighbors {
        Some(v) if *v.get_ref() < 0 => {
            return Err(Fail::new(
                Some(v.span()),
                what,
                format!("max_neighbors must be >= 0, got {}", v.get_ref()),
            ));
        }
        Some(v) => *v.get_ref() as usize,
        None => max_neighbors,
    };
    Ok(PersonMotion::Orca {
        neighbor_dist: opt(
            &raw.neighbor_dist,
            "neighbor_dist",
            Rule::NonNeg,
            what,
            neighbor_dist,
        )?,
        max_neighbors,
        time_horizon: opt(
            &raw.time_horizon,
            "time_horizon",
            Rule::Pos,
            what,
            time_horizon,
        )?,
        time_horizon_obst: opt(
            &raw.time_horizon_obst,
            "time_horizon_obst",
            Rule::Pos,
            what,
            time_horizon_obst,
        )?,
        radius_margin: opt(
            &raw.radius_margin,
            "radius_margin",
            Rule::NonNeg,
            what,
            radius_margin,
        )?,
    })
}

/// The keys a motion table has, with their spans.
fn present(m: &RawPersonMotion) -> Vec<(&'static str, Range<usize>)> {
    fn s<T>(v: &Option<S<T>>) -> Option<Range<usize>> {
        v.as_ref().map(|v| v.span())
    }
    [
        ("neighbor_dist", s(&m.neighbor_dist)),
        ("max_neighbors", s(&m.max_neighbors)),
        ("time_horizon", s(&m.time_horizon)),
        ("time_horizon_obst", s(&m.time_horizon_obst)),
        ("radius_margin", s(&m.radius_margin)),
        ("relaxation_time", s(&m.relaxation_time)),
        ("force_desired", s(&m.force_desired)),
        ("force_social", s(&m.force_social)),
        ("force_obstacle", s(&m.force_obstacle)),
        ("sigma_obstacle", s(&m.sigma_obstacle)),
        ("force_group_gaze", s(&m.force_group_gaze)),
        ("force_group_coherence", s(&m.force_group_coherence)),
        ("force_group_repulsion", s(&m.force_group_repulsion)),
        ("group_overlap", s(&m.group_overlap)),
        ("robot_scale", s(&m.robot_scale)),
    ]
    .into_iter()
    .filter_map(|(k, v)| v.map(|v| (k, v)))
    .collect()
}

/// The keys a behaviour table has, with their spans.
fn behavior_keys(t: &RawBehaviorTable) -> Vec<(&'static str, Range<usize>)> {
    fn s<T>(v: &Option<S<T>>) -> Option<Range<usize>> {
        v.as_ref().map(|v| v.span())
    }
    [
        ("detect_dist", s(&t.detect_dist)),
        ("duration", s(&t.duration)),
        ("once", s(&t.once)),
        ("vel", s(&t.vel)),
        ("other_force_factor", s(&t.other_force_factor)),
        ("stop_dist", s(&t.stop_dist)),
        ("front_dist", s(&t.front_dist)),
    ]
    .into_iter()
    .filter_map(|(k, v)| v.map(|v| (k, v)))
    .collect()
}

/// A person's behaviour from `v`, HuNavSim's defaults for the keys left
/// out (`hunav_loader.cpp`'s default configuration; the curious speed is
/// the person's `preferred_speed`, its `max_vel`).
fn behavior(v: &S<RawBehavior>, preferred_speed: f64, what: &str) -> Result<Behavior, Fail> {
    let empty = RawBehaviorTable::default();
    let (kind, kind_span, t) = match v.get_ref() {
        RawBehavior::Name(n) => (n.as_str(), v.span(), &empty),
        RawBehavior::Table(t) => match &t.kind {
            Some(k) => (k.get_ref().as_str(), k.span(), &**t),
            None => {
                return Err(Fail::new(
                    Some(v.span()),
                    what,
                    format!("behavior needs a `kind`: {BEHAVIORS}"),
                ));
            }
        },
    };
    let allowed: &[&str] = match kind {
        "regular" | "impassive" => &[],
        "surprised" => &["detect_dist", "duration", "once"],
        "scared" => &[
            "detect_dist",
            "duration",
            "once",
            "vel",
            "other_force_factor",
        ],
        "curious" => &["detect_dist", "duration", "once", "vel", "stop_dist"],
        "threatening" => &["detect_dist", "duration", "once", "vel", "front_dist"],
        other => {
            return Err(Fail::new(
                Some(kind_span),
                what,
                format!("unknown behavior `{other}`; expected {BEHAVIORS}"),
            ));
        }
    };
    for (key, span) in behavior_keys(t) {
        if !allowed.contains(&key) {
            let takes = if allowed.is_empty() {
                "no keys".to_string()
            } else {
                allowed.join(", ")
            };
            return Err(Fail::new(
                Some(span),
                what,
                format!("`{key}` does not apply to behavior `{kind}` (it takes: {takes})"),
            ));
        }
    }
    let f =
        |v: &Option<S<f64>>, key: &str, rule: Rule, default: f64| opt(v, key, rule, what, default);
    // HuNavSim's detection distances: the trees' `IsRobotVisible` (curious
    // 10, threatening 4) or `behavior.dist` (surprised 4, scared 3).
    let reaction = |detect: f64, duration: f64| -> Result<Reaction, Fail> {
        Ok(Reaction {
            detect_dist: f(&t.detect_dist, "detect_dist", Rule::NonNeg, detect)?,
            duration: f(&t.duration, "duration", Rule::NonNeg, duration)?,
            once: t.once.as_ref().is_none_or(|o| *o.get_ref()),
        })
    };
    Ok(match kind {
        "regular" => Behavior::Regular,
        "impassive" => Behavior::Impassive,
        "surprised" => Behavior::Surprised(reaction(4.0, 30.0)?),
        "scared" => Behavior::Scared {
            reaction: reaction(3.0, 40.0)?,
            vel: f(&t.vel, "vel", Rule::Pos, 0.6)?,
            other_force_factor: f(
                &t.other_force_factor,
                "other_force_factor",
                Rule::NonNeg,
                20.0,
            )?,
        },
        "curious" => Behavior::Curious {
            reaction: reaction(10.0, 40.0)?,
            vel: f(&t.vel, "vel", Rule::Pos, preferred_speed)?,
            stop_dist: f(&t.stop_dist, "stop_dist", Rule::NonNeg, 1.5)?,
        },
        _ => Behavior::Threatening {
            reaction: reaction(4.0, 40.0)?,
            vel: f(&t.vel, "vel", Rule::Pos, 2.0)?,
            front_dist: f(&t.front_dist, "front_dist", Rule::NonNeg, 1.4)?,
        },
    })
}

/// A person from its table `raw` (spanning `table`), the `index`th
/// `[[person]]`.
pub(super) fn resolve_person(
    raw: &RawPerson,
    table: Range<usize>,
    index: usize,
) -> Result<PersonSpec, Fail> {
    let anon = format!("person #{}", index + 1);
    let Some(name) = &raw.name else {
        return Err(Fail::new(Some(table), anon, "missing `name`"));
    };
    if name.get_ref().trim().is_empty() {
        return Err(Fail::new(Some(name.span()), anon, "name must not be empty"));
    }
    let what = format!("person `{}`", name.get_ref());
    let Some(start) = &raw.start else {
        return Err(Fail::new(Some(table), what, "missing `start`"));
    };
    let waypoints = match (&raw.goal, &raw.waypoints) {
        (Some(g), None) => vec![point(g, "goal", &what)?],
        (None, Some(w)) => {
            let pts = points(w, "waypoints", &what)?;
            if pts.is_empty() {
                return Err(Fail::new(
                    Some(w.span()),
                    what,
                    "waypoints needs at least one point",
                ));
            }
            pts
        }
        (Some(g), Some(_)) => {
            return Err(Fail::new(
                Some(g.span()),
                what,
                "give a `goal` or `waypoints`, not both",
            ));
        }
        (None, None) => {
            return Err(Fail::new(
                Some(table),
                what,
                "missing `goal` (or `waypoints`)",
            ));
        }
    };
    let cyclic = match &raw.cyclic {
        Some(c) if *c.get_ref() && raw.waypoints.is_none() => {
            return Err(Fail::new(
                Some(c.span()),
                what,
                "cyclic applies to `waypoints`: a single goal has nothing to cycle",
            ));
        }
        Some(c) => *c.get_ref(),
        None => false,
    };
    let radius = match &raw.radius {
        Some(r) => check(r, "radius", Rule::Pos, &what)?,
        None => PERSON_RADIUS,
    };
    let preferred_speed = match &raw.preferred_speed {
        Some(v) => check(v, "preferred_speed", Rule::Pos, &what)?,
        None => PERSON_SPEED,
    };
    let group = match &raw.group {
        Some(g) if g.get_ref().trim().is_empty() => {
            return Err(Fail::new(
                Some(g.span()),
                what,
                "group must not be empty (leave it out for a person alone)",
            ));
        }
        Some(g) => Some(g.get_ref().clone()),
        None => None,
    };
    Ok(PersonSpec {
        name: name.get_ref().clone(),
        start: point(start, "start", &what)?,
        waypoints,
        cyclic,
        radius,
        preferred_speed,
        sees_robots: raw.sees_robots.as_ref().is_none_or(|v| *v.get_ref()),
        behavior: match &raw.behavior {
            Some(b) => behavior(b, preferred_speed, &what)?,
            None => Behavior::Regular,
        },
        group,
        motion: match &raw.motion {
            Some(m) => resolve_motion(m, &what)?,
            None => PersonMotion::default(),
        },
    })
}
