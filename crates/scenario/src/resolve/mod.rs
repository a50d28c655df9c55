//! From the file as written (`raw`) to the resolved `Scenario`: built-in
//! defaults, `[defaults]`, each robot's own keys, `[generate]` and the
//! overrides, in that order of precedence; then every check.
//!
//! `resolve` here walks the document in that order; each part lives in its
//! own module: one robot from its layers (`robots`), the world and walls
//! (`world`), obstacles and their motion models (`obstacles`), the checks
//! across every body (`scene`), and the `[map]`, whose walls the bodies
//! must keep clear of (`map`). The number checks and built-in defaults they
//! share are the crate's `checks`, which `generate` uses too.

mod crowd;
mod map;
mod obstacles;
mod output;
mod people;
mod robots;
mod scene;
mod timing;
mod world;

use crate::error::{Fail, Spans};
use crate::generate;
use crate::overrides::RobotPatch;
use crate::raw::{RawDoc, RawRobot};
use crate::types::*;
use obstacles::resolve_obstacle;
use robots::{CAR_KEYS, Layer, resolve_robot, robot_patch};
use scene::check_scene;
use world::{resolve_wall, resolve_world};

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
    let mut people = Vec::new();
    let mut person_spans = Vec::new();
    for (i, p) in raw.person.iter().enumerate() {
        people.push(people::resolve_person(p.get_ref(), p.span(), i)?);
        person_spans.push(p.span());
    }
    let mut walls = Vec::new();
    for (i, w) in raw.wall.iter().enumerate() {
        walls.push(resolve_wall(w, i)?);
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

    if let Some(d) = defaults {
        defaults_fit(d, &robots)?;
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
        people,
        walls,
        map: None,
        output: output::resolve_output(raw.output.as_ref())?,
    };
    if let Some(m) = &raw.map {
        map::attach(
            m,
            spans.origin,
            &mut scenario,
            &robot_spans,
            &obstacle_spans,
        )?;
    }
    check_scene(&scenario, &robot_spans, &obstacle_spans, &raw)?;
    scene::check_people(&scenario, &person_spans, &raw)?;
    // [[crowd]]s: placed clear of everyone before them, so checked as
    // they are drawn; their names share the one namespace.
    let mut names: std::collections::BTreeSet<String> = scenario.body_names().into_iter().collect();
    for (i, c) in raw.crowd.iter().enumerate() {
        let people = crowd::generate(
            c,
            i,
            raw.crowd.len(),
            scenario.world.seed,
            scenario.world.arena,
            &scenario.robots,
            &scenario.people,
        )?;
        for p in &people {
            let fail = |reason: String| {
                Err(Fail::new(
                    Some(c.span()),
                    format!("crowd #{}", i + 1),
                    format!("person `{}` {reason}", p.name),
                ))
            };
            if let Some(a) = scenario.world.arena {
                let inside = |q: [f64; 2]| {
                    q[0] - p.radius >= a.min[0]
                        && q[0] + p.radius <= a.max[0]
                        && q[1] - p.radius >= a.min[1]
                        && q[1] + p.radius <= a.max[1]
                };
                if let Some(q) = std::iter::once(&p.start)
                    .chain(&p.waypoints)
                    .find(|q| !inside(**q))
                {
                    return fail(format!(
                        "would walk at [{:.3}, {:.3}], outside the arena",
                        q[0], q[1]
                    ));
                }
            }
            if let Some(k) = scenario
                .walls
                .iter()
                .position(|w| scene::dist_to_segment(p.start, w.segment) < p.radius)
            {
                return fail(format!("would start on wall #{}", k + 1));
            }
            if !names.insert(p.name.clone()) {
                return Err(Fail::new(
                    Some(c.span()),
                    format!("crowd #{}", i + 1),
                    format!(
                        "person `{}`: duplicate name (set another `name_prefix`)",
                        p.name
                    ),
                ));
            }
        }
        scenario.people.extend(people);
    }
    Ok(Resolved {
        scenario,
        file_robots,
    })
}

/// A `[defaults]` key that fits only some drives (a car's) or only a goal
/// heading (its tolerance) must fit some robot of the file: one that fits
/// none would say something of no robot.
fn defaults_fit(d: &RawRobot, robots: &[RobotSpec]) -> Result<(), Fail> {
    if !robots.iter().any(|r| r.kinematics == Kinematics::Ackermann) {
        for (key, field) in CAR_KEYS {
            if let Some(v) = field(d) {
                return Err(Fail::new(
                    Some(v.span()),
                    "defaults",
                    format!(
                        "{key} is a car's key and no robot is a car (kinematics = \"ackermann\")"
                    ),
                ));
            }
        }
    }
    if let Some(v) = &d.goal_heading_tolerance_deg
        && !robots.iter().any(|r| r.goal_heading.is_some())
    {
        return Err(Fail::new(
            Some(v.span()),
            "defaults",
            "goal_heading_tolerance_deg needs goal_heading_deg, and no robot has one",
        ));
    }
    Ok(())
}
