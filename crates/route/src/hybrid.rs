//! Hybrid A*: routes a car can drive, through walls and static obstacles.
//!
//! D. Dolgov, S. Thrun, M. Montemerlo & J. Diebel, "Path planning for
//! autonomous vehicles in unknown semi-structured environments", IJRR
//! 29(5), 2010 (its section 2, hybrid-state A*), with nav2's Smac
//! Hybrid-A* planner
//! (`nav2_smac_planner`, S. Macenski et al., "Open-source, cost-aware
//! kinematically feasible planning for mobile and surface robotics", 2024)
//! as the reference for the details the paper leaves open.
//!
//! **The search.** A* over cells of the plane (x, y) and of the heading
//! (72 bins by default), each cell holding a continuous pose, the cheapest
//! that has reached it (the paper's hybrid state: a discrete cell with a
//! continuous state of the vehicle in it). A pose is expanded by
//! motion primitives, arcs at the least turning radius R to the left and to
//! the right and a straight, driven forwards and, when the car may reverse,
//! backwards. Each primitive is as long as an arc turning by a whole number
//! of heading bins whose chord leaves the cell (nav2's
//! `HybridMotionTable::initDubins`/`initReedsShepp`: the least multiple of
//! the bin angle whose chord is at least sqrt 2 cells), so every successor
//! lies in another cell and every heading stays the start's plus whole
//! bins. A primitive costs its length, times [`Search::turn_penalty`] for
//! an arc, times [`Search::reverse_penalty`] backwards, plus
//! [`Search::gear_change`] radii where it changes gear (Dolgov et al.
//! penalise driving in reverse and switching the direction of motion;
//! nav2's `non_straight_penalty`, `reverse_penalty`). A cell once expanded
//! is closed.
//!
//! **The heuristics** (section 2) are two, and the larger is used: the
//! *non-holonomic-without-obstacles* cost, the length of the shortest
//! Reeds-Shepp (or, forwards only, Dubins) path to the goal ignoring every
//! obstacle, and the *holonomic-with-obstacles* cost, the shortest distance
//! over the clearance grid from the goal (a Dijkstra search once per route,
//! 16-connected: the 8 neighbours and the knight's moves) through the cells
//! where the car's inscribed disc may fit, ignoring its turning. The second
//! is scaled down by the 16-connected distance's largest excess over the
//! straight line (1 / cos(atan(1/2) / 2) = 1.0275, where the 8-connected
//! one would need 1.082) and less a cell and a half, so that both are lower
//! bounds on the path's length, and so on its cost. When the second finds no way at all, no pose of the car can
//! reach the goal and the route is refused at once.
//!
//! **The analytic expansion** (section 2, its analytic expansions): from
//! every Nth expanded pose, N falling as the pose nears the goal (nav2's
//! `analytic_expansion_ratio`: N = the heuristic over 3.5 cells, at least
//! 1), the shortest Reeds-Shepp or Dubins path to the goal is tried, when
//! it is at most [`Search::shot_range`] radii long; if the car's footprint
//! is clear of everything all along it, it is the route's last leg and the
//! search ends. A goal whose heading may vary is tried at the middle and
//! both ends of its tolerance and halfway to each, and one without a
//! heading at 16 headings and the bearing from the pose (nav2's goal
//! heading modes), the shortest clear one taken.
//!
//! **The goal's point.** A goal may be for another point of the body than
//! the reference point the radius is for, a distance [`Goal::offset`]
//! ahead of it along the heading (a car planned by its rear axle, whose
//! goal is its centre's): every goal pose tried is then the reference
//! point's, `offset` behind the goal's position along that pose's heading,
//! and the holonomic heuristic is lowered by `offset`.
//!
//! **The footprint** is the robot's true shape (a convex polygon or a
//! disc, [`mrsim_shape::Shape`], about the pose's point, which is the point
//! the turning radius is for), checked against the walls and discs in
//! three steps, cheapest first: if the clearance grid says the nearest wall
//! is farther than the shape's circumradius the pose is clear; if it is
//! nearer than its inscribed radius it is not (the inflation of a costmap
//! by the inscribed and circumscribed radii, as nav2's footprint collision
//! checker does); between the two the polygon is tested against the wall
//! segments and discs near it exactly ([`mrsim_shape::gap_to_segment`],
//! [`mrsim_shape::gap`]). The clearance grid's values carry an error of at
//! most a cell (its cells' centres, and its own tenth of a cell), which
//! both fast tests allow for. Obstacles of any other shape are given as
//! their outlines, walls ([`outline`]).
//!
//! **Between poses** the footprint is swept by conservative advancement
//! (B. Mirtich, "Impulse-based dynamic simulation of rigid body systems",
//! PhD thesis, 1996): a footprint whose gap to everything is g moves no
//! point farther than `s (1 + rho / R)` when its reference point drives
//! `s` along an arc (rho the circumradius), so the next pose checked is
//! `g / (1 + rho / R)` on (along a straight, `g` on), and never less than
//! an eighth of a cell. With a [`Search::margin`] of at least
//! `(1 + rho / R)` eighths of a cell every step is the full bound, so the
//! swept footprint is clear all along the path, not only at the poses
//! checked, and those keep the margin.

use crate::drive::{CarPath, Gear, Piece, Steer, wrap};
use crate::grid::{Clearance, Scene};
use crate::search::NEIGHBOURS;
use crate::{Entry, P, dubins, reeds_shepp};
use mrsim_shape::{Pose, Shape};
use std::collections::{BinaryHeap, HashMap};
use std::f64::consts::{PI, SQRT_2, TAU};
use std::hash::{BuildHasherDefault, Hasher};

/// The knight's moves that make the 8 neighbours 16 (the holonomic
/// heuristic's grid).
const KNIGHT: [(i64, i64, f64); 8] = [
    (2, 1, 2.236_067_977_499_79),
    (1, 2, 2.236_067_977_499_79),
    (-1, 2, 2.236_067_977_499_79),
    (-2, 1, 2.236_067_977_499_79),
    (-2, -1, 2.236_067_977_499_79),
    (-1, -2, 2.236_067_977_499_79),
    (1, -2, 2.236_067_977_499_79),
    (2, -1, 2.236_067_977_499_79),
];

/// Why a car has no route.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CarRouteError {
    /// A number of the car, the goal or the search is not usable: a
    /// turning radius, a cell or a penalty that is not finite and > 0 (>= 1
    /// for a penalty), or fewer than 4 heading bins.
    #[error("the car's route cannot be searched: {0}")]
    Bad(String),
    /// The start or the goal lies outside the area the walls span.
    #[error("the {which} [{}, {}] is outside the area the walls span", at[0], at[1])]
    Outside {
        /// `start` or `goal`.
        which: &'static str,
        /// The point.
        at: P,
    },
    /// The car's footprint at the goal overlaps a wall or an obstacle.
    #[error(
        "the car does not fit at its goal [{}, {}] heading {:.1} deg: its footprint \
         reaches {depth:.3} into a wall or an obstacle",
        at[0], at[1], heading.to_degrees()
    )]
    GoalBlocked {
        /// The goal's position.
        at: P,
        /// The goal's heading (rad).
        heading: f64,
        /// How deep the footprint overlaps.
        depth: f64,
    },
    /// The car's footprint at the start overlaps a wall or an obstacle.
    #[error(
        "the car's footprint at its start [{}, {}] reaches {depth:.3} into a wall or an obstacle",
        at[0], at[1]
    )]
    StartBlocked {
        /// The start's position.
        at: P,
        /// How deep the footprint overlaps.
        depth: f64,
    },
    /// No way from the start to the goal is wide enough even for the
    /// footprint's inscribed disc, whatever the turning radius.
    #[error(
        "no way from the start to the goal is wide enough for the car's inscribed disc \
         (radius {inscribed:.3}), however it turns"
    )]
    NoWay {
        /// The footprint's inscribed radius.
        inscribed: f64,
    },
    /// Every pose the car can reach from its start, turning no tighter than
    /// its radius (and forwards only if it may not reverse), was searched
    /// and none reaches the goal: at the search's resolution, one pose a
    /// cell of position and heading, so a way that needs a finer cell than
    /// [`Search::cell`] may exist.
    #[error(
        "the car cannot reach its goal turning no tighter than radius {radius:.3}{}: \
         all {expanded} poses it can reach were searched (one a cell of position and heading)",
        if *reverse { "" } else { " without reversing" }
    )]
    Unreachable {
        /// The turning radius.
        radius: f64,
        /// Whether it could reverse.
        reverse: bool,
        /// Poses expanded.
        expanded: usize,
    },
    /// The search expanded [`Search::max_nodes`] poses without reaching
    /// the goal.
    #[error("no route found within {limit} poses searched (the search's limit)")]
    Effort {
        /// The limit.
        limit: usize,
    },
}

/// A car: its footprint about its reference point, the least radius that
/// point turns on, and whether it may drive backwards.
#[derive(Debug, Clone, Copy)]
pub struct Car {
    /// Footprint in the body frame (x along the heading).
    pub shape: Shape,
    /// Least turning radius of the reference point, > 0
    /// ([`crate::turning_radius`]).
    pub radius: f64,
    /// May it reverse? (Reeds-Shepp steps if so, Dubins steps if not.)
    pub reverse: bool,
}

/// Where a car is to go.
#[derive(Debug, Clone, Copy)]
pub struct Goal {
    /// The goal's position.
    pub position: P,
    /// Its heading (rad), or `None` for any.
    pub heading: Option<f64>,
    /// How far from `heading` the route may end (rad, >= 0).
    pub heading_tolerance: f64,
    /// How far ahead of the reference point, along the heading, lies the
    /// point that must reach `position` (0: the reference point itself).
    /// A car planned by its rear axle whose goal is its centre's: half
    /// its wheelbase ahead. The route then ends with the reference point
    /// at `position` less `offset` along the final heading, whatever that
    /// heading is within the tolerance.
    pub offset: f64,
}

impl Goal {
    /// A goal pose, its heading exact.
    pub fn pose(p: Pose) -> Self {
        Self {
            position: p.position,
            heading: Some(p.heading),
            heading_tolerance: 0.0,
            offset: 0.0,
        }
    }

    /// Where the reference point ends with final heading `h`.
    pub fn reference_at(&self, h: f64) -> P {
        let (s, c) = h.sin_cos();
        [
            self.position[0] - self.offset * c,
            self.position[1] - self.offset * s,
        ]
    }
}

/// The search's settings (module documentation); [`Search::default`] is
/// nav2's defaults where it has them.
#[derive(Debug, Clone, Copy)]
pub struct Search {
    /// Heading bins (nav2: 72, 5 degrees each).
    pub headings: usize,
    /// Size of a search cell; `None`: the clearance grid's cell, but at
    /// least half the arc of one heading bin (so that a car of large
    /// radius is not searched at a finer step than it can steer).
    pub cell: Option<f64>,
    /// Cost factor of an arc over a straight (nav2's
    /// `non_straight_penalty`, 1.2).
    pub turn_penalty: f64,
    /// Cost factor of driving backwards (nav2's `reverse_penalty`, 2.1).
    pub reverse_penalty: f64,
    /// Cost of a change of gear, in turning radii.
    pub gear_change: f64,
    /// The least gap kept between the footprint and everything, at every
    /// pose checked (>= 0; lowered to the start's and the goal's own gap
    /// when they have less).
    pub margin: f64,
    /// The longest analytic expansion tried, in turning radii.
    pub shot_range: f64,
    /// The most poses expanded before [`CarRouteError::Effort`].
    pub max_nodes: usize,
}

impl Default for Search {
    fn default() -> Self {
        Self {
            headings: 72,
            cell: None,
            turn_penalty: 1.2,
            reverse_penalty: 2.1,
            gear_change: 1.0,
            margin: 0.0,
            shot_range: 8.0,
            max_nodes: 200_000,
        }
    }
}

/// A route a car can drive, and what the search took.
#[derive(Debug, Clone)]
pub struct CarRoute {
    /// The path: from the start to the goal (within its heading
    /// tolerance), arcs of the car's radius and straights.
    pub path: CarPath,
    /// Poses expanded.
    pub expanded: usize,
    /// Its cost (its length with the search's penalties).
    pub cost: f64,
}

/// The outline of a posed convex shape as wall segments (none for a disc:
/// give a disc as a disc).
pub fn outline(shape: &Shape, pose: Pose) -> Vec<[P; 2]> {
    match shape.placed(pose) {
        None => Vec::new(),
        Some(pl) => {
            let pts = pl.points();
            (0..pts.len())
                .map(|i| [pts[i], pts[(i + 1) % pts.len()]])
                .collect()
        }
    }
}

/// What a car's route goes around: the clearance grid, and the walls and
/// discs themselves in buckets for the exact test.
#[derive(Debug, Clone)]
pub struct CarMap {
    grid: Clearance,
    walls: Vec<[P; 2]>,
    discs: Vec<(P, f64)>,
    /// Bucket size, origin and counts across and up.
    bucket: f64,
    origin: P,
    bw: usize,
    bh: usize,
    /// Per bucket: walls (index) and discs (index + walls.len()).
    buckets: Vec<Vec<u32>>,
}

impl CarMap {
    /// Builds the clearance grid and the buckets over `scene` (its `pad`
    /// should be at least the largest footprint's circumradius, so that a
    /// route can go round a wall's free end).
    pub fn build(scene: &Scene) -> Self {
        let grid = Clearance::build(scene);
        let bucket = grid.res * 16.0;
        let origin = grid.origin;
        let bw = ((grid.w as f64 * grid.res) / bucket).ceil().max(1.0) as usize;
        let bh = ((grid.h as f64 * grid.res) / bucket).ceil().max(1.0) as usize;
        let mut buckets = vec![Vec::new(); bw * bh];
        let range = |lo: f64, hi: f64, o: f64, n: usize| {
            let a = ((lo - o) / bucket).floor().max(0.0) as usize;
            let b = (((hi - o) / bucket).floor().max(0.0) as usize).min(n - 1);
            a.min(n - 1)..=b
        };
        let mut put = |lo: P, hi: P, id: u32| {
            for j in range(lo[1], hi[1], origin[1], bh) {
                for i in range(lo[0], hi[0], origin[0], bw) {
                    buckets[j * bw + i].push(id);
                }
            }
        };
        for (k, s) in scene.walls.iter().enumerate() {
            let lo = [s[0][0].min(s[1][0]), s[0][1].min(s[1][1])];
            let hi = [s[0][0].max(s[1][0]), s[0][1].max(s[1][1])];
            put(lo, hi, k as u32);
        }
        for (k, &(c, r)) in scene.discs.iter().enumerate() {
            put(
                [c[0] - r, c[1] - r],
                [c[0] + r, c[1] + r],
                (scene.walls.len() + k) as u32,
            );
        }
        Self {
            grid,
            walls: scene.walls.to_vec(),
            discs: scene.discs.to_vec(),
            bucket,
            origin,
            bw,
            bh,
            buckets,
        }
    }

    /// The clearance grid (the same as [`Clearance::build`] of the scene).
    pub fn clearance(&self) -> &Clearance {
        &self.grid
    }

    /// A lower bound on the signed gap between the footprint at `pose` and
    /// every wall and disc (module documentation, "The footprint"): the
    /// grid's bound when that is at least `reach`, a negative number when
    /// the grid shows a wall inside the inscribed disc, else the exact gap
    /// to what lies within `reach` (at most `reach`); `-inf` outside the
    /// grid.
    fn gap(&self, f: &Footprint, pose: Pose, reach: f64) -> f64 {
        let Some((i, j)) = self.grid.cell(pose.position) else {
            return f64::NEG_INFINITY;
        };
        let c = self.grid.c[j * self.grid.w + i];
        let err = self.grid.res;
        let lower = c - err - f.circum;
        if lower >= reach {
            return lower;
        }
        if c + err < f.inscribed {
            return c + err - f.inscribed;
        }
        self.exact(f, pose, reach)
    }

    /// The exact gap to the walls and discs within `reach` of the
    /// footprint (`reach` if none is).
    fn exact(&self, f: &Footprint, pose: Pose, reach: f64) -> f64 {
        let p = pose.position;
        let r = f.circum + reach;
        let span = |v: f64, o: f64, n: usize| {
            let a = ((v - r - o) / self.bucket).floor();
            let b = ((v + r - o) / self.bucket).floor();
            let a = a.clamp(0.0, (n - 1) as f64) as usize;
            let b = b.clamp(0.0, (n - 1) as f64) as usize;
            a..=b
        };
        let mut g = reach;
        for j in span(p[1], self.origin[1], self.bh) {
            for i in span(p[0], self.origin[0], self.bw) {
                for &id in &self.buckets[j * self.bw + i] {
                    let id = id as usize;
                    let d = if id < self.walls.len() {
                        mrsim_shape::gap_to_segment(&f.shape, pose, self.walls[id])
                    } else {
                        let (c, rad) = self.discs[id - self.walls.len()];
                        mrsim_shape::gap(&f.shape, pose, &Shape::disc(rad), Pose::new(c, 0.0))
                    };
                    g = g.min(d);
                }
            }
        }
        g
    }

    /// The exact signed gap between `shape` at `pose` and every wall and
    /// disc (`f64::INFINITY` if there are none): what the tests and a
    /// caller checking a path use.
    pub fn gap_at(&self, shape: &Shape, pose: Pose) -> f64 {
        let mut g = f64::INFINITY;
        for s in &self.walls {
            g = g.min(mrsim_shape::gap_to_segment(shape, pose, *s));
        }
        for &(c, r) in &self.discs {
            g = g.min(mrsim_shape::gap(
                shape,
                pose,
                &Shape::disc(r),
                Pose::new(c, 0.0),
            ));
        }
        g
    }

    /// The shortest route for `car` from `start` to `goal` (module
    /// documentation). The path starts at `start` and ends at the goal's
    /// position with a heading within its tolerance.
    pub fn route(
        &self,
        car: &Car,
        start: Pose,
        goal: &Goal,
        search: &Search,
    ) -> Result<CarRoute, CarRouteError> {
        Planner::new(self, car, start, goal, search)?.run()
    }
}

/// A footprint and its two radii.
#[derive(Debug, Clone, Copy)]
struct Footprint {
    shape: Shape,
    circum: f64,
    inscribed: f64,
}

/// A hasher for the cells' keys (already well spread u64s).
#[derive(Default)]
struct Mix(u64);

impl Hasher for Mix {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 29)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// A searched pose.
#[derive(Debug, Clone, Copy)]
struct Node {
    pose: Pose,
    g: f64,
    /// Its gap to everything (a lower bound).
    gap: f64,
    parent: u32,
    /// The primitive that reached it.
    piece: Piece,
    key: u64,
}

/// One cell's state: the cheapest node so far, and whether expanded.
#[derive(Debug, Clone, Copy)]
struct CellState {
    g: f64,
    closed: bool,
}

struct Planner<'a> {
    map: &'a CarMap,
    foot: Footprint,
    radius: f64,
    reverse: bool,
    start: Pose,
    goal: Goal,
    search: Search,
    /// Goal headings tried by the analytic expansion (empty: any heading).
    headings: Vec<f64>,
    /// How much shorter than the Reeds-Shepp/Dubins length to the goal's
    /// middle heading a path to another allowed heading may be.
    slack: f64,
    cell: f64,
    bin: f64,
    step: f64,
    need: f64,
    /// Holonomic distance to the goal per grid cell.
    holo: Vec<f32>,
}

impl<'a> Planner<'a> {
    fn new(
        map: &'a CarMap,
        car: &Car,
        start: Pose,
        goal: &Goal,
        search: &Search,
    ) -> Result<Self, CarRouteError> {
        let bad = |what: &str| Err(CarRouteError::Bad(what.to_string()));
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(car.radius) {
            return bad(&format!("turning radius {} (must be > 0)", car.radius));
        }
        if search.headings < 4 {
            return bad(&format!("{} heading bins (at least 4)", search.headings));
        }
        if search.cell.is_some_and(|c| !pos(c)) {
            return bad("the search's cell (must be > 0)");
        }
        for (name, v) in [
            ("turn_penalty", search.turn_penalty),
            ("reverse_penalty", search.reverse_penalty),
        ] {
            if !(v.is_finite() && v >= 1.0) {
                return bad(&format!("{name} {v} (must be >= 1)"));
            }
        }
        let at_least_0 = |v: f64| v.is_finite() && v >= 0.0;
        if ![search.gear_change, search.margin, search.shot_range]
            .into_iter()
            .all(at_least_0)
        {
            return bad("gear_change, margin and shot_range must be finite and >= 0");
        }
        let finite = |p: P| p[0].is_finite() && p[1].is_finite();
        let usable = finite(start.position)
            && start.heading.is_finite()
            && finite(goal.position)
            && goal.heading.is_none_or(f64::is_finite)
            && at_least_0(goal.heading_tolerance)
            && at_least_0(goal.offset);
        if !usable {
            return bad("the start and the goal must be finite");
        }
        let grid = &map.grid;
        let sc = grid.cell(start.position).ok_or(CarRouteError::Outside {
            which: "start",
            at: start.position,
        })?;
        let gc = grid.cell(goal.position).ok_or(CarRouteError::Outside {
            which: "goal",
            at: goal.position,
        })?;
        let foot = Footprint {
            shape: car.shape,
            circum: car.shape.circumradius(),
            inscribed: car.shape.inradius(),
        };
        let tol = goal.heading_tolerance.min(PI);
        let headings = match goal.heading {
            None => Vec::new(),
            Some(h) if tol >= PI => (0..16).map(|k| h + TAU * k as f64 / 16.0).collect(),
            Some(h) if tol > 0.0 => vec![h, h - tol / 2.0, h + tol / 2.0, h - tol, h + tol],
            Some(h) => vec![h],
        };
        let r = car.radius;
        let slack = match goal.heading {
            Some(_) if tol > 0.0 && tol < PI => {
                let o = Pose::new([0.0, 0.0], 0.0);
                let turn = Pose::new([0.0, 0.0], tol);
                if car.reverse {
                    reeds_shepp::length(o, turn, r)
                } else {
                    // A forward loop back onto the middle heading.
                    dubins::length(o, turn, r).min(dubins::length(turn, o, r))
                }
            }
            _ => 0.0,
        };
        let bin = TAU / search.headings as f64;
        let cell = search.cell.unwrap_or(grid.res.max(0.5 * r * bin));
        let chord = (SQRT_2 * cell / (2.0 * r)).min(1.0).asin() * 2.0;
        let k = (chord / bin).ceil().max(1.0);
        let step = r * k * bin;
        let mut me = Self {
            map,
            foot,
            radius: r,
            reverse: car.reverse,
            start,
            goal: *goal,
            search: *search,
            headings,
            slack,
            cell,
            bin,
            step,
            need: search.margin,
            holo: Vec::new(),
        };
        // The goal and the start must fit; the margin is lowered to what
        // they have.
        let reach = search.margin + grid.res;
        let gs = map
            .exact(&foot, start, reach)
            .min(me.map.gap(&foot, start, reach));
        if gs < 0.0 {
            return Err(CarRouteError::StartBlocked {
                at: start.position,
                depth: -gs,
            });
        }
        me.need = me.need.min(gs);
        if let Some(h) = goal.heading {
            let gp = Pose::new(goal.reference_at(h), h);
            let gg = map.exact(&foot, gp, reach).min(map.gap(&foot, gp, reach));
            if gg < 0.0 && tol == 0.0 {
                return Err(CarRouteError::GoalBlocked {
                    at: goal.position,
                    heading: h,
                    depth: -gg,
                });
            }
            me.need = me.need.min(gg.max(0.0));
        }
        me.holo = me.holonomic(gc);
        let sk = sc.1 * grid.w + sc.0;
        if !me.holo[sk].is_finite() {
            return Err(CarRouteError::NoWay {
                inscribed: foot.inscribed,
            });
        }
        Ok(me)
    }

    /// Dijkstra from the goal's cell over the grid's cells where the
    /// inscribed disc may fit (module documentation).
    fn holonomic(&self, goal: (usize, usize)) -> Vec<f32> {
        let grid = &self.map.grid;
        let (w, h) = (grid.w, grid.h);
        let open_cell = |k: usize| grid.c[k] + grid.res >= self.foot.inscribed;
        let mut d = vec![f64::INFINITY; w * h];
        let gk = goal.1 * w + goal.0;
        let mut heap = BinaryHeap::new();
        d[gk] = 0.0;
        heap.push(Entry { key: 0.0, cell: gk });
        while let Some(Entry { key, cell }) = heap.pop() {
            if key > d[cell] {
                continue;
            }
            let (i, j) = ((cell % w) as i64, (cell / w) as i64);
            for (di, dj, len) in NEIGHBOURS.into_iter().chain(KNIGHT) {
                let (ni, nj) = (i + di, j + dj);
                if ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                    continue;
                }
                let n = nj as usize * w + ni as usize;
                if !open_cell(n) {
                    continue;
                }
                let next = key + len * grid.res;
                if next < d[n] {
                    d[n] = next;
                    heap.push(Entry { key: next, cell: n });
                }
            }
        }
        // The 16-connected distance's largest excess over the straight
        // line: halfway between two of its directions, 1 / cos(atan(1/2) / 2).
        let excess = 1.0 / (0.5f64.atan() / 2.0).cos();
        d.into_iter()
            .map(|v| {
                if v.is_finite() {
                    (v / excess - 1.5 * grid.res).max(0.0) as f32
                } else {
                    f32::INFINITY
                }
            })
            .collect()
    }

    /// The length of the shortest obstacle-free path (Reeds-Shepp or
    /// Dubins) from `p` to the goal pose with heading `h`.
    fn analytic_length(&self, p: Pose, h: f64) -> f64 {
        let g = Pose::new(self.goal.reference_at(h), h);
        if self.reverse {
            reeds_shepp::length(p, g, self.radius)
        } else {
            dubins::length(p, g, self.radius)
        }
    }

    fn analytic(&self, p: Pose, h: f64) -> CarPath {
        let g = Pose::new(self.goal.reference_at(h), h);
        if self.reverse {
            reeds_shepp::shortest(p, g, self.radius)
        } else {
            dubins::shortest(p, g, self.radius)
        }
    }

    /// The heuristic (module documentation): infinite where the goal
    /// cannot be reached even holonomically.
    fn heuristic(&self, p: Pose) -> f64 {
        let grid = &self.map.grid;
        let Some((i, j)) = grid.cell(p.position) else {
            return f64::INFINITY;
        };
        // The reference point ends within `offset` of the goal's
        // position, from which the holonomic distance is measured.
        let holo = (f64::from(self.holo[j * grid.w + i]) - self.goal.offset).max(0.0);
        let non = match (self.goal.heading, self.headings.len()) {
            (Some(h), 1..=5) => (self.analytic_length(p, h) - self.slack).max(0.0),
            _ => 0.0,
        };
        holo.max(non)
    }

    /// The cell key of a pose inside the grid.
    fn key(&self, p: Pose) -> Option<u64> {
        let grid = &self.map.grid;
        let x = (p.position[0] - grid.origin[0]) / self.cell;
        let y = (p.position[1] - grid.origin[1]) / self.cell;
        let (wx, wy) = (
            grid.w as f64 * grid.res / self.cell,
            grid.h as f64 * grid.res / self.cell,
        );
        if !(x >= 0.0 && y >= 0.0 && x < wx && y < wy) {
            return None;
        }
        let n = self.search.headings as f64;
        let k = ((wrap(p.heading) / self.bin).round().rem_euclid(n)) as u64;
        Some(((k << 21 | y as u64) << 21) | x as u64)
    }

    /// Drives `piece` from `from` (whose gap is `gap`), checking the swept
    /// footprint (module documentation): the end pose and its gap, or
    /// `None` if the footprint comes nearer than the margin.
    fn sweep(&self, from: Pose, gap: f64, piece: Piece) -> Option<(Pose, f64)> {
        let total = piece.length.abs();
        let sign = piece.length.signum();
        let spread = match piece.steer {
            Steer::Straight => 1.0,
            _ => 1.0 + self.foot.circum / self.radius,
        };
        let least = self.map.grid.res / 8.0;
        let reach = self.need + self.map.grid.res + total * spread;
        let (mut done, mut g) = (0.0, gap);
        loop {
            let room = g / spread;
            if done + room >= total {
                let end = piece.advance(from, piece.length, self.radius);
                let ge = if done == total {
                    g
                } else {
                    self.map.gap(&self.foot, end, reach)
                };
                return (ge >= self.need).then_some((end, ge));
            }
            done = (done + room.max(least)).min(total);
            let at = piece.advance(from, sign * done, self.radius);
            g = self.map.gap(&self.foot, at, reach);
            if g < self.need {
                return None;
            }
        }
    }

    /// Sweeps a whole path from `from` (gap `gap`): is it clear?
    fn clear(&self, path: &CarPath, gap: f64) -> bool {
        let mut at = path.start();
        let mut g = gap;
        for &p in path.pieces() {
            match self.sweep(at, g, p) {
                Some((e, ge)) => (at, g) = (e, ge),
                None => return false,
            }
        }
        true
    }

    /// The analytic expansion from `p`: the shortest clear Reeds-Shepp or
    /// Dubins path to an allowed goal pose, if one is short enough.
    fn shot(&self, p: Pose, gap: f64) -> Option<CarPath> {
        let range = self.search.shot_range * self.radius;
        let mut tries: Vec<(f64, f64)> = if self.headings.is_empty() {
            let d = [
                self.goal.position[0] - p.position[0],
                self.goal.position[1] - p.position[1],
            ];
            let mut hs: Vec<f64> = (0..16).map(|k| TAU * k as f64 / 16.0).collect();
            hs.push(d[1].atan2(d[0]));
            hs.into_iter()
                .map(|h| (self.analytic_length(p, h), h))
                .collect()
        } else {
            self.headings
                .iter()
                .map(|&h| (self.analytic_length(p, h), h))
                .collect()
        };
        tries.retain(|t| t.0 <= range);
        tries.sort_by(|a, b| a.0.total_cmp(&b.0));
        tries
            .into_iter()
            .take(3)
            .map(|(_, h)| self.analytic(p, h))
            .find(|path| self.clear(path, gap))
    }

    /// The cost of driving `piece` after arriving in gear `before`.
    fn cost(&self, piece: Piece, before: Option<Gear>) -> f64 {
        let mut c = piece.length.abs();
        if piece.steer != Steer::Straight {
            c *= self.search.turn_penalty;
        }
        if piece.gear() == Gear::Reverse {
            c *= self.search.reverse_penalty;
        }
        if before.is_some_and(|g| g != piece.gear()) {
            c += self.search.gear_change * self.radius;
        }
        c
    }

    fn path_cost(&self, path: &CarPath, mut before: Option<Gear>) -> f64 {
        let mut c = 0.0;
        for &p in path.pieces() {
            c += self.cost(p, before);
            before = Some(p.gear());
        }
        c
    }

    /// Is pose `p` at the goal (within the goal's tolerance)?
    fn at_goal(&self, p: Pose) -> bool {
        crate::dist(p.position, self.goal.reference_at(p.heading)) <= 1e-9
            && self
                .goal
                .heading
                .is_none_or(|h| wrap(p.heading - h).abs() <= self.goal.heading_tolerance + 1e-9)
    }

    fn run(self) -> Result<CarRoute, CarRouteError> {
        let mut prims = Vec::new();
        let gears: &[f64] = if self.reverse { &[1.0, -1.0] } else { &[1.0] };
        for &g in gears {
            for steer in [Steer::Straight, Steer::Left, Steer::Right] {
                prims.push(Piece {
                    steer,
                    length: g * self.step,
                });
            }
        }
        let reach = self.need + self.map.grid.res;
        let gap0 = self.map.gap(&self.foot, self.start, reach);
        let key0 = self.key(self.start).ok_or(CarRouteError::Outside {
            which: "start",
            at: self.start.position,
        })?;
        let mut nodes = vec![Node {
            pose: self.start,
            g: 0.0,
            gap: gap0,
            parent: u32::MAX,
            piece: Piece {
                steer: Steer::Straight,
                length: 0.0,
            },
            key: key0,
        }];
        let mut cells: HashMap<u64, CellState, BuildHasherDefault<Mix>> = HashMap::default();
        cells.insert(
            key0,
            CellState {
                g: 0.0,
                closed: false,
            },
        );
        let mut open = BinaryHeap::new();
        open.push(Entry {
            key: self.heuristic(self.start),
            cell: 0,
        });
        let mut expanded = 0usize;
        let mut since_shot = usize::MAX;
        while let Some(Entry { cell: idx, .. }) = open.pop() {
            let node = nodes[idx];
            let Some(st) = cells.get_mut(&node.key) else {
                continue;
            };
            if st.closed || node.g > st.g + 1e-9 {
                continue;
            }
            st.closed = true;
            expanded += 1;
            if expanded > self.search.max_nodes {
                return Err(CarRouteError::Effort {
                    limit: self.search.max_nodes,
                });
            }
            let before = (node.parent != u32::MAX).then(|| node.piece.gear());
            if self.at_goal(node.pose) {
                return Ok(self.finish(&nodes, idx, None, node.g, expanded));
            }
            let h = self.heuristic(node.pose);
            let period = ((h / (3.5 * self.cell)).floor() as usize).max(1);
            since_shot = since_shot.saturating_add(1);
            if since_shot >= period {
                since_shot = 0;
                if let Some(shot) = self.shot(node.pose, node.gap) {
                    let c = node.g + self.path_cost(&shot, before);
                    return Ok(self.finish(&nodes, idx, Some(shot), c, expanded));
                }
            }
            for &prim in &prims {
                let end = prim.advance(node.pose, prim.length, self.radius);
                let Some(key) = self.key(end) else {
                    continue;
                };
                if key == node.key {
                    continue;
                }
                let g = node.g + self.cost(prim, before);
                if cells.get(&key).is_some_and(|s| s.closed || s.g <= g) {
                    continue;
                }
                let Some((end, gap)) = self.sweep(node.pose, node.gap, prim) else {
                    continue;
                };
                let hn = self.heuristic(end);
                if !hn.is_finite() {
                    continue;
                }
                cells.insert(key, CellState { g, closed: false });
                nodes.push(Node {
                    pose: end,
                    g,
                    gap,
                    parent: idx as u32,
                    piece: prim,
                    key,
                });
                open.push(Entry {
                    key: g + hn,
                    cell: nodes.len() - 1,
                });
            }
        }
        Err(CarRouteError::Unreachable {
            radius: self.radius,
            reverse: self.reverse,
            expanded,
        })
    }

    /// The route to node `idx`, then `shot` if any.
    fn finish(
        &self,
        nodes: &[Node],
        idx: usize,
        shot: Option<CarPath>,
        cost: f64,
        expanded: usize,
    ) -> CarRoute {
        let mut pieces = Vec::new();
        let mut k = idx;
        while nodes[k].parent != u32::MAX {
            pieces.push(nodes[k].piece);
            k = nodes[k].parent as usize;
        }
        pieces.reverse();
        if let Some(s) = shot {
            pieces.extend_from_slice(s.pieces());
        }
        CarRoute {
            path: CarPath::new(self.start, self.radius, pieces),
            expanded,
            cost,
        }
    }
}
