//! `[[crowd]]`: many people at once, placed by a seeded pattern; every
//! other key is a person's (`radius`, `preferred_speed`, `sees_robots`,
//! `behavior`, `group`, `motion`), the same for each.
//!
//! - `circle-crossing` (CrowdNav's `generate_circle_crossing_human`):
//!   each person at a uniform angle on the circle of `circle_radius`
//!   (default 4) about `center`, moved by a noise uniform in
//!   [-v/2, v/2) in x and in y (v the preferred speed: CrowdNav's
//!   `(rand - 0.5) * v_pref`), its goal the opposite point (the start
//!   mirrored through the centre, noise included); drawn again while the
//!   start or the goal comes within r + r' + 0.2 of any robot's or
//!   earlier person's start or goal (CrowdNav's discomfort distance 0.2).
//! - `square-crossing` (CrowdNav's `generate_square_crossing_human`): a
//!   side drawn at random, the start uniform in that half of the square of
//!   side `square_width` (default 10) about `center`, the goal uniform in
//!   the other half; the start drawn again while within r + r' + 0.2 of
//!   another start, the goal while within that of another goal.
//! - `flow`: a two-way stream along x through the box `area` (default the
//!   arena): each person starts uniformly in the box, at least r + r' +
//!   0.2 from every other start, and walks at its own height between the
//!   box's two ends, cyclically, the first half of the crowd first to the
//!   right, the others first to the left.
//!
//! Each crowd draws from its own stream of the scenario's seed
//! (`world.seed`, tag `crowd`, the crowd's index), so the same file gives
//! the same people. Names are `name_prefix` (default `h`, or `c<k>h` for
//! the k-th crowd when there are several) and the index.

use super::people::resolve_person;
use crate::checks::{Rule, check, point};
use crate::error::Fail;
use crate::raw::{P, Pt, RawCrowd, RawPerson, S};
use crate::rng::Rng;
use crate::types::{Arena, PersonSpec, RobotSpec};
use std::f64::consts::PI;
use std::ops::Range;

const PATTERNS: &str = "circle-crossing | square-crossing | flow";
/// CrowdNav's `discomfort_dist`: the room kept between generated people.
const DISCOMFORT: f64 = 0.2;
/// Draws before a pattern gives up on placing a person.
const TRIES: usize = 10_000;
/// Most people one `[[crowd]]` makes.
const MAX_COUNT: i64 = 1_000_000;

/// The people of the `index`th of `crowds` crowd tables, among `robots` and
/// the people placed before (`people`), in an optional `arena`.
pub(super) fn generate(
    c: &S<RawCrowd>,
    index: usize,
    crowds: usize,
    seed: u64,
    arena: Option<Arena>,
    robots: &[RobotSpec],
    people: &[PersonSpec],
) -> Result<Vec<PersonSpec>, Fail> {
    let raw = c.get_ref();
    let table = c.span();
    let what = format!("crowd #{}", index + 1);
    let Some(count) = &raw.count else {
        return Err(Fail::new(Some(table), what, "missing `count`"));
    };
    let n = *count.get_ref();
    if !(1..=MAX_COUNT).contains(&n) {
        return Err(Fail::new(
            Some(count.span()),
            what,
            format!("count must be in 1..={MAX_COUNT}, got {n}"),
        ));
    }
    let n = n as usize;
    let Some(pattern) = &raw.pattern else {
        return Err(Fail::new(
            Some(table),
            what,
            format!("missing `pattern`: {PATTERNS}"),
        ));
    };
    let at = |span: &Option<Range<usize>>, key: &str| -> Result<(), Fail> {
        match span {
            Some(s) => Err(Fail::new(
                Some(s.clone()),
                what.clone(),
                format!("`{key}` does not apply to pattern `{}`", pattern.get_ref()),
            )),
            None => Ok(()),
        }
    };
    let span = |v: &Option<S<f64>>| v.as_ref().map(|v| v.span());
    match pattern.get_ref().as_str() {
        "circle-crossing" => {
            at(&span(&raw.square_width), "square_width")?;
            at(&raw.area.as_ref().map(|a| a.span()), "area")?;
        }
        "square-crossing" => {
            at(&span(&raw.circle_radius), "circle_radius")?;
            at(&raw.area.as_ref().map(|a| a.span()), "area")?;
        }
        "flow" => {
            at(&span(&raw.circle_radius), "circle_radius")?;
            at(&span(&raw.square_width), "square_width")?;
            at(&raw.center.as_ref().map(|a| a.span()), "center")?;
        }
        other => {
            return Err(Fail::new(
                Some(pattern.span()),
                what,
                format!("unknown pattern `{other}`; expected {PATTERNS}"),
            ));
        }
    }
    let center = match &raw.center {
        Some(c) => point(c, "center", &what)?,
        None => [0.0, 0.0],
    };
    let prefix = match &raw.name_prefix {
        Some(p) if p.get_ref().trim().is_empty() => {
            return Err(Fail::new(
                Some(p.span()),
                what,
                "name_prefix must not be empty",
            ));
        }
        Some(p) => p.get_ref().clone(),
        None if crowds > 1 => format!("c{}h", index + 1),
        None => "h".to_string(),
    };
    // The person every member is, but for its name and route: its keys
    // checked once, at the crowd's lines.
    let person = |name: String, start: P, route: Route| RawPerson {
        name: Some(S::new(table.clone(), name)),
        start: Some(S::new(table.clone(), Pt(start))),
        goal: match &route {
            Route::Goal(g) => Some(S::new(table.clone(), Pt(*g))),
            Route::Cycle(_) => None,
        },
        waypoints: match &route {
            Route::Goal(_) => None,
            Route::Cycle(w) => Some(S::new(table.clone(), w.iter().map(|p| Pt(*p)).collect())),
        },
        cyclic: match &route {
            Route::Goal(_) => None,
            Route::Cycle(_) => Some(S::new(table.clone(), true)),
        },
        radius: raw.radius.clone(),
        preferred_speed: raw.preferred_speed.clone(),
        sees_robots: raw.sees_robots.clone(),
        behavior: raw.behavior.clone(),
        group: raw.group.clone(),
        motion: raw.motion.clone(),
    };
    let template = resolve_person(
        &person("template".into(), [0.0; 2], Route::Goal([0.0; 2])),
        table.clone(),
        index,
    )
    .map_err(|mut f| {
        f.what = what.clone();
        f
    })?;
    let (r, v) = (template.radius, template.preferred_speed);
    let mut rng = Rng::stream(seed, "crowd", index as u64);
    // Every start and goal so far, with its body's radius.
    let largest = robots
        .iter()
        .map(|x| x.radius)
        .chain(people.iter().map(|p| p.radius))
        .fold(r, f64::max);
    let cell = r + largest + DISCOMFORT;
    let mut starts = Placed::new(
        cell,
        robots
            .iter()
            .map(|x| (x.start, x.radius))
            .chain(people.iter().map(|p| (p.start, p.radius))),
    );
    let mut goals = Placed::new(
        cell,
        robots.iter().map(|x| (x.goal, x.radius)).chain(
            people
                .iter()
                .filter_map(|p| p.waypoints.last().map(|g| (*g, p.radius))),
        ),
    );
    let clear = |p: P, of: &Placed| of.clear(p, r);
    let full = |k: usize| {
        Fail::new(
            Some(table.clone()),
            what.clone(),
            format!(
                "could not place person {} of {n} (radius {r}) clear of the others \
                 by {DISCOMFORT} after {TRIES} draws: too many for the pattern's room",
                k + 1
            ),
        )
    };
    let mut out = Vec::with_capacity(n);
    let flow_box = match (pattern.get_ref().as_str(), &raw.area) {
        ("flow", Some(a)) => {
            let a = a.get_ref();
            Some(Arena {
                min: point(&a.min, "area.min", &what)?,
                max: point(&a.max, "area.max", &what)?,
            })
        }
        ("flow", None) => match arena {
            Some(a) => Some(a),
            None => {
                return Err(Fail::new(
                    Some(table),
                    what,
                    "pattern `flow` needs `area = { min, max }` or an arena",
                ));
            }
        },
        _ => None,
    };
    if let Some(b) = flow_box
        && !(b.max[0] - b.min[0] > 2.0 * r && b.max[1] - b.min[1] > 2.0 * r)
    {
        return Err(Fail::new(
            raw.area
                .as_ref()
                .map_or(Some(table.clone()), |a| Some(a.span())),
            what,
            format!("the flow's box is too small for people of radius {r}"),
        ));
    }
    for k in 0..n {
        let name = format!("{prefix}{k}");
        let (start, route) = match pattern.get_ref().as_str() {
            "circle-crossing" => {
                let big_r = match &raw.circle_radius {
                    Some(x) => check(x, "circle_radius", Rule::Pos, &what)?,
                    None => 4.0,
                };
                let mut found = None;
                for _ in 0..TRIES {
                    let angle = rng.unit() * 2.0 * PI;
                    let nx = (rng.unit() - 0.5) * v;
                    let ny = (rng.unit() - 0.5) * v;
                    let p = [
                        center[0] + big_r * angle.cos() + nx,
                        center[1] + big_r * angle.sin() + ny,
                    ];
                    let g = [2.0 * center[0] - p[0], 2.0 * center[1] - p[1]];
                    // CrowdNav tests the start against every start and
                    // goal; the goal, mirrored, is then clear too.
                    if clear(p, &starts) && clear(p, &goals) && clear(g, &goals) {
                        found = Some((p, g));
                        break;
                    }
                }
                let (p, g) = found.ok_or_else(|| full(k))?;
                (p, Route::Goal(g))
            }
            "square-crossing" => {
                let w = match &raw.square_width {
                    Some(x) => check(x, "square_width", Rule::Pos, &what)?,
                    None => 10.0,
                };
                let sign = if rng.unit() > 0.5 { -1.0 } else { 1.0 };
                let mut draw = |side: f64, of: &Placed| {
                    for _ in 0..TRIES {
                        let p = [
                            center[0] + rng.unit() * w * 0.5 * side,
                            center[1] + (rng.unit() - 0.5) * w,
                        ];
                        if clear(p, of) {
                            return Some(p);
                        }
                    }
                    None
                };
                let p = draw(sign, &starts).ok_or_else(|| full(k))?;
                let g = draw(-sign, &goals).ok_or_else(|| full(k))?;
                (p, Route::Goal(g))
            }
            _ => {
                let Some(b) = flow_box else {
                    return Err(full(k));
                };
                let (lo, hi) = ([b.min[0] + r, b.min[1] + r], [b.max[0] - r, b.max[1] - r]);
                let mut found = None;
                for _ in 0..TRIES {
                    let p = [
                        lo[0] + rng.unit() * (hi[0] - lo[0]),
                        lo[1] + rng.unit() * (hi[1] - lo[1]),
                    ];
                    if clear(p, &starts) {
                        found = Some(p);
                        break;
                    }
                }
                let p = found.ok_or_else(|| full(k))?;
                let (right, left) = ([hi[0], p[1]], [lo[0], p[1]]);
                let cycle = if k < n.div_ceil(2) {
                    vec![right, left]
                } else {
                    vec![left, right]
                };
                (p, Route::Cycle(cycle))
            }
        };
        let spec = resolve_person(&person(name, start, route), table.clone(), index)?;
        starts.push(spec.start, spec.radius);
        if let Some(g) = spec.waypoints.last() {
            goals.push(*g, spec.radius);
        }
        out.push(spec);
    }
    Ok(out)
}

/// Points placed so far with their bodies' radii, in square cells of a
/// side no less than any two bodies' radii and the discomfort distance,
/// so that whether a new point is clear of every one is told by the
/// points of its own cell and the eight around it.
struct Placed {
    cell: f64,
    cells: std::collections::HashMap<(i64, i64), Vec<(P, f64)>>,
}

impl Placed {
    /// `points` in cells of side `cell` (> 0).
    fn new(cell: f64, points: impl Iterator<Item = (P, f64)>) -> Self {
        let mut placed = Self {
            cell,
            cells: std::collections::HashMap::new(),
        };
        for (p, radius) in points {
            placed.push(p, radius);
        }
        placed
    }

    /// The cell of `p`.
    fn key(&self, p: P) -> (i64, i64) {
        (
            (p[0] / self.cell).floor() as i64,
            (p[1] / self.cell).floor() as i64,
        )
    }

    /// Adds a body of radius `radius` at `p`.
    fn push(&mut self, p: P, radius: f64) {
        let key = self.key(p);
        self.cells.entry(key).or_default().push((p, radius));
    }

    /// Is a body of radius `r` at `p` clear of every body placed by its
    /// radius, the other's and the discomfort distance? (Bodies beyond
    /// the eight cells around `p`'s are further than a cell, so clear.)
    fn clear(&self, p: P, r: f64) -> bool {
        let (cx, cy) = self.key(p);
        (cx - 1..=cx + 1).all(|x| {
            (cy - 1..=cy + 1).all(|y| {
                self.cells.get(&(x, y)).is_none_or(|of| {
                    of.iter()
                        .all(|(q, rq)| (p[0] - q[0]).hypot(p[1] - q[1]) >= r + rq + DISCOMFORT)
                })
            })
        })
    }
}

/// A generated person's route.
#[derive(Clone)]
enum Route {
    /// One goal.
    Goal(P),
    /// Waypoints walked cyclically.
    Cycle(Vec<P>),
}
