//! Checks that need every resolved body at once: one namespace for robots and
//! obstacles, no body starting on another or on a wall, starts and goals
//! inside the arena, intentional obstacles targeting a body that exists.

use super::robots::RobotSpans;
use crate::error::Fail;
use crate::raw::{P, RawDoc};
use crate::types::*;
use std::collections::BTreeMap;
use std::ops::Range;

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

/// How far two bodies' starts overlap (> 0), by their true shapes; two
/// discs as mrsim always compared them (centre distance below the radii).
fn overlap(a: (P, f64, mrsim_shape::Shape, f64), b: (P, f64, mrsim_shape::Shape, f64)) -> f64 {
    use mrsim_shape::{Pose, gap};
    if a.2.is_disc() && b.2.is_disc() {
        let d = dist(a.0, b.0);
        return if d < a.1 + b.1 { a.1 + b.1 - d } else { 0.0 };
    }
    (-gap(&a.2, Pose::new(a.0, a.3), &b.2, Pose::new(b.0, b.3))).max(0.0)
}

fn robot_body(r: &RobotSpec) -> (P, f64, mrsim_shape::Shape, f64) {
    (r.start, r.radius, r.body_shape(), r.start_heading())
}

fn obstacle_body(o: &ObstacleSpec) -> (P, f64, mrsim_shape::Shape, f64) {
    (o.start, o.radius, o.body_shape(), o.heading)
}

/// Why two starts overlap, in words: two discs by their distance and
/// radii, other shapes by the depth of the overlap.
fn overlap_reason(
    kind: &str,
    name: &str,
    a: (P, f64, mrsim_shape::Shape, f64),
    b: (P, f64, mrsim_shape::Shape, f64),
) -> String {
    if a.2.is_disc() && b.2.is_disc() {
        let d = dist(a.0, b.0);
        format!(
            "starts overlapping {kind} `{name}`: distance {d:.4} < {} + {}",
            a.1, b.1
        )
    } else {
        format!(
            "starts overlapping {kind} `{name}`: their shapes overlap by {:.4}",
            overlap(a, b)
        )
    }
}

/// The bounding box of a body's start, [min, max].
fn start_box(r: &RobotSpec) -> [P; 2] {
    let p = r.start;
    match r
        .body_shape()
        .placed(mrsim_shape::Pose::new(p, r.start_heading()))
    {
        None => [
            [p[0] - r.radius, p[1] - r.radius],
            [p[0] + r.radius, p[1] + r.radius],
        ],
        Some(poly) => poly.points().iter().fold(
            [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]],
            |[lo, hi], q| {
                [
                    [lo[0].min(q[0]), lo[1].min(q[1])],
                    [hi[0].max(q[0]), hi[1].max(q[1])],
                ]
            },
        ),
    }
}

/// Checks that need every body: names, overlaps, arena, targets.
pub(super) fn check_scene(
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
        )
        .chain(s.people.iter().enumerate().map(|(k, p)| {
            (
                p.name.as_str(),
                "person",
                raw.person
                    .get(k)
                    .map(|t| t.get_ref().name.as_ref().map_or(t.span(), |n| n.span())),
            )
        }));
    for (name, kind, span) in names {
        if let Some(prev) = seen.insert(name, kind) {
            return Err(Fail::new(
                span,
                format!("{kind} `{name}`"),
                format!(
                    "duplicate name: there is already a {prev} `{name}` (robots, obstacles and people share one namespace)"
                ),
            ));
        }
    }

    // Under SCHED_DEADLINE every planner whose work takes a core needs a
    // reservation: there is no default bandwidth to give it.
    if let Some(cpus) = &s.world.cpus
        && cpus.scheduler == Scheduler::Deadline
    {
        for (r, sp) in s.robots.iter().zip(robot_spans) {
            if r.timing
                .as_ref()
                .is_some_and(|t| t.cpu && t.reservation.is_none())
            {
                return Err(Fail::new(
                    sp.cpu.clone().or(sp.table.clone()),
                    format!("robot `{}`", r.name),
                    "timing.compute.cpu = true under [world.cpus] scheduler = \"deadline\" \
                     needs timing.reservation = { runtime_ms, period_ms }",
                ));
            }
        }
    }

    let starts = StartGrid::new(&s.robots);
    for (i, (r, sp)) in s.robots.iter().zip(robot_spans).enumerate() {
        let what = format!("robot `{}`", r.name);
        if let Some(other) = starts.first_overlap(&s.robots, i) {
            let other = &s.robots[other];
            return Err(Fail::new(
                sp.start.clone(),
                what,
                overlap_reason("robot", &other.name, robot_body(r), robot_body(other)),
            ));
        }
        for o in &s.obstacles {
            if overlap(robot_body(r), obstacle_body(o)) > 0.0 {
                return Err(Fail::new(
                    sp.start.clone(),
                    what,
                    overlap_reason("obstacle", &o.name, robot_body(r), obstacle_body(o)),
                ));
            }
        }
        let body = r.body_shape();
        for (k, w) in s.walls.iter().enumerate() {
            if !body.is_disc() {
                let pose = mrsim_shape::Pose::new(r.start, r.start_heading());
                let g = mrsim_shape::gap_to_segment(&body, pose, w.segment);
                if g < 0.0 {
                    return Err(Fail::new(
                        sp.start.clone(),
                        what,
                        format!(
                            "starts overlapping wall #{}: the wall reaches {:.4} into its shape",
                            k + 1,
                            -g
                        ),
                    ));
                }
                continue;
            }
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
            let [lo, hi] = start_box(r);
            let fits =
                lo[0] >= a.min[0] && hi[0] <= a.max[0] && lo[1] >= a.min[1] && hi[1] <= a.max[1];
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

/// The robots' starts in square cells as wide as the largest diameter, so
/// the robots a start can overlap are in the 3 x 3 cells around it: the
/// overlap check is linear in the robots, not quadratic (100,000 robots
/// took minutes).
struct StartGrid {
    cell: f64,
    cells: std::collections::HashMap<(i64, i64), Vec<usize>>,
}

impl StartGrid {
    fn new(robots: &[RobotSpec]) -> Self {
        let cell = 2.0 * robots.iter().map(|r| r.radius).fold(0.0, f64::max);
        let mut cells: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
        if cell > 0.0 && cell.is_finite() {
            for (i, r) in robots.iter().enumerate() {
                cells.entry(Self::key(cell, r.start)).or_default().push(i);
            }
        }
        Self { cell, cells }
    }

    fn key(cell: f64, p: [f64; 2]) -> (i64, i64) {
        ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64)
    }

    /// The first robot before `i` (in scenario order) whose start overlaps
    /// robot `i`'s, as a scan of every earlier robot finds it.
    fn first_overlap(&self, robots: &[RobotSpec], i: usize) -> Option<usize> {
        let r = &robots[i];
        if self.cells.is_empty() {
            return None;
        }
        let (cx, cy) = Self::key(self.cell, r.start);
        let mut first: Option<usize> = None;
        for dx in -1..=1_i64 {
            for dy in -1..=1_i64 {
                let key = (cx.saturating_add(dx), cy.saturating_add(dy));
                for &j in self.cells.get(&key).map_or(&[][..], Vec::as_slice) {
                    let other = &robots[j];
                    if j < i
                        && first.is_none_or(|f| j < f)
                        && overlap(robot_body(r), robot_body(other)) > 0.0
                    {
                        first = Some(j);
                    }
                }
            }
        }
        first
    }
}

/// A person's checks against the scene: its start clear of every robot,
/// obstacle, wall and earlier person, its start and points inside the
/// arena.
pub(super) fn check_people(
    s: &Scenario,
    person_spans: &[Range<usize>],
    raw: &RawDoc,
) -> Result<(), Fail> {
    let disc = |p: &PersonSpec| (p.start, p.radius, mrsim_shape::Shape::disc(p.radius), 0.0);
    for (k, (p, sp)) in s.people.iter().zip(person_spans).enumerate() {
        let what = format!("person `{}`", p.name);
        let table = raw.person.get(k).map(|t| t.get_ref());
        let start_span = table
            .and_then(|t| t.start.as_ref().map(|v| v.span()))
            .unwrap_or(sp.clone());
        let fail = |reason: String| Err(Fail::new(Some(start_span.clone()), what.clone(), reason));
        for r in &s.robots {
            if overlap(disc(p), robot_body(r)) > 0.0 {
                return fail(overlap_reason("robot", &r.name, disc(p), robot_body(r)));
            }
        }
        for o in &s.obstacles {
            if overlap(disc(p), obstacle_body(o)) > 0.0 {
                return fail(overlap_reason(
                    "obstacle",
                    &o.name,
                    disc(p),
                    obstacle_body(o),
                ));
            }
        }
        for q in &s.people[..k] {
            if overlap(disc(p), disc(q)) > 0.0 {
                return fail(overlap_reason("person", &q.name, disc(p), disc(q)));
            }
        }
        for (w, wall) in s.walls.iter().enumerate() {
            let d = dist_to_segment(p.start, wall.segment);
            if d < p.radius {
                return fail(format!(
                    "starts overlapping wall #{}: distance {d:.4} < radius {}",
                    w + 1,
                    p.radius
                ));
            }
        }
        if let Some(a) = s.world.arena {
            let inside = |q: P| {
                q[0] - p.radius >= a.min[0]
                    && q[0] + p.radius <= a.max[0]
                    && q[1] - p.radius >= a.min[1]
                    && q[1] + p.radius <= a.max[1]
            };
            if !inside(p.start) {
                return fail(format!(
                    "start [{}, {}] is outside the arena (with radius {})",
                    p.start[0], p.start[1], p.radius
                ));
            }
            if let Some(q) = p.waypoints.iter().find(|q| !inside(**q)) {
                let span = table
                    .and_then(|t| {
                        t.goal
                            .as_ref()
                            .map(|v| v.span())
                            .or(t.waypoints.as_ref().map(|v| v.span()))
                    })
                    .unwrap_or(sp.clone());
                return Err(Fail::new(
                    Some(span),
                    what,
                    format!(
                        "point [{}, {}] is outside the arena (with radius {})",
                        q[0], q[1], p.radius
                    ),
                ));
            }
        }
    }
    Ok(())
}
