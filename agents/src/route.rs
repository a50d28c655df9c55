//! `route = "shortest"`: the planner is steered along the shortest way the
//! robot's disc fits through the run's walls and static obstacles
//! (`mrsim-route`), computed once when the planner is built.
//!
//! [`Routed`] wraps the robot's planner (outside the look-ahead controller
//! of a unicycle, so that progress is the centre's): each tick it projects
//! the robot onto its route and shows the planner, as its goal, the route's
//! point [`ahead`] further on (the real goal, with the real tolerance, once
//! that is within reach); the planner itself is unchanged and sees only a
//! nearer goal. When the robot has not advanced along its route for
//! [`PATIENCE`] s it plans again from where it stands, with the bodies it
//! senses standing (slower than a tenth of its top speed) within reach as
//! obstacles, or without them if they leave no way.
//!
//! The route keeps the centre [`margin`] more than the radius from walls
//! wherever the map leaves room (one more radius: the local planners' own
//! clearance needs room to work in, and a route grazing a corner at the
//! bare radius leaves none). The waypoint shown is pulled back along the
//! route, if need be, until the robot's disc (grown by half the margin)
//! reaches it in a straight line, so that it never lies round a corner. The grid is the map's own cells when the
//! scenario has a `[map]`, else half the radius.

use mrsim_planners::{Command, Diagnostic, Observation, Planner, Segment, Vec2};
use mrsim_route::{Clearance, Follower, P, Path, RouteError, Scene, Side};
use mrsim_scenario::{Lane, Motion, ObstacleSpec, RobotSpec, Scenario};

/// Seconds without progress along the route before it is planned again.
pub const PATIENCE: f64 = 8.0;

/// Extra clearance a route keeps over the radius where it can.
pub fn margin(spec: &RobotSpec) -> f64 {
    spec.radius
}

/// How far sideways a route with a `lane` is moved at most, where the
/// walls leave room: a radius and half the [`margin`] (one and a half
/// radii), so that two robots in opposite lanes of a corridor pass with
/// their discs half a radius apart, more than the local planners' own
/// padding.
pub fn lane_offset(spec: &RobotSpec) -> f64 {
    spec.radius + margin(spec) / 2.0
}

/// The side robot `spec`'s route keeps to, if any.
fn side(spec: &RobotSpec) -> Option<Side> {
    match spec.lane {
        Lane::None => None,
        Lane::Right => Some(Side::Right),
        Lane::Left => Some(Side::Left),
    }
}

/// `path` moved into robot `spec`'s lane, if it keeps to one.
fn in_lane(grid: &Clearance, path: Path, spec: &RobotSpec) -> Path {
    match side(spec) {
        Some(side) => grid.keep_to(
            &path,
            side,
            lane_offset(spec),
            spec.radius + margin(spec),
            spec.radius,
        ),
        None => path,
    }
}

/// How far along the route, beyond the robot's progress, its planner's
/// goal is: two seconds at top speed, and at least four radii (so that
/// the goal is out of the robot's own footprint and braking distance).
pub fn ahead(spec: &RobotSpec) -> f64 {
    (2.0 * spec.max_speed).max(4.0 * spec.radius)
}

/// What routes go around: the run's walls (the map's outlines, `[[wall]]`s
/// and the arena) and its static obstacles, and the grid's cell size.
#[derive(Debug, Clone)]
pub struct RouteScene {
    walls: Vec<[P; 2]>,
    discs: Vec<(P, f64)>,
    resolution: Option<f64>,
}

impl RouteScene {
    /// The routes' scene of a resolved scenario.
    pub fn of(scenario: &Scenario) -> Self {
        let walls = mrsim_scenario::walls_and_arena(&scenario.walls, scenario.world.arena);
        let res = scenario
            .map
            .as_ref()
            .map(|m| m.resolution * scenario.length_unit.per_metre());
        Self::new(&walls, &scenario.obstacles, res)
    }

    /// From walls, the scenario's obstacles (only the static ones count)
    /// and a map's cell size in scenario units, if any.
    pub fn new(walls: &[[P; 2]], obstacles: &[ObstacleSpec], map_resolution: Option<f64>) -> Self {
        Self {
            walls: walls.to_vec(),
            discs: obstacles
                .iter()
                .filter(|o| matches!(o.motion, Motion::Static))
                .map(|o| (o.start, o.radius))
                .collect(),
            resolution: map_resolution,
        }
    }

    /// From the walls planners see.
    pub(crate) fn from_segments(
        walls: &[Segment],
        obstacles: &[ObstacleSpec],
        map_resolution: Option<f64>,
    ) -> Self {
        let walls: Vec<[P; 2]> = walls
            .iter()
            .map(|w| [[w.a.x, w.a.y], [w.b.x, w.b.y]])
            .collect();
        Self::new(&walls, obstacles, map_resolution)
    }

    /// The clearance grid for robot `spec` and its route from start to
    /// goal.
    pub fn route(&self, spec: &RobotSpec) -> Result<(Clearance, Path), RouteError> {
        let res = self.resolution.unwrap_or_else(|| {
            if spec.radius > 0.0 {
                spec.radius / 2.0
            } else {
                // A point robot: a 400th of the walls' extent.
                let span = self
                    .walls
                    .iter()
                    .flatten()
                    .chain([&spec.start, &spec.goal])
                    .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], p| {
                        [lo.min(p[0]).min(p[1]), hi.max(p[0]).max(p[1])]
                    });
                ((span[1] - span[0]) / 400.0).max(f64::MIN_POSITIVE)
            }
        });
        let grid = Clearance::build(&Scene {
            walls: &self.walls,
            discs: &self.discs,
            points: &[spec.start, spec.goal],
            resolution: res,
            pad: 2.0 * (spec.radius + margin(spec)),
        });
        let path = grid.route(spec.start, spec.goal, spec.radius, margin(spec), &[])?;
        let path = in_lane(&grid, path, spec);
        Ok((grid, path))
    }
}

/// `planner` as robot `spec` drives with it: steered along its route on
/// `scene` when its `route` is `shortest` ([`Routed`]), else unchanged.
pub fn fit_route(
    planner: Box<dyn Planner>,
    spec: &RobotSpec,
    scene: &RouteScene,
) -> Result<Box<dyn Planner>, RouteError> {
    if spec.route != mrsim_scenario::Route::Shortest {
        return Ok(planner);
    }
    let (grid, path) = scene.route(spec)?;
    Ok(Box::new(Routed::new(planner, spec, grid, path)))
}

/// A planner steered along its robot's route (module documentation).
pub struct Routed {
    inner: Box<dyn Planner>,
    spec: RobotSpec,
    grid: Clearance,
    follower: Follower,
    goal: P,
    radius: f64,
    margin: f64,
    ahead: f64,
    reach: f64,
    slow: f64,
    replans: u32,
}

impl Routed {
    /// Wraps `inner` for robot `spec` along `path` on `grid`.
    pub fn new(inner: Box<dyn Planner>, spec: &RobotSpec, grid: Clearance, path: Path) -> Self {
        let ahead = ahead(spec);
        Self {
            inner,
            spec: spec.clone(),
            grid,
            follower: Follower::new(path, ahead, PATIENCE),
            goal: spec.goal,
            radius: spec.radius,
            margin: margin(spec),
            ahead,
            reach: 2.0 * ahead,
            slow: spec.max_speed / 10.0,
            replans: 0,
        }
    }

    /// Plans again from `p`, around the standing bodies within reach.
    fn replan(&mut self, obs: &Observation, p: P) {
        let blocked: Vec<(P, f64)> = obs
            .others
            .iter()
            .filter(|o| {
                (o.position - obs.me.position).norm() <= self.reach + o.radius
                    && o.velocity.norm() < self.slow
            })
            .map(|o| ([o.position.x, o.position.y], o.radius))
            .collect();
        let path = self
            .grid
            .route(p, self.goal, self.radius, self.margin, &blocked)
            .or_else(|_| self.grid.route(p, self.goal, self.radius, self.margin, &[]));
        if let Ok(path) = path {
            let path = in_lane(&self.grid, path, &self.spec);
            self.follower.replace(path, obs.time);
            self.replans += 1;
        }
    }
}

impl Planner for Routed {
    fn plan(&mut self, obs: &Observation) -> Command {
        let p = [obs.me.position.x, obs.me.position.y];
        if self.follower.stuck(obs.time) {
            self.replan(obs, p);
        }
        let far = self.follower.waypoint(p, obs.time);
        // Round a corner: the furthest point up to the waypoint, and at
        // least a quarter of the way there, that the disc (grown by half
        // the margin) reaches in a straight line; the waypoint itself if
        // none is.
        let need = self.radius + self.margin / 2.0;
        let (s0, step) = (self.follower.progress(), self.grid.resolution());
        let mut s = s0 + self.ahead;
        let mut w = far;
        while !self.grid.sees(p, w, need) {
            s -= step;
            if s < s0 + self.ahead / 4.0 {
                w = far;
                break;
            }
            w = self.follower.at(s);
        }
        let mut seen = *obs;
        seen.goal = Vec2::new(w[0], w[1]);
        self.inner.plan(&seen)
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut d = self.inner.diagnostics();
        d.push(Diagnostic {
            name: "route_progress".into(),
            value: self.follower.progress(),
        });
        d.push(Diagnostic {
            name: "route_replans".into(),
            value: f64::from(self.replans),
        });
        d
    }

    fn native_unicycle(&self) -> bool {
        self.inner.native_unicycle()
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }
}
