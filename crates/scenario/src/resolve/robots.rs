//! One robot from its layers of settings (its own keys, the overrides that
//! select it, `[generate]`, `[defaults]`, the built-in defaults): pick each
//! field from the highest layer that has it, check it in every layer.

use crate::checks::{Rule, builtin, check, de_fail, point, points, shape};
use crate::error::{Fail, Spans};
use crate::overrides::{RobotPatch, set_path};
use crate::raw::{P, RawParams, RawRobot, RawSensor, S};
use crate::types::*;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// One layer of robot settings, highest precedence first.
pub(super) struct Layer<'a> {
    pub raw: &'a RawRobot,
    pub what: String,
}

impl Layer<'_> {
    /// Is this the `[defaults]` table (whose keys are for the robots they
    /// fit, not a statement about each robot)?
    fn is_defaults(&self) -> bool {
        self.what == "defaults"
    }
}

/// A number key's field of a robot table.
type Field = fn(&RawRobot) -> &Option<S<f64>>;

/// The keys that apply to a car only (`kinematics = "ackermann"`), with
/// their fields.
pub(super) const CAR_KEYS: [(&str, Field); 4] = [
    ("wheelbase", |r| &r.wheelbase),
    ("max_steering_deg", |r| &r.max_steering_deg),
    ("max_steering_rate_deg", |r| &r.max_steering_rate_deg),
    ("max_reverse_speed", |r| &r.max_reverse_speed),
];

/// Where a robot's errors point.
#[derive(Debug, Clone)]
pub(crate) struct RobotSpans {
    pub table: Option<Range<usize>>,
    pub start: Option<Range<usize>>,
    pub goal: Option<Range<usize>>,
    /// The `timing.compute.cpu` that decided the robot's `cpu`, if any.
    pub cpu: Option<Range<usize>>,
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
pub(super) fn resolve_robot(
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
    let sensor = match pick(layers, |r| &r.sensor) {
        Some((raw, what)) => Some(lidar(raw, what)?),
        None => None,
    };
    let timing = super::timing::resolve_timing(layers)?;
    let (body, radius) = body_shape(layers)?;
    let spec = RobotSpec {
        name,
        start,
        goal,
        planner: pick(layers, |r| &r.planner)
            .map_or(builtin::PLANNER.to_string(), |(p, _)| p.get_ref().clone()),
        params,
        radius,
        shape: body,
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
        kinematics: pick(layers, |r| &r.kinematics)
            .map_or(Kinematics::Holonomic, |(k, _)| *k.get_ref()),
        max_angular_speed: pick_num(
            layers,
            |r| &r.max_angular_speed,
            "max_angular_speed",
            Rule::Pos,
            DEFAULT_MAX_ANGULAR_SPEED,
        )?,
        max_angular_accel: pick_num(
            layers,
            |r| &r.max_angular_accel,
            "max_angular_accel",
            Rule::Pos,
            DEFAULT_MAX_ANGULAR_ACCEL,
        )?,
        lookahead: 0.0,
        ackermann: None,
        goal_heading: None,
        route: pick(layers, |r| &r.route).map_or(Route::Direct, |(v, _)| *v.get_ref()),
        lane: pick(layers, |r| &r.lane).map_or(Lane::None, |(v, _)| *v.get_ref()),
        sensor,
        timing,
        replay: None,
    };
    let mut spec = spec;
    spec.lookahead = lookahead(layers, &spec)?;
    spec.ackermann = ackermann(layers, spec.kinematics, table.as_ref(), &anon)?;
    spec.goal_heading = goal_heading(layers, spec.kinematics)?;
    if spec.lane != Lane::None
        && spec.route != Route::Shortest
        && let Some((v, what)) = pick(layers, |r| &r.lane)
    {
        return Err(Fail::new(
            Some(v.span()),
            what,
            "lane needs route = \"shortest\": it says which side of a corridor the robot's \
             route keeps to, and a robot without a route drives straight at its goal",
        ));
    }
    let cpu = layers
        .iter()
        .filter_map(|l| l.raw.timing.as_ref())
        .filter_map(|t| t.get_ref().compute.as_ref())
        .find_map(|c| c.get_ref().cpu.as_ref().map(|c| c.span()));
    let spans = RobotSpans {
        table,
        start: start_span,
        goal: goal_span,
        cpu,
    };
    Ok((spec, spans, placed))
}

/// The robot's shape and radius: a disc takes `radius` (checked in every
/// layer); another shape's radius is the circumscribed one, and a `radius`
/// in the layer that gives the shape, or a higher one, is refused (it would
/// say two sizes). A lower layer's radius (`[defaults]`) is for discs.
fn body_shape(layers: &[Layer]) -> Result<(ShapeSpec, f64), Fail> {
    let radius = pick_num(
        layers,
        |r| &r.radius,
        "radius",
        Rule::NonNeg,
        builtin::RADIUS,
    )?;
    let mut chosen = None;
    for (i, l) in layers.iter().enumerate() {
        if let Some(v) = &l.raw.shape {
            let s = shape(v, &l.what)?;
            chosen.get_or_insert((i, s));
        }
    }
    let Some((at, spec)) = chosen else {
        return Ok((ShapeSpec::Disc, radius));
    };
    if spec.is_disc() {
        return Ok((spec, radius));
    }
    if let Some((l, r)) = layers[..=at]
        .iter()
        .find_map(|l| l.raw.radius.as_ref().map(|r| (l, r)))
    {
        return Err(Fail::new(
            Some(r.span()),
            &l.what,
            "radius is the size of a disc; a rectangle or polygon is sized by its own keys              (its circumscribed radius is computed): leave radius out",
        ));
    }
    let r = spec.shape(radius).circumradius();
    Ok((spec, r))
}

/// The robot's `lookahead`: as given, which on a unicycle must be below
/// `goal_tolerance` (the look-ahead point is what the planner brings to the
/// goal, and the planner is told `goal_tolerance - lookahead`), or
/// [`default_lookahead_for`] the tolerance.
fn lookahead(layers: &[Layer], spec: &RobotSpec) -> Result<f64, Fail> {
    let given = pick_num(layers, |r| &r.lookahead, "lookahead", Rule::Pos, f64::NAN)?;
    if given.is_nan() {
        return Ok(default_lookahead_for(spec.goal_tolerance));
    }
    if spec.kinematics == Kinematics::Unicycle
        && given >= spec.goal_tolerance
        && let Some((v, what)) = pick(layers, |r| &r.lookahead)
    {
        return Err(Fail::new(
            Some(v.span()),
            what,
            format!(
                "lookahead {given} must be below goal_tolerance {}: a planner on a unicycle \
                 brings the point `lookahead` ahead of the centre to the goal and is told \
                 goal_tolerance - lookahead, so that the centre ends within goal_tolerance; \
                 with nothing left the robot cannot be sure to arrive (leave lookahead out \
                 for half the tolerance, at most {DEFAULT_LOOKAHEAD})",
                spec.goal_tolerance
            ),
        ));
    }
    Ok(given)
}

/// The name of a drive as a scenario writes it.
fn drive_name(k: Kinematics) -> &'static str {
    match k {
        Kinematics::Holonomic => "holonomic",
        Kinematics::Unicycle => "unicycle",
        Kinematics::Ackermann => "ackermann",
    }
}

/// A car's geometry and limits, when the robot is one: `wheelbase`
/// required, `max_steering_deg` in (0, 90) (default
/// [`DEFAULT_MAX_STEERING_DEG`]), `max_steering_rate_deg` > 0 (default
/// [`DEFAULT_MAX_STEERING_RATE_DEG`]), `max_reverse_speed` >= 0 (default
/// 0), each checked in every layer. On another drive these keys are
/// refused where the robot's own table (or an override) gives them; a
/// `[defaults]` one is for the cars of the file (refused by `resolve` when
/// there is none).
fn ackermann(
    layers: &[Layer],
    kinematics: Kinematics,
    table: Option<&Range<usize>>,
    anon: &str,
) -> Result<Option<Ackermann>, Fail> {
    if kinematics != Kinematics::Ackermann {
        for l in layers.iter().filter(|l| !l.is_defaults()) {
            for (key, field) in CAR_KEYS {
                if let Some(v) = field(l.raw) {
                    return Err(Fail::new(
                        Some(v.span()),
                        &l.what,
                        format!(
                            "{key} is a car's key (kinematics = \"ackermann\"); this robot is {}",
                            drive_name(kinematics)
                        ),
                    ));
                }
            }
        }
        return Ok(None);
    }
    let wheelbase = pick_num(layers, |r| &r.wheelbase, "wheelbase", Rule::Pos, f64::NAN)?;
    if wheelbase.is_nan() {
        let (span, what) = match pick(layers, |r| &r.kinematics) {
            Some((k, what)) => (Some(k.span()), what),
            None => (table.cloned(), anon),
        };
        return Err(Fail::new(
            span,
            what,
            "kinematics = \"ackermann\" needs `wheelbase`, the distance between the axles (> 0)",
        ));
    }
    let max_steering = pick_num(
        layers,
        |r| &r.max_steering_deg,
        "max_steering_deg",
        Rule::Acute,
        DEFAULT_MAX_STEERING_DEG,
    )?;
    let max_steering_rate = pick_num(
        layers,
        |r| &r.max_steering_rate_deg,
        "max_steering_rate_deg",
        Rule::Pos,
        DEFAULT_MAX_STEERING_RATE_DEG,
    )?;
    let max_reverse_speed = pick_num(
        layers,
        |r| &r.max_reverse_speed,
        "max_reverse_speed",
        Rule::NonNeg,
        0.0,
    )?;
    Ok(Some(Ackermann {
        wheelbase,
        max_steering: max_steering.to_radians(),
        max_steering_rate: max_steering_rate.to_radians(),
        max_reverse_speed,
    }))
}

/// The heading the robot must have at its goal (`goal_heading_deg`, any
/// finite angle; `goal_heading_tolerance_deg` in (0, 180], default
/// [`DEFAULT_GOAL_HEADING_TOLERANCE_DEG`], only with a goal heading: where
/// the robot's own table gives it without one it is refused, a
/// `[defaults]` one is for the robots that have one). A holonomic robot's
/// heading stays 0, so a goal heading it can never meet is refused.
fn goal_heading(layers: &[Layer], kinematics: Kinematics) -> Result<Option<GoalHeading>, Fail> {
    let heading = pick_num(
        layers,
        |r| &r.goal_heading_deg,
        "goal_heading_deg",
        Rule::Finite,
        f64::NAN,
    )?;
    let tolerance = pick_num(
        layers,
        |r| &r.goal_heading_tolerance_deg,
        "goal_heading_tolerance_deg",
        Rule::HalfTurn,
        DEFAULT_GOAL_HEADING_TOLERANCE_DEG,
    )?;
    if heading.is_nan() {
        for l in layers.iter().filter(|l| !l.is_defaults()) {
            if let Some(v) = &l.raw.goal_heading_tolerance_deg {
                return Err(Fail::new(
                    Some(v.span()),
                    &l.what,
                    "goal_heading_tolerance_deg needs goal_heading_deg (the heading it is a \
                     tolerance of)",
                ));
            }
        }
        return Ok(None);
    }
    let goal = GoalHeading {
        heading: heading.to_radians(),
        tolerance: tolerance.to_radians(),
    };
    if kinematics == Kinematics::Holonomic
        && !goal.holds(0.0)
        && let Some((v, what)) = pick(layers, |r| &r.goal_heading_deg)
    {
        return Err(Fail::new(
            Some(v.span()),
            what,
            format!(
                "goal_heading_deg {heading} can never be met: a holonomic robot never turns \
                 (its heading stays 0), and 0 is not within goal_heading_tolerance_deg \
                 {tolerance} of it"
            ),
        ));
    }
    Ok(Some(goal))
}

/// A `sensor` table: only `kind = "lidar"` is known; each key is checked
/// and defaults to beams 360, fov_deg 360, range 10, noise 0, record false.
fn lidar(raw: &S<RawSensor>, what: &str) -> Result<Lidar, Fail> {
    let r = raw.get_ref();
    match &r.kind {
        Some(k) if k.get_ref() == "lidar" => {}
        Some(k) => {
            return Err(Fail::new(
                Some(k.span()),
                what,
                format!("unknown sensor kind `{}` (known: lidar)", k.get_ref()),
            ));
        }
        None => {
            return Err(Fail::new(
                Some(raw.span()),
                what,
                "sensor needs `kind` (known: lidar)",
            ));
        }
    }
    let num = |v: &Option<S<f64>>, key: &str, rule: Rule, default: f64| match v {
        Some(v) => check(v, key, rule, what),
        None => Ok(default),
    };
    let beams = match &r.beams {
        Some(b) if *b.get_ref() == 0 => {
            return Err(Fail::new(
                Some(b.span()),
                what,
                "sensor beams must be >= 1, got 0",
            ));
        }
        Some(b) => *b.get_ref(),
        None => 360,
    };
    Ok(Lidar {
        beams,
        fov_deg: num(&r.fov_deg, "sensor fov_deg", Rule::Degrees, 360.0)?,
        range: num(&r.range, "sensor range", Rule::Pos, 10.0)?,
        noise: num(&r.noise, "sensor noise", Rule::NonNeg, 0.0)?,
        record: r.record.as_ref().is_some_and(|b| *b.get_ref()),
    })
}

/// The overrides that select a generated robot, as a robot table.
pub(super) fn robot_patch(
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
