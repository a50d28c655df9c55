//! `route = "shortest"`: the planner is steered along the shortest way the
//! robot's disc fits through the run's walls and static obstacles
//! (`mrsim-route`), computed once when the planner is built.
//! A car's (`kinematics = "ackermann"`) is a route it can drive, which it
//! follows itself ([`crate::car_route`]).
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
//!
//! **Giving way.** Two robots meeting head-on in a passage wide enough for
//! one (a door, a corridor narrowed by pillars) stop face to face, each
//! waiting for the other: a deadlock no local planner on its own resolves.
//! Routed robots give way, by a rule each applies to what it senses,
//! without communication, the way traffic and multi-robot navigation
//! stacks resolve it (one of the two, chosen by a fixed priority, backs
//! off into a free place and waits). A robot that has stood still (within
//! a quarter of [`ahead`]) for [`YIELD_AFTER`] s with another robot in its
//! way (nearer to its route ahead, up to twice [`ahead`] on, than both
//! radii and half the [`margin`], and not moving away from it faster than
//! a tenth of its top speed) gives way if that robot's id is the higher;
//! after [`YIELD_ESCALATE`] s it gives way to a standing robot in its way
//! whatever the ids (the other, which should have, could not), so the rule
//! never leaves both waiting. Both see the same ids, so only one of two
//! robots stopped face to face gives way first. To give way it goes to the
//! nearest place, by the way there (up to four times [`ahead`], around
//! the bodies it senses), with room for its disc and a quarter of the
//! margin, at least both radii and half the margin from the other's
//! presumed way: the line from the other through this robot and on back
//! along this robot's route (where it came from, where the other is
//! going). It waits there until the other is no longer in its way ahead,
//! or for [`YIELD_WAIT`] s at most, then plans its route again from where
//! it stands. A robot that finds no such place does not give way (and
//! looks again a second later): the other's escalation then does. The
//! diagnostic `route_yield` is 1 while the robot gives way (`route_yields`
//! counts the times). A planner that avoids from its laser scan alone has
//! no other robot's id or state, so its robot does not give way.
//!
//! **Narrow passages.** The route's stretches too narrow for two of the
//! robot side by side (doors) are marked whenever it is planned; a
//! unicycle whose planner plans its (v, omega) itself (dwa) takes them in
//! turn with the robots coming the other way, holding short of them, and
//! backs off from a robot or a wall it stands nose to nose with
//! ([`crate::passage`]).

use crate::passage::{self, Stretch};
use mrsim_planners::{BodyKind, Command, Diagnostic, Observation, Planner, Segment, Sensed, Vec2};
use mrsim_route::{
    CarRouteError, Clearance, Follower, P, Path, Refuge, RouteError, Scene, Side, to_way,
};
use mrsim_scenario::{Kinematics, Lane, Motion, ObstacleSpec, RobotSpec, Scenario};
use mrsim_shape::{Pose, Shape};

/// Seconds without progress along the route before it is planned again.
pub const PATIENCE: f64 = 8.0;

/// Seconds a robot stands (within a quarter of [`ahead`] of where it
/// stood) with another robot in its way before it yields to it, when the
/// other's id is the higher.
pub const YIELD_AFTER: f64 = 3.0;

/// Seconds a robot stands with another robot in its way before it yields
/// whatever their ids (the other, which should have yielded, could not).
pub const YIELD_ESCALATE: f64 = 3.0 * YIELD_AFTER;

/// Seconds a robot stands face to face with another before it backs off.
pub const BACK_AFTER: f64 = 4.0;

/// How long it backs off, s.
pub const BACK_FOR: f64 = 2.0;

/// How fast it backs off, m/s.
pub const BACK_SPEED: f64 = 0.2;

/// Seconds a yielding robot waits at most before it routes again.
pub const YIELD_WAIT: f64 = 2.0 * PATIENCE;

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
    /// Every static obstacle's shape and pose (cars' routes go round
    /// their true shapes).
    statics: Vec<(Shape, Pose)>,
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
            statics: obstacles
                .iter()
                .filter(|o| matches!(o.motion, Motion::Static))
                .map(|o| (o.body_shape(), Pose::new(o.start, o.heading)))
                .collect(),
            resolution: map_resolution,
        }
    }

    /// The walls.
    pub(crate) fn walls(&self) -> &[[P; 2]] {
        &self.walls
    }

    /// The static obstacles, each's shape and pose.
    pub(crate) fn statics(&self) -> &[(Shape, Pose)] {
        &self.statics
    }

    /// The map's cell in scenario units, if there is a map.
    pub(crate) fn resolution(&self) -> Option<f64> {
        self.resolution
    }

    /// Checks that robot `spec` has a route (with `route = "shortest"`):
    /// a car's by Hybrid A* ([`crate::car_route`]), any other's over the
    /// clearance grid.
    pub fn check(&self, spec: &RobotSpec) -> Result<(), RouteFailure> {
        if spec.kinematics == Kinematics::Ackermann {
            self.car_route(spec)?;
        } else {
            self.route(spec)?;
        }
        Ok(())
    }

    /// The points of robot `spec`'s route, from its start to its goal (a
    /// car's: its centre's along the route), and their length.
    pub fn line(&self, spec: &RobotSpec) -> Result<(Vec<P>, f64), RouteFailure> {
        if spec.kinematics == Kinematics::Ackermann {
            let (setup, route) = self.car_route(spec)?;
            let step = setup.wheelbase / 8.0;
            Ok(crate::car_route::centre_line(
                &route.path,
                setup.wheelbase,
                step,
            ))
        } else {
            let (_, path) = self.route(spec)?;
            Ok((path.points().to_vec(), path.length()))
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

/// Why a robot has no route.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RouteFailure {
    /// A disc's (or a unicycle's): no way is wide enough.
    #[error(transparent)]
    Disc(#[from] RouteError),
    /// A car's: Hybrid A* found no route it can drive.
    #[error(transparent)]
    Car(#[from] CarRouteError),
}

/// `planner` as robot `spec` drives with it when its `route` is
/// `shortest`: steered along its route on `scene` ([`Routed`]), or, a car,
/// driven along its car's route ([`crate::car_route::CarRouted`]); else
/// unchanged.
pub fn fit_route(
    planner: Box<dyn Planner>,
    spec: &RobotSpec,
    scene: &RouteScene,
) -> Result<Box<dyn Planner>, RouteFailure> {
    if spec.route != mrsim_scenario::Route::Shortest {
        return Ok(planner);
    }
    if spec.kinematics == Kinematics::Ackermann {
        let (setup, route) = scene.car_route(spec)?;
        return Ok(Box::new(crate::car_route::CarRouted::new(
            planner,
            spec,
            scene.clone(),
            setup,
            &route,
        )));
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
    /// Where the robot last stood still and since when.
    stand: (P, f64),
    /// Whom it gives way to, when it does.
    yielding: Option<Yielding>,
    /// No new look for a refuge before this time (after a failed one).
    next_look: f64,
    yields: u32,
    /// The narrow stretches of its route ([`crate::passage`]).
    stretches: Vec<Stretch>,
    /// Its footprint, and the footprint's width and circumscribed radius.
    body: mrsim_shape::Shape,
    width: f64,
    extent: f64,
    /// Where it holds short of a narrow stretch, if it does, and for whom.
    holding: Option<(P, u32)>,
    /// Whom it has held for while they stood, and since when.
    waited: Vec<(u32, f64)>,
    holds: u32,
    /// It backs off until this time.
    back_until: f64,
}

/// A robot giving way: to whom, along which of its own way ahead the other
/// stood, and since when.
struct Yielding {
    to: u32,
    way: Vec<P>,
    since: f64,
}

impl Routed {
    /// Wraps `inner` for robot `spec` along `path` on `grid`.
    pub fn new(inner: Box<dyn Planner>, spec: &RobotSpec, grid: Clearance, path: Path) -> Self {
        let ahead = ahead(spec);
        let body = spec.body_shape();
        let (width, extent) = (2.0 * body.inradius(), body.circumradius());
        let stretches = passage::marked(&grid, &path, width, extent);
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
            stand: ([f64::NAN; 2], 0.0),
            yielding: None,
            next_look: f64::NEG_INFINITY,
            yields: 0,
            stretches,
            body,
            width,
            extent,
            holding: None,
            waited: Vec::new(),
            holds: 0,
            back_until: f64::NEG_INFINITY,
        }
    }

    /// Does the robot take turns at narrow stretches and back off when
    /// face to face ([`crate::passage`])? A unicycle whose route has narrow
    /// stretches and whose planner plans its (v, omega) itself from the
    /// others' states.
    fn turns(&self) -> bool {
        !self.stretches.is_empty()
            && self.spec.kinematics == Kinematics::Unicycle
            && self.inner.plans_unicycle()
            && !self.inner.needs_scan()
    }

    /// Is the robot face to face with another (their reaches and a little
    /// apart, the other ahead), or its footprint within 0.15 m of a wall
    /// ahead?
    fn faces(&self, obs: &Observation, p: P) -> bool {
        let h = [obs.me.heading.cos(), obs.me.heading.sin()];
        let robot = obs.others.iter().any(|o| {
            let d = [o.position.x - p[0], o.position.y - p[1]];
            o.kind == BodyKind::Robot
                && d[0].hypot(d[1]) < self.extent + o.radius + 0.3
                && d[0] * h[0] + d[1] * h[1] > 0.0
        });
        let me = self.body;
        let pose = Pose::new(p, obs.me.heading);
        robot
            || obs.walls.iter().any(|w| {
                let w = [[w.a.x, w.a.y], [w.b.x, w.b.y]];
                let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                let ahead = (m[0] - p[0]) * h[0] + (m[1] - p[1]) * h[1] > 0.0;
                ahead
                    && mrsim_shape::segment_distance(w, p) < 2.0 * self.extent
                    && mrsim_shape::gap_to_segment(&me, pose, w) < 0.15
            })
    }

    /// Can the footprint back straight off by `by` clear of the walls and
    /// of the others (each grown by how far it goes while the robot backs)?
    fn room_behind(&self, obs: &Observation, p: P, by: f64) -> bool {
        let me = self.body;
        let hd = obs.me.heading;
        let h = [hd.cos(), hd.sin()];
        let near = by + 2.0 * self.extent + 1.0;
        let walls: Vec<[P; 2]> = obs
            .walls
            .iter()
            .map(|w| [[w.a.x, w.a.y], [w.b.x, w.b.y]])
            .filter(|w| mrsim_shape::segment_distance(*w, p) < near)
            .collect();
        let n = (by / 0.1).ceil().max(1.0) as u32;
        (1..=n).all(|k| {
            let a = by * f64::from(k) / f64::from(n);
            let pose = Pose::new([p[0] - h[0] * a, p[1] - h[1] * a], hd);
            walls
                .iter()
                .all(|w| mrsim_shape::gap_to_segment(&me, pose, *w) > 0.03)
                && obs.others.iter().all(|o| {
                    let at = Pose::new([o.position.x, o.position.y], o.heading);
                    mrsim_shape::gap(&me, pose, &o.shape, at) > 0.05 + o.velocity.norm() * BACK_FOR
                })
        })
    }

    /// Follows `path` from now on, its narrow stretches marked.
    fn follow(&mut self, path: Path, time: f64) {
        self.stretches = passage::marked(&self.grid, &path, self.width, self.extent);
        self.follower.replace(path, time);
    }

    /// The turn-taking rule at narrow stretches ([`crate::passage`]), each
    /// tick: the point its planner is shown while it holds short of the
    /// next stretch, if it does.
    fn turn_rule(&mut self, obs: &Observation) -> Option<P> {
        if self.yielding.is_some() {
            self.holding = None;
            return None;
        }
        let s0 = self.follower.progress();
        let me = &obs.me;
        let cap = me.max_speed;
        let st = self.stretches.iter().find(|st| st.to > s0).copied();
        let p = [me.position.x, me.position.y];
        let v = me.velocity.norm();
        let braking = v * v / (2.0 * me.max_accel.max(1e-9));
        let held_for = st.and_then(|st| {
            // Beyond the horizon, or committed: it goes on.
            if st.from - s0 > cap * passage::HORIZON || s0 >= st.from - self.extent - braking {
                return None;
            }
            let rule = passage::Me {
                id: me.id,
                position: p,
                velocity: [me.velocity.x, me.velocity.y],
                heading: me.heading,
                cap,
                accel: me.max_accel,
                slow: self.slow,
                width: self.width,
                extent: self.extent,
            };
            let (time, slow, waited) = (obs.time, self.slow, &self.waited);
            let ignored = |o: &Sensed| {
                o.velocity.norm() < slow
                    && waited
                        .iter()
                        .any(|&(id, since)| id == o.id && time - since >= PATIENCE)
            };
            passage::hold_for(&st, &rule, obs.others, &ignored).map(|id| (st, id))
        });
        // Whom it has held for while they stand, since when (forgotten
        // once they move, or it no longer holds).
        self.waited.retain(|&(id, _)| {
            held_for.is_some()
                && obs
                    .others
                    .iter()
                    .any(|o| o.id == id && o.velocity.norm() < self.slow)
        });
        let Some((st, id)) = held_for else {
            self.holding = None;
            return None;
        };
        if !self.waited.iter().any(|w| w.0 == id)
            && obs
                .others
                .iter()
                .any(|o| o.id == id && o.velocity.norm() < self.slow)
        {
            self.waited.push((id, obs.time));
        }
        let s_hold = st.from - passage::hold_back(self.extent);
        let at = match self.holding {
            Some((at, _)) if s0 >= s_hold => at,
            _ if s0 >= s_hold => p,
            _ => self.follower.at(s_hold),
        };
        if self.holding.is_none() {
            self.holds += 1;
        }
        self.holding = Some((at, id));
        self.follower.wait(obs.time);
        Some(at)
    }

    /// How far from a way another robot must be to leave it free: both
    /// radii and half the margin.
    fn off(&self, other: &Sensed) -> f64 {
        self.radius + other.radius + self.margin / 2.0
    }

    /// The robot's own way ahead: from where it stands along its route to
    /// [`ahead`] twice beyond its progress.
    fn way_ahead(&self, p: P) -> Vec<P> {
        let s0 = self.follower.progress();
        let step = self.ahead / 4.0;
        let mut way = vec![p];
        let mut s = s0;
        while s <= s0 + self.reach {
            way.push(self.follower.at(s));
            s += step;
        }
        way
    }

    /// The robots in the way ahead (within the way's reach and nearer to
    /// it than [`Routed::off`]) that are not leaving it (moving away from
    /// this robot slower than a tenth of its top speed), nearest first.
    fn blockers<'o>(&self, obs: &'o Observation, way: &[P]) -> Vec<&'o Sensed> {
        let me = obs.me.position;
        let mut found: Vec<&Sensed> = obs
            .others
            .iter()
            .filter(|o| {
                let d = o.position - me;
                let n = d.norm();
                o.kind == BodyKind::Robot
                    && n <= self.reach + o.radius
                    && n > 0.0
                    && o.velocity.dot(&d) / n < self.slow
                    && to_way([o.position.x, o.position.y], way) < self.off(o)
            })
            .collect();
        found.sort_by(|a, b| {
            (a.position - me)
                .norm()
                .total_cmp(&(b.position - me).norm())
                .then(a.id.cmp(&b.id))
        });
        found
    }

    /// Gives way to `other` if a refuge is near: the nearest place with
    /// room for the disc, at least [`Routed::off`] from the way `other`
    /// presumably wants (the line from it through this robot and on back
    /// along this robot's route), reached around the bodies sensed near.
    /// Whether it does.
    fn give_way(&mut self, obs: &Observation, p: P, other: &Sensed, way: Vec<P>) -> bool {
        let mut theirs = self.follower.path().up_to(self.follower.progress());
        theirs.push(p);
        theirs.push([other.position.x, other.position.y]);
        let within = 2.0 * self.reach;
        let blocked: Vec<(P, f64)> = obs
            .others
            .iter()
            .filter(|o| (o.position - obs.me.position).norm() <= within + self.radius + o.radius)
            .map(|o| ([o.position.x, o.position.y], o.radius))
            .collect();
        let path = self.grid.refuge(&Refuge {
            from: p,
            radius: self.radius,
            room: self.radius + self.margin / 4.0,
            way: &theirs,
            off: self.off(other),
            blocked: &blocked,
            within,
        });
        let Some(path) = path else {
            return false;
        };
        self.follow(path, obs.time);
        self.yielding = Some(Yielding {
            to: other.id,
            way,
            since: obs.time,
        });
        self.yields += 1;
        true
    }

    /// The yielding rule (module documentation), each tick before the
    /// waypoint: starts or ends a yield.
    fn yield_rule(&mut self, obs: &Observation, p: P) {
        if self.inner.needs_scan() {
            return;
        }
        if let Some(y) = &self.yielding {
            let still = obs.others.iter().any(|o| {
                o.id == y.to && to_way([o.position.x, o.position.y], &y.way) < self.off(o)
            });
            if !still || obs.time - y.since > YIELD_WAIT {
                self.yielding = None;
                self.stand = (p, obs.time);
                self.replan(obs, p);
            }
            return;
        }
        let stood = obs.time - self.stand.1;
        if stood < YIELD_AFTER || obs.time < self.next_look || self.follower.at_end() {
            return;
        }
        let way = self.way_ahead(p);
        let blockers = self.blockers(obs, &way);
        let me = obs.me.id;
        let to = blockers
            .iter()
            .find(|o| o.id > me)
            .or_else(|| {
                blockers
                    .first()
                    .filter(|o| stood >= YIELD_ESCALATE && o.velocity.norm() < self.slow)
            })
            .copied()
            .copied();
        if let Some(other) = to
            && !self.give_way(obs, p, &other, way)
        {
            self.next_look = obs.time + 1.0;
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
            self.follow(path, obs.time);
            self.replans += 1;
        }
    }
}

impl Planner for Routed {
    fn plan(&mut self, obs: &Observation) -> Command {
        let p = [obs.me.position.x, obs.me.position.y];
        if self.stand.0[0].is_nan()
            || (p[0] - self.stand.0[0]).hypot(p[1] - self.stand.0[1]) > self.ahead / 4.0
        {
            self.stand = (p, obs.time);
        }
        let turns = self.turns();
        if turns {
            let backing = obs.time < self.back_until;
            let start = !backing && obs.time - self.stand.1 >= BACK_AFTER && self.faces(obs, p);
            if (backing && self.room_behind(obs, p, 0.1))
                || (start && self.room_behind(obs, p, 0.5))
            {
                if start {
                    self.back_until = obs.time + BACK_FOR;
                    self.stand = (p, obs.time);
                }
                return Command::Unicycle {
                    v: -BACK_SPEED,
                    omega: 0.0,
                };
            }
            self.back_until = f64::NEG_INFINITY;
        }
        let hold = if turns { self.turn_rule(obs) } else { None };
        if hold.is_none() {
            if self.yielding.is_none() && self.follower.stuck(obs.time) {
                self.replan(obs, p);
            }
            self.yield_rule(obs, p);
        }
        let far = self.follower.waypoint(p, obs.time);
        if let Some(at) = hold {
            let mut seen = *obs;
            seen.goal = Vec2::new(at[0], at[1]);
            return self.inner.plan(&seen);
        }
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
        d.push(Diagnostic {
            name: "route_yield".into(),
            value: if self.yielding.is_some() { 1.0 } else { 0.0 },
        });
        d.push(Diagnostic {
            name: "route_yields".into(),
            value: f64::from(self.yields),
        });
        d.push(Diagnostic {
            name: "route_hold".into(),
            value: if self.holding.is_some() { 1.0 } else { 0.0 },
        });
        d.push(Diagnostic {
            name: "route_holds".into(),
            value: f64::from(self.holds),
        });
        d
    }

    fn native_unicycle(&self) -> bool {
        self.inner.native_unicycle()
    }

    fn native_ackermann(&self) -> bool {
        self.inner.native_ackermann()
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }
}
