//! From the file as written (`raw`) to the resolved `Scenario`: built-in
//! defaults, `[defaults]`, each robot's own keys, `[generate]` and the
//! overrides, in that order of precedence; then every check.

use crate::error::{Fail, Spans};
use crate::generate;
use crate::overrides::{RobotPatch, set_path};
use crate::raw::{P, Pt, RawDoc, RawMotion, RawObstacle, RawParams, RawRobot, RawWorld, S};
use crate::types::*;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

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
        _ => Ok(x),
    }
}

fn opt(v: &Option<S<f64>>, key: &str, rule: Rule, what: &str, default: f64) -> Result<f64, Fail> {
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

fn points(v: &S<Vec<Pt>>, key: &str, what: &str) -> Result<Vec<P>, Fail> {
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

/// One layer of robot settings, highest precedence first.
struct Layer<'a> {
    raw: &'a RawRobot,
    what: String,
}

/// Where a robot's errors point.
#[derive(Debug, Clone)]
pub(crate) struct RobotSpans {
    pub table: Option<Range<usize>>,
    pub start: Option<Range<usize>>,
    pub goal: Option<Range<usize>>,
}

/// Picks a field from the first layer that has it, checking it in every
/// layer that has it.
fn pick_num(
    layers: &[Layer],
    f: impl Fn(&RawRobot) -> &Option<S<f64>>,
    key: &str,
    rule: Rule,
    default: f64,
) -> Result<f64, Fail> {
    let mut chosen = None;
    for l in layers {
        if let Some(v) = f(l.raw) {
            let x = check(v, key, rule, &l.what)?;
            chosen.get_or_insert(x);
        }
    }
    Ok(chosen.unwrap_or(default))
}

fn pick<'a, T>(
    layers: &'a [Layer],
    f: impl Fn(&'a RawRobot) -> &'a Option<S<T>>,
) -> Option<(&'a S<T>, &'a str)> {
    layers
        .iter()
        .find_map(|l| f(l.raw).as_ref().map(|v| (v, l.what.as_str())))
}

fn check_params(params: &S<RawParams>, what: &str) -> Result<(), Fail> {
    for (k, v) in params.get_ref() {
        let finite = match v.get_ref() {
            ParamValue::Number(x) => x.is_finite(),
            ParamValue::Numbers(xs) => xs.iter().all(|x| x.is_finite()),
            ParamValue::Points(ps) => ps.iter().flatten().all(|x| x.is_finite()),
            ParamValue::Bool(_) | ParamValue::Text(_) => true,
        };
        if !finite {
            return Err(Fail::new(
                Some(v.span()),
                what,
                format!("parameter `{k}` must be finite numbers"),
            ));
        }
    }
    Ok(())
}

/// Resolves one robot from its layers. `given` is the name, start and goal
/// of a generated robot (used where no layer has them). Returns the spec and
/// whether start and goal were given by a layer.
fn resolve_robot(
    layers: &[Layer],
    given: Option<(String, P, P)>,
    index: usize,
    table: Option<Range<usize>>,
) -> Result<(RobotSpec, RobotSpans, bool), Fail> {
    let anon = format!("robot #{}", index + 1);
    let missing = |key: &str| {
        Fail::new(
            table.clone(),
            anon.as_str(),
            format!("missing `{key}` (every [[robot]] needs name, start and goal)"),
        )
    };
    let name = match (pick(layers, |r| &r.name), &given) {
        (Some((n, what)), _) => {
            if n.get_ref().trim().is_empty() {
                return Err(Fail::new(Some(n.span()), what, "name must not be empty"));
            }
            n.get_ref().clone()
        }
        (None, Some((n, _, _))) => n.clone(),
        (None, None) => return Err(missing("name")),
    };
    let start_raw = pick(layers, |r| &r.start);
    let goal_raw = pick(layers, |r| &r.goal);
    let placed = start_raw.is_some() || goal_raw.is_some();
    let (start, start_span) = match (start_raw, &given) {
        (Some((v, what)), _) => (point(v, "start", what)?, Some(v.span())),
        (None, Some((_, s, _))) => (*s, table.clone()),
        (None, None) => return Err(missing("start")),
    };
    let (goal, goal_span) = match (goal_raw, &given) {
        (Some((v, what)), _) => (point(v, "goal", what)?, Some(v.span())),
        (None, Some((_, _, g))) => (*g, table.clone()),
        (None, None) => return Err(missing("goal")),
    };

    let mut params = BTreeMap::new();
    for l in layers.iter().rev() {
        if let Some(p) = &l.raw.params {
            check_params(p, &l.what)?;
            for (k, v) in p.get_ref() {
                params.insert(k.clone(), v.get_ref().clone());
            }
        }
    }
    let mut path = Vec::new();
    if let Some((p, what)) = pick(layers, |r| &r.path) {
        path = points(p, "path", what)?;
        if path.len() < 2 {
            return Err(Fail::new(
                Some(p.span()),
                what,
                format!("path needs at least 2 points, got {}", path.len()),
            ));
        }
    }
    let boundary = match pick(layers, |r| &r.boundary) {
        Some((b, what)) => {
            let x = check(b, "boundary", Rule::Pos, what)?;
            if path.is_empty() {
                return Err(Fail::new(
                    Some(b.span()),
                    what,
                    "boundary needs a path (the corridor is around the designated path)",
                ));
            }
            Some(x)
        }
        None => None,
    };
    let goal_hold_ticks = match pick(layers, |r| &r.goal_hold_ticks) {
        Some((v, what)) if *v.get_ref() == 0 => {
            return Err(Fail::new(
                Some(v.span()),
                what,
                "goal_hold_ticks must be >= 1, got 0",
            ));
        }
        Some((v, _)) => *v.get_ref(),
        None => builtin::GOAL_HOLD_TICKS,
    };
    let spec = RobotSpec {
        name,
        start,
        goal,
        planner: pick(layers, |r| &r.planner)
            .map_or(builtin::PLANNER.to_string(), |(p, _)| p.get_ref().clone()),
        params,
        radius: pick_num(
            layers,
            |r| &r.radius,
            "radius",
            Rule::NonNeg,
            builtin::RADIUS,
        )?,
        mass: pick_num(layers, |r| &r.mass, "mass", Rule::Pos, builtin::MASS)?,
        damping: pick_num(
            layers,
            |r| &r.damping,
            "damping",
            Rule::NonNeg,
            builtin::DAMPING,
        )?,
        max_speed: pick_num(
            layers,
            |r| &r.max_speed,
            "max_speed",
            Rule::Pos,
            builtin::MAX_SPEED,
        )?,
        max_accel: pick_num(
            layers,
            |r| &r.max_accel,
            "max_accel",
            Rule::Pos,
            builtin::MAX_ACCEL,
        )?,
        velocity_lag: pick_num(
            layers,
            |r| &r.velocity_lag,
            "velocity_lag",
            Rule::NonNeg,
            builtin::VELOCITY_LAG,
        )?,
        sensing_range: pick_num(
            layers,
            |r| &r.sensing_range,
            "sensing_range",
            Rule::Pos,
            builtin::SENSING_RANGE,
        )?,
        field_of_view_deg: pick_num(
            layers,
            |r| &r.field_of_view_deg,
            "field_of_view_deg",
            Rule::Degrees,
            builtin::FIELD_OF_VIEW_DEG,
        )?,
        goal_tolerance: pick_num(
            layers,
            |r| &r.goal_tolerance,
            "goal_tolerance",
            Rule::Pos,
            builtin::GOAL_TOLERANCE,
        )?,
        goal_hold_ticks,
        velocity_source: pick(layers, |r| &r.velocity_source)
            .map_or(VelocitySource::Truth, |(v, _)| *v.get_ref()),
        position_noise: pick_num(
            layers,
            |r| &r.position_noise,
            "position_noise",
            Rule::NonNeg,
            builtin::POSITION_NOISE,
        )?,
        path,
        boundary,
    };
    let spans = RobotSpans {
        table,
        start: start_span,
        goal: goal_span,
    };
    Ok((spec, spans, placed))
}

fn resolve_world(w: Option<&S<RawWorld>>) -> Result<WorldConfig, Fail> {
    let empty = RawWorld::default();
    let raw = w.map_or(&empty, |w| w.get_ref());
    let what = "world";
    let arena = match &raw.arena {
        Some(a) => {
            let min = point(&a.get_ref().min, "arena.min", what)?;
            let max = point(&a.get_ref().max, "arena.max", what)?;
            if !(min[0] < max[0] && min[1] < max[1]) {
                return Err(Fail::new(
                    Some(a.span()),
                    what,
                    format!(
                        "arena min must be < max in x and y, got min [{}, {}], max [{}, {}]",
                        min[0], min[1], max[0], max[1]
                    ),
                ));
            }
            Some(Arena { min, max })
        }
        None => None,
    };
    if let Some(s) = &raw.substeps
        && *s.get_ref() == 0
    {
        return Err(Fail::new(
            Some(s.span()),
            what,
            "substeps must be >= 1, got 0",
        ));
    }
    Ok(WorldConfig {
        dt: opt(&raw.dt, "dt", Rule::Pos, what, 0.1)?,
        substeps: raw.substeps.as_ref().map_or(10, |s| *s.get_ref()),
        duration: opt(&raw.duration, "duration", Rule::Pos, what, 60.0)?,
        mode: raw.mode.as_ref().map_or(Mode::Lockstep, |m| *m.get_ref()),
        on_deadline_miss: raw
            .on_deadline_miss
            .as_ref()
            .map_or(MissPolicy::Hold, |m| *m.get_ref()),
        seed: raw.seed.as_ref().map_or(1, |s| *s.get_ref()),
        arena,
        deadline: opt(&raw.deadline, "deadline", Rule::Fraction, what, 1.0)?,
        stall_timeout: opt(&raw.stall_timeout, "stall_timeout", Rule::Pos, what, 2.0)?,
    })
}

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
    for (key, span) in present(raw) {
        if !allowed.contains(&key) {
            return Err(Fail::new(
                Some(span),
                what,
                format!(
                    "`{key}` does not apply to motion model `{}` (it takes: {})",
                    model.get_ref(),
                    if allowed.is_empty() {
                        "nothing".to_string()
                    } else {
                        allowed.join(", ")
                    }
                ),
            ));
        }
    }
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

fn resolve_obstacle(o: &S<RawObstacle>, index: usize) -> Result<ObstacleSpec, Fail> {
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
    Ok(ObstacleSpec {
        name: name.get_ref().clone(),
        start: point(start, "start", &what)?,
        radius: opt(
            &raw.radius,
            "radius",
            Rule::NonNeg,
            &what,
            builtin::OBSTACLE_RADIUS,
        )?,
        motion: match &raw.motion {
            Some(m) => resolve_motion(m, &what)?,
            None => Motion::Static,
        },
    })
}

/// Everything `resolve` gives back.
pub(crate) struct Resolved {
    pub scenario: Scenario,
    /// How many robots come from the file (the rest are generated).
    pub file_robots: usize,
}

/// Resolves and checks the whole document.
pub(crate) fn resolve(
    raw: RawDoc,
    patches: &[RobotPatch],
    spans: &Spans,
) -> Result<Resolved, Fail> {
    let world = resolve_world(raw.world.as_ref())?;
    let defaults = raw.defaults.as_ref().map(|d| d.get_ref());
    if let Some(d) = defaults {
        for (key, v) in [
            ("name", d.name.as_ref().map(|v| v.span())),
            ("start", d.start.as_ref().map(|v| v.span())),
            ("goal", d.goal.as_ref().map(|v| v.span())),
        ] {
            if let Some(span) = v {
                return Err(Fail::new(
                    Some(span),
                    "defaults",
                    format!("`{key}` cannot be a default; give it in each [[robot]]"),
                ));
            }
        }
    }
    let default_layer = defaults.map(|d| Layer {
        raw: d,
        what: "defaults".into(),
    });

    let mut robots = Vec::new();
    let mut robot_spans = Vec::new();
    for (i, r) in raw.robot.iter().enumerate() {
        let what = match &r.get_ref().name {
            Some(n) => format!("robot `{}`", n.get_ref()),
            None => format!("robot #{}", i + 1),
        };
        let mut layers = vec![Layer {
            raw: r.get_ref(),
            what,
        }];
        layers.extend(default_layer.iter().map(|d| Layer {
            raw: d.raw,
            what: d.what.clone(),
        }));
        let (spec, rs, _) = resolve_robot(&layers, None, i, Some(r.span()))?;
        robots.push(spec);
        robot_spans.push(rs);
    }
    let file_robots = robots.len();

    let mut obstacles = Vec::new();
    let mut obstacle_spans = Vec::new();
    for (i, o) in raw.obstacle.iter().enumerate() {
        obstacles.push(resolve_obstacle(o, i)?);
        obstacle_spans.push(o.span());
    }
    let mut walls = Vec::new();
    for (i, w) in raw.wall.iter().enumerate() {
        let what = format!("wall #{}", i + 1);
        let Some(seg) = &w.get_ref().segment else {
            return Err(Fail::new(Some(w.span()), what, "missing `segment`"));
        };
        let [Pt(a), Pt(b)] = seg.get_ref().as_slice() else {
            return Err(Fail::new(
                Some(seg.span()),
                what,
                format!(
                    "segment must be two points [[x0, y0], [x1, y1]], got {}",
                    seg.get_ref().len()
                ),
            ));
        };
        let (a, b) = (*a, *b);
        if !a.iter().chain(&b).all(|x| x.is_finite()) {
            return Err(Fail::new(
                Some(seg.span()),
                what,
                "segment must be finite numbers",
            ));
        }
        if a == b {
            return Err(Fail::new(
                Some(seg.span()),
                what,
                "segment ends must differ",
            ));
        }
        walls.push(WallSpec { segment: [a, b] });
    }

    // [generate]: the robots' settings first (overrides may change their
    // radius), then their places.
    if let Some(g) = &raw.generate {
        let plan = generate::plan(g, &world)?;
        let gen_raw = RawRobot {
            planner: g.get_ref().planner.clone(),
            params: g.get_ref().params.clone(),
            radius: g.get_ref().robot_radius.clone(),
            ..RawRobot::default()
        };
        let mut specs = Vec::new();
        for (k, name) in plan.names.iter().enumerate() {
            let patch = robot_patch(patches, name, spans)?;
            let mut layers = Vec::new();
            if let Some(p) = &patch {
                layers.push(Layer {
                    raw: p,
                    what: format!("robot `{name}`"),
                });
            }
            layers.push(Layer {
                raw: &gen_raw,
                what: "generate".into(),
            });
            layers.extend(default_layer.iter().map(|d| Layer {
                raw: d.raw,
                what: d.what.clone(),
            }));
            let given = (name.clone(), [0.0, 0.0], [0.0, 0.0]);
            let (spec, rs, placed) =
                resolve_robot(&layers, Some(given), file_robots + k, Some(g.span()))?;
            specs.push((spec, rs, placed));
        }
        let r_max = specs.iter().map(|(s, _, _)| s.radius).fold(0.0, f64::max);
        let places = generate::place(&plan, g, &world, r_max, &robots, &obstacles)?;
        for ((mut spec, rs, placed), (start, goal)) in specs.into_iter().zip(places) {
            if !placed {
                spec.start = start;
                spec.goal = goal;
            }
            robots.push(spec);
            robot_spans.push(rs);
        }
    }
    // A robot override naming no robot at all.
    for p in patches {
        if let crate::overrides::Selector::Name(n) = &p.selector
            && !robots.iter().any(|r| &r.name == n)
        {
            return Err(Fail::new(
                Some(spans.sentinel(p.index)),
                "",
                format!("no robot named `{n}`"),
            ));
        }
    }

    if robots.is_empty() {
        return Err(Fail::new(
            Some(0..0),
            "scenario",
            "no robots: add [[robot]] tables or a [generate] table",
        ));
    }
    let mut scenario = Scenario {
        name: raw.name.as_ref().map_or_else(
            || {
                std::path::Path::new(spans.origin)
                    .file_stem()
                    .map_or("scenario".into(), |s| s.to_string_lossy().into_owned())
            },
            |n| n.get_ref().clone(),
        ),
        description: raw
            .description
            .as_ref()
            .map_or(String::new(), |d| d.get_ref().clone()),
        length_unit: raw
            .length_unit
            .as_ref()
            .map_or(LengthUnit::M, |u| *u.get_ref()),
        world,
        robots,
        obstacles,
        walls,
        map: None,
    };
    if let Some(m) = &raw.map {
        crate::map::attach(
            m,
            spans.origin,
            &mut scenario,
            &robot_spans,
            &obstacle_spans,
        )?;
    }
    check_scene(&scenario, &robot_spans, &obstacle_spans, &raw)?;
    Ok(Resolved {
        scenario,
        file_robots,
    })
}

/// The overrides that select a generated robot, as a robot table.
fn robot_patch(
    patches: &[RobotPatch],
    name: &str,
    spans: &Spans,
) -> Result<Option<RawRobot>, Fail> {
    let mut table = DeTable::new();
    let mut first = None;
    for p in patches.iter().filter(|p| p.selects(name)) {
        let span = spans.sentinel(p.index);
        first.get_or_insert(span.clone());
        set_path(&mut table, &p.rest, p.value.clone(), &span)
            .map_err(|reason| Fail::new(Some(span), format!("robot `{name}`"), reason))?;
    }
    let Some(span) = first else {
        return Ok(None);
    };
    let de = toml::de::ValueDeserializer::from(Spanned::new(span, DeValue::Table(table)));
    RawRobot::deserialize(de)
        .map(Some)
        .map_err(|e| de_fail(e, &format!("robot `{name}`")))
}

fn dist(a: P, b: P) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to the segment `[a, b]`.
pub(crate) fn dist_to_segment(p: P, [a, b]: [P; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Checks that need every body: names, overlaps, arena, targets.
fn check_scene(
    s: &Scenario,
    robot_spans: &[RobotSpans],
    obstacle_spans: &[Range<usize>],
    raw: &RawDoc,
) -> Result<(), Fail> {
    // One namespace for robots and obstacles.
    let mut seen: BTreeMap<&str, &str> = BTreeMap::new();
    let names = s
        .robots
        .iter()
        .zip(robot_spans)
        .map(|(r, sp)| (r.name.as_str(), "robot", sp.table.clone()))
        .chain(
            s.obstacles
                .iter()
                .zip(obstacle_spans)
                .map(|(o, sp)| (o.name.as_str(), "obstacle", Some(sp.clone()))),
        );
    for (name, kind, span) in names {
        if let Some(prev) = seen.insert(name, kind) {
            return Err(Fail::new(
                span,
                format!("{kind} `{name}`"),
                format!(
                    "duplicate name: there is already a {prev} `{name}` (robots and obstacles share one namespace)"
                ),
            ));
        }
    }

    for (i, (r, sp)) in s.robots.iter().zip(robot_spans).enumerate() {
        let what = format!("robot `{}`", r.name);
        for other in &s.robots[..i] {
            let d = dist(r.start, other.start);
            if d < r.radius + other.radius {
                return Err(Fail::new(
                    sp.start.clone(),
                    what,
                    format!(
                        "starts overlapping robot `{}`: distance {d:.4} < {} + {}",
                        other.name, r.radius, other.radius
                    ),
                ));
            }
        }
        for o in &s.obstacles {
            let d = dist(r.start, o.start);
            if d < r.radius + o.radius {
                return Err(Fail::new(
                    sp.start.clone(),
                    what,
                    format!(
                        "starts overlapping obstacle `{}`: distance {d:.4} < {} + {}",
                        o.name, r.radius, o.radius
                    ),
                ));
            }
        }
        for (k, w) in s.walls.iter().enumerate() {
            let d = dist_to_segment(r.start, w.segment);
            if d < r.radius {
                return Err(Fail::new(
                    sp.start.clone(),
                    what,
                    format!(
                        "starts overlapping wall #{}: distance {d:.4} < radius {}",
                        k + 1,
                        r.radius
                    ),
                ));
            }
        }
        if let Some(a) = s.world.arena {
            let p = r.start;
            let fits = p[0] - r.radius >= a.min[0]
                && p[0] + r.radius <= a.max[0]
                && p[1] - r.radius >= a.min[1]
                && p[1] + r.radius <= a.max[1];
            if !fits {
                return Err(Fail::new(
                    sp.start.clone(),
                    what,
                    format!(
                        "start [{}, {}] is outside the arena (with radius {})",
                        p[0], p[1], r.radius
                    ),
                ));
            }
            let g = r.goal;
            if !(g[0] >= a.min[0] && g[0] <= a.max[0] && g[1] >= a.min[1] && g[1] <= a.max[1]) {
                return Err(Fail::new(
                    sp.goal.clone(),
                    what,
                    format!("goal [{}, {}] is outside the arena", g[0], g[1]),
                ));
            }
        }
    }

    for (i, (o, sp)) in s.obstacles.iter().zip(obstacle_spans).enumerate() {
        let what = format!("obstacle `{}`", o.name);
        if let Some(a) = s.world.arena {
            let p = o.start;
            if !(p[0] >= a.min[0] && p[0] <= a.max[0] && p[1] >= a.min[1] && p[1] <= a.max[1]) {
                let span = raw.obstacle[i]
                    .get_ref()
                    .start
                    .as_ref()
                    .map_or(sp.clone(), |v| v.span());
                return Err(Fail::new(
                    Some(span),
                    what,
                    format!("start [{}, {}] is outside the arena", p[0], p[1]),
                ));
            }
        }
        if let Motion::Intentional {
            target: Some(t), ..
        } = &o.motion
        {
            let span = raw.obstacle[i]
                .get_ref()
                .motion
                .as_ref()
                .and_then(|m| m.get_ref().target.as_ref().map(|t| t.span()))
                .unwrap_or(sp.clone());
            if t == &o.name {
                return Err(Fail::new(
                    Some(span),
                    what,
                    "an obstacle cannot target itself",
                ));
            }
            if !seen.contains_key(t.as_str()) {
                return Err(Fail::new(
                    Some(span),
                    what,
                    format!("unknown target `{t}`: no robot or obstacle has that name"),
                ));
            }
        }
    }
    Ok(())
}
