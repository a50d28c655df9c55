//! `[generate]`: many robots at once.
//!
//! - `circle`: `count` robots evenly on a circle of `radius` around `center`,
//!   robot k at angle 2πk/count, each going to the antipodal point.
//! - `crossing`: two streams crossing at `center` at right angles. The first
//!   ceil(count/2) robots queue along -x and go +x; the others queue along -y
//!   and go +y. The stream's head starts `radius` before the centre and every
//!   robot ends as far past it as it started before it (the queue, mirrored).
//! - `corridor`: two groups on the line y = center.y entering from opposite
//!   ends and swapping: the first ceil(count/2) queue left of
//!   `center.x - radius` and go right, the others queue right of
//!   `center.x + radius` and go left, each to the place the other group's
//!   queue held. The walls are the file's `[[wall]]`s.
//! - `random`: starts and goals drawn uniformly inside the world's arena if
//!   there is one, else in the square of side 2·radius around `center`; no
//!   two starts (and no two goals) closer than two robot radii plus a 10 %
//!   margin, no start on a file robot or obstacle. Seeded by `world.seed`
//!   (SplitMix64), so the same file gives the same robots.
//!
//! `jitter` (default 0) moves every generated start by a distance drawn
//! uniformly in [0, jitter] in a direction drawn uniformly in [0, 2π),
//! seeded by `world.seed` (a SplitMix64 stream of its own, so `random`'s
//! draws do not change with it); goals stay where they are. An exactly
//! symmetric start (the circle) makes symmetric planners such as ORCA stop
//! in a ring of touching discs; RVO2's Circle example only escapes through
//! its f32 round-off. A small jitter is the honest, reproducible stand-in.
//!
//! Queue spacing (crossing, corridor) is 3 robot radii centre to centre
//! (one radius of gap), or radius/count for point robots.
//! Names are `name_prefix` (default `g`) and the index, zero-padded to at
//! least two digits (`g00`, `g01`, ..., `g100` for 101 robots).

use crate::checks::{Rule, check, point};
use crate::error::Fail;
use crate::raw::{P, RawGenerate, S};
use crate::rng::Rng;
use crate::types::{Arena, ObstacleSpec, RobotSpec, WorldConfig};
use std::f64::consts::PI;

/// The kind of generation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    Circle,
    Crossing,
    Corridor,
    Random,
}

/// What `[generate]` asks for, checked.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    pub kind: Kind,
    pub names: Vec<String>,
    pub radius: Option<f64>,
    pub center: P,
    pub jitter: f64,
}

const WHAT: &str = "generate";
/// Most robots `[generate]` makes (a sanity bound: 100,000 robots run in-process).
const MAX_COUNT: usize = 1_000_000;

/// Checks `[generate]` and names its robots.
pub(crate) fn plan(g: &S<RawGenerate>, world: &WorldConfig) -> Result<Plan, Fail> {
    let raw = g.get_ref();
    let Some(kind) = &raw.kind else {
        return Err(Fail::new(
            Some(g.span()),
            WHAT,
            "missing `kind`: circle | crossing | corridor | random",
        ));
    };
    let k = match kind.get_ref().as_str() {
        "circle" => Kind::Circle,
        "crossing" => Kind::Crossing,
        "corridor" => Kind::Corridor,
        "random" => Kind::Random,
        other => {
            return Err(Fail::new(
                Some(kind.span()),
                WHAT,
                format!("unknown kind `{other}`; expected circle | crossing | corridor | random"),
            ));
        }
    };
    let Some(count) = &raw.count else {
        return Err(Fail::new(Some(g.span()), WHAT, "missing `count`"));
    };
    let n = *count.get_ref() as usize;
    if n == 0 || n > MAX_COUNT {
        return Err(Fail::new(
            Some(count.span()),
            WHAT,
            format!("count must be in 1..={MAX_COUNT}, got {n}"),
        ));
    }
    let radius = raw
        .radius
        .as_ref()
        .map(|r| check(r, "radius", Rule::Pos, WHAT))
        .transpose()?;
    if radius.is_none() && !(k == Kind::Random && world.arena.is_some()) {
        let why = if k == Kind::Random {
            "kind `random` needs `radius` (or an arena in [world])"
        } else {
            "missing `radius`"
        };
        return Err(Fail::new(Some(g.span()), WHAT, why));
    }
    if let Some(r) = &raw.robot_radius {
        check(r, "robot_radius", Rule::NonNeg, WHAT)?;
    }
    let jitter = raw
        .jitter
        .as_ref()
        .map(|j| check(j, "jitter", Rule::NonNeg, WHAT))
        .transpose()?
        .unwrap_or(0.0);
    let center = raw
        .center
        .as_ref()
        .map(|c| point(c, "center", WHAT))
        .transpose()?
        .unwrap_or([0.0, 0.0]);
    let prefix = match &raw.name_prefix {
        Some(p) if p.get_ref().trim().is_empty() => {
            return Err(Fail::new(
                Some(p.span()),
                WHAT,
                "name_prefix must not be empty",
            ));
        }
        Some(p) => p.get_ref().clone(),
        None => "g".to_string(),
    };
    let digits = (n - 1).to_string().len().max(2);
    let names = (0..n).map(|i| format!("{prefix}{i:0digits$}")).collect();
    Ok(Plan {
        kind: k,
        names,
        radius,
        center,
        jitter,
    })
}

/// Starts and goals of the generated robots, in name order.
pub(crate) fn place(
    plan: &Plan,
    g: &S<RawGenerate>,
    world: &WorldConfig,
    robot_radius: f64,
    robots: &[RobotSpec],
    obstacles: &[ObstacleSpec],
) -> Result<Vec<(P, P)>, Fail> {
    let n = plan.names.len();
    let [cx, cy] = plan.center;
    let big_r = plan.radius.unwrap_or(1.0);
    let na = n.div_ceil(2);
    let nb = n - na;
    let spacing = |group: usize| {
        if robot_radius > 0.0 {
            3.0 * robot_radius
        } else {
            big_r / group.max(1) as f64
        }
    };
    let mut places = match plan.kind {
        Kind::Circle => (0..n)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / n as f64;
                let (s, c) = a.sin_cos();
                (
                    [cx + big_r * c, cy + big_r * s],
                    [cx - big_r * c, cy - big_r * s],
                )
            })
            .collect(),
        Kind::Crossing => {
            let sa = spacing(na);
            let sb = spacing(nb);
            let mut out = Vec::with_capacity(n);
            for k in 0..na {
                let back = big_r + k as f64 * sa;
                let ahead = big_r + (na - 1 - k) as f64 * sa;
                out.push(([cx - back, cy], [cx + ahead, cy]));
            }
            for k in 0..nb {
                let back = big_r + k as f64 * sb;
                let ahead = big_r + (nb - 1 - k) as f64 * sb;
                out.push(([cx, cy - back], [cx, cy + ahead]));
            }
            out
        }
        Kind::Corridor => {
            let s = spacing(na);
            let mut out = Vec::with_capacity(n);
            for k in 0..na {
                let back = big_r + k as f64 * s;
                let ahead = big_r + (na - 1 - k) as f64 * s;
                out.push(([cx - back, cy], [cx + ahead, cy]));
            }
            for k in 0..nb {
                let back = big_r + k as f64 * s;
                let ahead = big_r + (nb - 1 - k) as f64 * s;
                out.push(([cx + back, cy], [cx - ahead, cy]));
            }
            out
        }
        Kind::Random => random(plan, g, world, robot_radius, robots, obstacles)?,
    };
    jitter_starts(&mut places, plan.jitter, world.seed);
    Ok(places)
}

/// Moves every start by up to `jitter` in a seeded random direction.
fn jitter_starts(places: &mut [(P, P)], jitter: f64, seed: u64) {
    if jitter <= 0.0 {
        return;
    }
    // A stream of its own: `random` draws from `Rng(seed)`.
    let mut rng = Rng(seed ^ 0x6A17_7E12_5EED_0001);
    for (start, _) in places {
        let distance = rng.unit() * jitter;
        let (s, c) = (rng.unit() * 2.0 * PI).sin_cos();
        start[0] += distance * c;
        start[1] += distance * s;
    }
}

fn random(
    plan: &Plan,
    g: &S<RawGenerate>,
    world: &WorldConfig,
    r: f64,
    robots: &[RobotSpec],
    obstacles: &[ObstacleSpec],
) -> Result<Vec<(P, P)>, Fail> {
    let area = match (world.arena, plan.radius) {
        (Some(a), _) => a,
        (None, Some(big_r)) => Arena {
            min: [plan.center[0] - big_r, plan.center[1] - big_r],
            max: [plan.center[0] + big_r, plan.center[1] + big_r],
        },
        (None, None) => {
            return Err(Fail::new(
                Some(g.span()),
                WHAT,
                "kind `random` needs `radius` or an arena",
            ));
        }
    };
    let (lo, hi) = (
        [area.min[0] + r, area.min[1] + r],
        [area.max[0] - r, area.max[1] - r],
    );
    if lo[0] > hi[0] || lo[1] > hi[1] {
        return Err(Fail::new(
            Some(g.span()),
            WHAT,
            format!("robots of radius {r} do not fit in the area"),
        ));
    }
    let gap = 2.0 * r * 1.1;
    let mut rng = Rng(world.seed);
    let mut draw = |taken: &Taken, fixed: &[(P, f64)]| -> Option<P> {
        for _ in 0..2_000 {
            let p = [
                lo[0] + rng.unit() * (hi[0] - lo[0]),
                lo[1] + rng.unit() * (hi[1] - lo[1]),
            ];
            let free = taken.far_from_all(p)
                && fixed
                    .iter()
                    .all(|(q, rq)| (p[0] - q[0]).hypot(p[1] - q[1]) >= (r + rq) * 1.1);
            if free {
                return Some(p);
            }
        }
        None
    };
    let fixed: Vec<(P, f64)> = robots
        .iter()
        .map(|x| (x.start, x.radius))
        .chain(obstacles.iter().map(|o| (o.start, o.radius)))
        .collect();
    let fixed_goals: Vec<(P, f64)> = robots.iter().map(|x| (x.goal, x.radius)).collect();
    let mut starts = Taken::new(gap);
    let mut goals = Taken::new(gap);
    let full = || {
        Fail::new(
            Some(g.span()),
            WHAT,
            format!(
                "could not place {} robots of radius {r} without overlap in [{}, {}]..[{}, {}]",
                plan.names.len(),
                area.min[0],
                area.min[1],
                area.max[0],
                area.max[1]
            ),
        )
    };
    for _ in 0..plan.names.len() {
        let s = draw(&starts, &fixed).ok_or_else(full)?;
        starts.push(s);
        let q = draw(&goals, &fixed_goals).ok_or_else(full)?;
        goals.push(q);
    }
    Ok(starts.order.into_iter().zip(goals.order).collect())
}

/// The points drawn so far, in order and in square cells as wide as
/// `gap`: a point nearer than `gap` to a new one is in the 3 x 3 cells
/// around it, so a draw looks at a few points instead of every earlier
/// one (the same answer: a million robots took minutes scanning them all).
struct Taken {
    gap: f64,
    order: Vec<P>,
    cells: std::collections::HashMap<(i64, i64), Vec<P>>,
}

impl Taken {
    fn new(gap: f64) -> Self {
        Self {
            gap,
            order: Vec::new(),
            cells: Default::default(),
        }
    }

    fn key(&self, p: P) -> (i64, i64) {
        (
            (p[0] / self.gap).floor() as i64,
            (p[1] / self.gap).floor() as i64,
        )
    }

    /// Whether `p` is at least `gap` from every point taken.
    fn far_from_all(&self, p: P) -> bool {
        if !(self.gap > 0.0 && self.gap.is_finite()) {
            // Every distance is at least a gap of zero (or the grid cannot
            // be built): the scan of every point decides.
            return self
                .order
                .iter()
                .all(|q| (p[0] - q[0]).hypot(p[1] - q[1]) >= self.gap);
        }
        let (cx, cy) = self.key(p);
        (-1..=1_i64).all(|dx| {
            (-1..=1_i64).all(|dy| {
                let key = (cx.saturating_add(dx), cy.saturating_add(dy));
                self.cells.get(&key).is_none_or(|qs| {
                    qs.iter()
                        .all(|q| (p[0] - q[0]).hypot(p[1] - q[1]) >= self.gap)
                })
            })
        })
    }

    fn push(&mut self, p: P) {
        self.order.push(p);
        if self.gap > 0.0 && self.gap.is_finite() {
            let key = self.key(p);
            self.cells.entry(key).or_default().push(p);
        }
    }
}
