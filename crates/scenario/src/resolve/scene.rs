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
            let d = dist(r.start, other.start);
            return Err(Fail::new(
                sp.start.clone(),
                what,
                format!(
                    "starts overlapping robot `{}`: distance {d:.4} < {} + {}",
                    other.name, r.radius, other.radius
                ),
            ));
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
                        && dist(r.start, other.start) < r.radius + other.radius
                    {
                        first = Some(j);
                    }
                }
            }
        }
        first
    }
}
