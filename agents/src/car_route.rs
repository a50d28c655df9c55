//! `route = "shortest"` for a car (`kinematics = "ackermann"`): a route it
//! can drive, planned once by Hybrid A* (`mrsim_route::hybrid`) when its
//! planner is built, and driven by pure pursuit (`mrsim_route::pursuit`)
//! forwards and backwards between its changes of gear, slowing and
//! stopping for the bodies it senses in its way, or, on the open road, by
//! its planner when that plans the car's own controls (dwa).
//!
//! **What is planned.** The car is a kinematic bicycle whose pose names the
//! centre of its body, the wheelbase L centred on it. Only its rear axle
//! moves along its heading, so the route is planned for the rear axle,
//! where the paths of Dubins and Reeds-Shepp are exact for the bicycle
//! (its heading is the path's tangent, its turn rate the path's curvature
//! times its speed): the footprint searched is the body's true shape moved
//! L/2 forwards, so that its origin is the rear axle (a disc becomes the
//! regular octagon around it), and the goal is the centre's (the goal's
//! point L/2 ahead of the reference, `Goal::offset`), at the goal heading
//! when the scenario gives one (`goal_heading_deg`). The route turns on
//! [`RADIUS_FACTOR`] times the car's least turning radius L / tan(max
//! steering), so that the pursuit has steering to spare where it must
//! catch up (the steering turns at most `max_steering_rate_deg`, and a
//! route's arcs begin and end abruptly), and keeps [`margin`] from walls
//! and static obstacles (the rectangles and polygons as their outlines),
//! which lets the body stray that far off its route without touching
//! them. It ends at the goal heading exactly, leaving the scenario's
//! whole tolerance to the pursuit; only when no route does may it end
//! within half the tolerance (its last arcs would otherwise turn the
//! heading within the tolerance in a few decimetres, more sharply than
//! the steering can follow).
//!
//! **Driving it.** Each tick the rear axle is projected onto the route and
//! steered by pure pursuit to the route's point [`lookahead`] on (a
//! second of its speed, from a quarter of the wheelbase to the wheelbase)
//! within the present segment (the run between two changes of gear): steering
//! atan(L kappa), kappa the pursuit arc's curvature, in either gear. Its
//! speed is the smallest of: the car's top speed in that gear; the speed
//! from which it stops at the segment's end braking at half `max_accel`
//! (at a change of gear and at the goal), but at least a creep
//! ([`creep`]) until it gets there; the speed at which the steering,
//! turning at its rate limit, reaches the pursuit's within a quarter of
//! the look-ahead of travel; and the speed from which it stops, braking
//! at half `max_accel`, before the first pose along the route ahead (in
//! the present gear) where its footprint would come within [`keep`] of
//! a sensed body (robot or moving obstacle, taken where it is, its keep
//! grown by a second of its speed) nearer than the body is now. The static
//! obstacles the route was planned around are not counted.
//!
//! **Giving way.** Cars whose ways cross (at a junction, a merge) each
//! decide by one rule applied to what they sense, without communication,
//! who goes first, so that no two stop across each other's way (the
//! gridlock of four cars in a junction, each in front of the next). Each
//! robot sensed is taken to go on along its velocity (standing, along its
//! heading), speeding up at the car's own acceleration to the car's own
//! top speed (as one of its fleet would), for up to [`GIVE_WAY_HORIZON`]
//! s; a moving obstacle keeps its velocity; people and standing obstacles
//! are left to the keep above. The car finds the first pose of its route
//! ahead where its footprint would come within the keep of the body's on
//! that way, and the times both take to get there: it goes first if it is
//! through (past the pose by both bodies' extents) [`MARGIN_TIME`] before
//! the other arrives, or simply arrives first by more than that; arriving
//! within [`MARGIN_TIME`] of each other, the lower id goes first. Else it
//! stops a quarter of its look-ahead short of that pose (the ways' poses
//! found within twice the keep, so that a car stopped there leaves the
//! other's way the keep), unless it can no longer stop there braking at
//! `max_accel` (it is committed, and the other, which sees it nearer,
//! waits); and, giving way to any, short of the first way it crosses, so
//! that waiting for a car in the far lane it does not stand in the near
//! one. A body going within 45 degrees of
//! the route's direction there is followed, not given way to. A robot
//! that has stood [`crate::route::PATIENCE`] s while the car waits for it
//! is not coming (parked at its goal, say): the car no longer gives way
//! to it, and the keep above holds it off it where it stands.
//!
//! **The open road: the robot's planner.** A planner that plans the car's
//! (speed, steering) itself with its true footprint
//! (`Planner::plans_ackermann`: dwa) drives the car where its route is
//! open road: forwards, the segment's end further than two circumscribed
//! radii beyond the point shown, and no car given way to. It is shown, as
//! its goal (at no tolerance), the centre's point of the route
//! [`road_ahead`] on, and its command is taken but for its speed, capped
//! to stop at the segment's end; a command backwards is not taken (the
//! pursuit drives that tick). Bodies beside and on the route are then its
//! planner's to avoid, not the keep's. Everywhere else (the changes of
//! gear, the last stretch to the goal and its heading, a car giving way)
//! the pursuit drives: a planner steers for a point, not along a route,
//! cuts the route's arcs, does not stop at changes of gear and arrives at
//! whatever heading it came in, which in a parking bay between two cars is
//! a contact. A holonomic planner through the tracking controller (orca)
//! is not consulted: on the junction's variants its discs, grown by the
//! tracking bound to wider than a lane, stopped for the cars passing in
//! the other lane and grazed the kerbs (docs/shapes.md). The diagnostic
//! `route_planner` is 1 on the ticks the planner drove.
//!
//! **Replanning.** When the car has made no progress along its route for
//! [`crate::route::PATIENCE`] s (something stands in its way), its route
//! is planned again from where it stands, around the bodies it senses
//! standing (slower than a tenth of its top speed) within twice its
//! braking look ahead as well, each grown by the keep (so that it passes
//! a parked car by its route's margin and the keep); if there is no such
//! route it waits, and tries again after as long. While they stand where
//! they stood, those bodies count as in the way only if the car strays
//! within half the keep of them.
//!
//! The diagnostics `route_progress` (the route's length driven, m),
//! `route_replans` and `route_gear` (1 forwards, -1 backwards, 0 stopped
//! at the goal) say how it goes.

use crate::passage::time_to;
use crate::route::{PATIENCE, RouteScene};
use mrsim_planners::{
    BodyKind, Command, Diagnostic, Kinematics, Observation, Planner, Polygon, Pose, Sensed, Shape,
};
use mrsim_route::{
    Car, CarMap, CarPath, CarPose, CarRoute, CarRouteError, Gear, Goal, Pursuit, Scene, Search,
    outline,
};
use mrsim_scenario::RobotSpec;

/// A wall segment.
type Wall = [[f64; 2]; 2];

/// A disc: centre and radius.
type Disc = ([f64; 2], f64);

/// The route's turning radius over the car's least.
pub const RADIUS_FACTOR: f64 = 1.25;

/// The gap a car's route keeps from walls and static obstacles: a quarter
/// of the body's [`Shape::inradius`] (half its width, for a rectangle
/// longer than wide: 0.2 m for a 1.6 m wide car).
pub fn margin(spec: &RobotSpec) -> f64 {
    spec.body_shape().inradius() / 4.0
}

/// The gap the car keeps from sensed bodies along its way ahead: its
/// route's [`margin`] doubled.
pub fn keep(spec: &RobotSpec) -> f64 {
    2.0 * margin(spec)
}

/// The pursuit's look-ahead at speed `speed`: a second of it, between a
/// quarter of the wheelbase and the wheelbase.
pub fn lookahead(wheelbase: f64, speed: f64) -> f64 {
    speed.abs().clamp(wheelbase / 4.0, wheelbase)
}

/// How far along its route, on the open road, the point a car's planner
/// is shown lies: 1.5 s of its speed, at least twice the wheelbase.
pub fn road_ahead(wheelbase: f64, speed: f64) -> f64 {
    (1.5 * speed.abs()).max(2.0 * wheelbase)
}

/// How far ahead in time a car looks for the ways of moving bodies that
/// cross its route, s.
pub const GIVE_WAY_HORIZON: f64 = 8.0;

/// Two arrivals at a crossing less than this apart are together, s; a car
/// goes first only if it is through this long before the other gets there.
pub const MARGIN_TIME: f64 = 1.0;

/// A body moving within 45 degrees of the route's direction where their
/// ways meet is followed, not given way to: the cosine.
const FOLLOWING: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The spacing of the route's poses and of the body's times searched for
/// a crossing, m.
const CROSSING_STEP: f64 = 0.25;

/// The way a sensed body is taken to go when the car looks whether to
/// give way to it (module documentation, "Giving way").
struct Way {
    /// The direction: its velocity's, or, standing, a robot's heading.
    u: (f64, f64),
    /// How far it goes within [`GIVE_WAY_HORIZON`].
    length: f64,
    /// Its speed along `u`.
    speed: f64,
    /// A robot's top speed and acceleration, taken as the car's own; `None`
    /// for a body that keeps its velocity.
    drive: Option<(f64, f64)>,
    /// Is it a robot standing (slower than `slow`)?
    standing: bool,
}

impl Way {
    /// The way of `o`: a robot speeding up from its speed along its heading
    /// (or velocity) to `cap` at `accel`; a moving obstacle at its
    /// velocity; `None` for people and for obstacles slower than `slow`.
    fn of(o: &Sensed, slow: f64, cap: f64, accel: f64) -> Option<Self> {
        let v = o.velocity.norm();
        match o.kind {
            BodyKind::Robot => {
                let u = if v >= slow {
                    (o.velocity.x / v, o.velocity.y / v)
                } else {
                    (o.heading.cos(), o.heading.sin())
                };
                Some(Self {
                    u,
                    length: cap * GIVE_WAY_HORIZON,
                    speed: o.velocity.x * u.0 + o.velocity.y * u.1,
                    drive: Some((cap, accel)),
                    standing: v < slow,
                })
            }
            BodyKind::Obstacle if v >= slow => Some(Self {
                u: (o.velocity.x / v, o.velocity.y / v),
                length: v * GIVE_WAY_HORIZON,
                speed: v,
                drive: None,
                standing: false,
            }),
            _ => None,
        }
    }

    /// The time it takes to go `a` along its way.
    fn time_to(&self, a: f64) -> f64 {
        match self.drive {
            Some((cap, accel)) => time_to(a, self.speed, cap, accel),
            None => a / self.speed,
        }
    }
}

/// The least speed the car drives at until it reaches the end of a
/// segment: a fiftieth of its wheelbase per second.
pub fn creep(wheelbase: f64) -> f64 {
    wheelbase / 50.0
}

/// `shape` in the frame of a point `back` behind its origin along x (the
/// rear axle of a car whose shape is about its centre): a polygon's points
/// moved forwards by `back`; a disc's regular octagon around it, moved so.
pub fn rear_footprint(shape: &Shape, back: f64) -> Shape {
    let pts: Vec<[f64; 2]> = match shape {
        Shape::Polygon(p) => p.points().to_vec(),
        Shape::Disc { radius } => {
            let r = radius / (std::f64::consts::PI / 8.0).cos();
            (0..8)
                .map(|k| {
                    let a = std::f64::consts::TAU * (k as f64 + 0.5) / 8.0;
                    [r * a.cos(), r * a.sin()]
                })
                .collect()
        }
    };
    let moved: Vec<[f64; 2]> = pts.iter().map(|p| [p[0] + back, p[1]]).collect();
    // Moving a convex counter-clockwise polygon keeps it so.
    Polygon::new(&moved).map_or(*shape, Shape::Polygon)
}

/// `shape` grown by `by` on every side: a disc's radius, a convex
/// polygon's edges each moved out by `by` (its corners mitred, so the
/// polygon holds every point within `by` of the shape).
pub fn grown(shape: &Shape, by: f64) -> Shape {
    match shape {
        Shape::Disc { radius } => Shape::disc(radius + by),
        Shape::Polygon(p) => {
            let pts = p.points();
            let n = pts.len();
            // Each edge's outward normal (the polygon is counter-clockwise).
            let normal = |i: usize| {
                let (a, b) = (pts[i], pts[(i + 1) % n]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let l = dx.hypot(dy).max(1e-12);
                [dy / l, -dx / l]
            };
            let out: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    // The corner `i` between edges `i - 1` and `i`, moved
                    // along their normals' bisector to meet both moved
                    // edges.
                    let (m0, m1) = (normal((i + n - 1) % n), normal(i));
                    let c = 1.0 + m0[0] * m1[0] + m0[1] * m1[1];
                    let k = by / (c / 2.0).max(1e-6);
                    let q = pts[i];
                    [
                        q[0] + (m0[0] + m1[0]) * k / 2.0,
                        q[1] + (m0[1] + m1[1]) * k / 2.0,
                    ]
                })
                .collect();
            Polygon::new(&out).map_or(*shape, Shape::Polygon)
        }
    }
}

/// The car a robot's route is planned for, its wheelbase and its goal.
#[derive(Debug, Clone, Copy)]
pub struct CarSetup {
    /// The rear-axle footprint, the route's radius, and reverse.
    pub car: Car,
    /// The wheelbase.
    pub wheelbase: f64,
    /// Where the rear axle starts.
    pub start: Pose,
    /// The centre's goal, `offset` half the wheelbase, at the goal heading
    /// exactly if there is one.
    pub goal: Goal,
    /// Half the scenario's goal heading tolerance (0 without one): the
    /// tolerance of the route's end when none ends at the heading exactly.
    pub loose: f64,
    /// The search's settings.
    pub search: Search,
    /// The grid's cell: the map's, or an eighth of the body's inscribed
    /// radius (the footprint is checked exactly where the grid cannot
    /// tell; a finer grid costs its square in time at every replanning).
    pub resolution: f64,
}

impl CarSetup {
    /// The setup of car `spec` on a map of cell `map_resolution` (if any).
    pub fn of(spec: &RobotSpec, map_resolution: Option<f64>) -> Result<Self, CarRouteError> {
        let Some(ack) = spec.ackermann else {
            return Err(CarRouteError::Bad(format!(
                "robot `{}` is not a car (no wheelbase)",
                spec.name
            )));
        };
        let l = ack.wheelbase;
        let body = spec.body_shape();
        let h = spec.start_heading();
        let (s, c) = h.sin_cos();
        let start = Pose::new(
            [spec.start[0] - l / 2.0 * c, spec.start[1] - l / 2.0 * s],
            h,
        );
        let goal = Goal {
            position: spec.goal,
            heading: spec.goal_heading.map(|g| g.heading),
            heading_tolerance: 0.0,
            offset: l / 2.0,
        };
        Ok(Self {
            car: Car {
                shape: rear_footprint(&body, l / 2.0),
                radius: RADIUS_FACTOR * ack.min_turning_radius(),
                reverse: ack.max_reverse_speed > 0.0,
            },
            wheelbase: l,
            start,
            goal,
            loose: spec.goal_heading.map_or(0.0, |g| g.tolerance / 2.0),
            search: Search {
                margin: margin(spec),
                ..Search::default()
            },
            resolution: map_resolution.unwrap_or(body.inradius() / 8.0),
        })
    }

    /// The route on `map` from the rear axle's pose `from`: to the goal
    /// heading exactly, or if there is none such, within [`Self::loose`]
    /// of it.
    pub fn route(&self, map: &CarMap, from: Pose) -> Result<CarRoute, CarRouteError> {
        let exact = map.route(&self.car, from, &self.goal, &self.search);
        match exact {
            Err(_) if self.loose > 0.0 => {
                let loose = Goal {
                    heading_tolerance: self.loose,
                    ..self.goal
                };
                map.route(&self.car, from, &loose, &self.search).or(exact)
            }
            done => done,
        }
    }

    /// The map of `scene` for this car, with `blocked` (bodies standing in
    /// its way: shape and pose) as obstacles too, covering `from`.
    pub fn map(&self, scene: &RouteScene, blocked: &[(Shape, Pose)], from: Pose) -> CarMap {
        let (walls, discs) = scene.car_obstacles(blocked);
        let goal = self.goal.position;
        CarMap::build(&Scene {
            walls: &walls,
            discs: &discs,
            points: &[self.start.position, from.position, goal],
            resolution: self.resolution,
            pad: 2.0 * self.car.shape.circumradius(),
        })
    }
}

impl RouteScene {
    /// The walls and discs a car's route goes round: the walls, the
    /// outlines of the static rectangles and polygons and of `blocked`'s,
    /// and the static discs and `blocked`'s.
    fn car_obstacles(&self, blocked: &[(Shape, Pose)]) -> (Vec<Wall>, Vec<Disc>) {
        let mut walls = self.walls().to_vec();
        let mut discs = Vec::new();
        for (shape, pose) in self.statics().iter().chain(blocked) {
            match shape {
                Shape::Disc { radius } => discs.push((pose.position, *radius)),
                Shape::Polygon(_) => walls.extend(outline(shape, *pose)),
            }
        }
        (walls, discs)
    }

    /// The route of car `spec`, from its start to its goal (module
    /// documentation).
    pub fn car_route(&self, spec: &RobotSpec) -> Result<(CarSetup, CarRoute), CarRouteError> {
        let setup = CarSetup::of(spec, self.resolution())?;
        let map = setup.map(self, &[], setup.start);
        let route = setup.route(&map, setup.start)?;
        Ok((setup, route))
    }
}

/// The centre of a car of `wheelbase` whose rear axle is at `p`.
fn centre(p: &CarPose, wheelbase: f64) -> [f64; 2] {
    let (s, c) = p.heading.sin_cos();
    [
        p.position[0] + wheelbase / 2.0 * c,
        p.position[1] + wheelbase / 2.0 * s,
    ]
}

/// The centre's positions along a car's rear-axle `path`, at most `step`
/// apart, for a wheelbase `wheelbase`, and their length.
pub fn centre_line(path: &CarPath, wheelbase: f64, step: f64) -> (Vec<[f64; 2]>, f64) {
    let pts: Vec<[f64; 2]> = path
        .poses(step)
        .iter()
        .map(|p| centre(p, wheelbase))
        .collect();
    let len = pts
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    (pts, len)
}

/// A car driven along its route (module documentation).
pub struct CarRouted {
    inner: Box<dyn Planner>,
    scene: RouteScene,
    setup: CarSetup,
    pursuit: Pursuit,
    /// Static obstacles' positions (not counted as in the way).
    statics: Vec<[f64; 2]>,
    /// The bodies the route was last planned again around (id, where
    /// each stood), not counted as in the way while they stand there.
    around: Vec<(u32, [f64; 2])>,
    /// The body the car last waited for to give way, and since when.
    waited_for: Option<(u32, f64)>,
    keep: f64,
    lookahead: f64,
    slow: f64,
    replans: u32,
    last_try: f64,
    gear: f64,
    /// Did the planner drive the last tick (the open road)?
    planner_drove: bool,
}

impl CarRouted {
    /// Drives robot `spec` along `route` (planned by `setup` on `scene`);
    /// `inner` is kept for what it says of itself (whether it needs a
    /// scan).
    pub fn new(
        inner: Box<dyn Planner>,
        spec: &RobotSpec,
        scene: RouteScene,
        setup: CarSetup,
        route: &CarRoute,
    ) -> Self {
        let lookahead = lookahead(setup.wheelbase, 0.0);
        let at_cusp = spec.goal_tolerance.min(setup.wheelbase / 20.0);
        Self {
            inner,
            statics: scene.statics().iter().map(|s| s.1.position).collect(),
            around: Vec::new(),
            waited_for: None,
            scene,
            setup,
            pursuit: Pursuit::new(&route.path, lookahead, at_cusp, PATIENCE),
            keep: keep(spec),
            lookahead,
            slow: spec.max_speed / 10.0,
            replans: 0,
            last_try: f64::NEG_INFINITY,
            gear: 1.0,
            planner_drove: false,
        }
    }

    /// On the open road (forwards, the segment's end beyond two
    /// circumscribed radii and the point shown), the
    /// centre's goal shown to the planner: the route's point
    /// [`road_ahead`] on; else `None` (the pursuit drives).
    fn open_road(
        &self,
        t: &mrsim_route::pursuit::Target,
        speed: f64,
    ) -> Option<mrsim_planners::Vec2> {
        if t.gear != Gear::Forward {
            return None;
        }
        let l = self.setup.wheelbase;
        let ahead = road_ahead(l, speed);
        let approach = 2.0 * self.setup.car.shape.circumradius();
        if t.to_stop <= approach + ahead {
            return None;
        }
        let poses = self.pursuit.poses();
        let k = poses.partition_point(|p| p.s <= self.pursuit.progress() + ahead);
        let p = poses.get(k.checked_sub(1)?)?;
        Some(mrsim_planners::Vec2::from(centre(p, l)))
    }

    /// Is `o` one of the static obstacles the route went round?
    fn known(&self, o: &Sensed) -> bool {
        o.kind == BodyKind::Obstacle
            && self
                .statics
                .iter()
                .any(|p| (p[0] - o.position.x).hypot(p[1] - o.position.y) <= o.radius / 2.0)
    }

    /// Is `o` a body the route was last planned again around, standing
    /// where it stood?
    fn went_round(&self, o: &Sensed) -> bool {
        self.around.iter().any(|(id, p)| {
            *id == o.id && (p[0] - o.position.x).hypot(p[1] - o.position.y) <= self.keep / 2.0
        })
    }

    /// How far the car may drive along its route before its footprint
    /// comes within the keep of a sensed body nearer than it is now
    /// (module documentation), up to `look`; `look` when nothing is in
    /// the way.
    fn free(&self, obs: &Observation, rear: Pose, look: f64, to_stop: f64) -> f64 {
        let foot = self.setup.car.shape;
        let reach = look + 2.0 * foot.circumradius();
        let near: Vec<(&Sensed, f64, f64)> = obs
            .others
            .iter()
            .filter(|o| !self.known(o))
            .filter(|o| {
                let d = (o.position.x - rear.position[0]).hypot(o.position.y - rear.position[1]);
                d <= reach + o.radius
            })
            .map(|o| {
                let at = Pose::new([o.position.x, o.position.y], o.heading);
                let now = mrsim_shape::gap(&foot, rear, &o.shape, at);
                // A body the route went round, `grown` by the keep: only
                // straying half the keep towards it counts.
                let keep = if self.went_round(o) {
                    self.keep / 2.0
                } else {
                    self.keep + o.velocity.norm()
                };
                (o, now, keep)
            })
            .collect();
        if near.is_empty() {
            return look;
        }
        let s0 = self.pursuit.progress();
        let end = s0 + look.min(to_stop);
        for p in self.pursuit.poses() {
            if p.s <= s0 {
                continue;
            }
            if p.s > end {
                break;
            }
            for &(o, now, keep) in &near {
                let at = Pose::new([o.position.x, o.position.y], o.heading);
                let g = mrsim_shape::gap(&foot, p.pose(), &o.shape, at);
                if g < keep && g < now - 1e-6 {
                    return (p.s - s0 - self.lookahead / 4.0).max(0.0);
                }
            }
        }
        look
    }

    /// How far the car may drive along its route before it must give way
    /// to a body whose way crosses it ahead and that gets there first
    /// (module documentation, "Giving way"), up to `look`; `look` when it
    /// gives way to none. `speed` is its present speed along its gear,
    /// `cap` the gear's top speed, `accel` its acceleration.
    fn give_way(&mut self, obs: &Observation, speed: f64, cap: f64, accel: f64, look: f64) -> f64 {
        let foot = self.setup.car.shape;
        let r_me = foot.circumradius();
        let s0 = self.pursuit.progress();
        let mut limit = look;
        let mut waiting = None;
        // How far ahead the first way it crosses is.
        let mut first_way = f64::INFINITY;
        for o in obs.others {
            let Some(way) = Way::of(o, self.slow, cap, accel) else {
                continue;
            };
            if self.known(o) || self.went_round(o) {
                continue;
            }
            // A robot standing this long while the car waits for it is
            // not coming: `free` keeps the gap to it where it stands.
            if way.standing
                && self
                    .waited_for
                    .is_some_and(|(id, since)| id == o.id && obs.time - since >= PATIENCE)
            {
                continue;
            }
            let reach = r_me + o.radius + 2.0 * self.keep;
            let Some((s_c, a_in, tangent)) = self.crossing(o, &way, reach, s0, look) else {
                continue;
            };
            // Going the same way: following, not crossing (`free` keeps
            // the gap behind it).
            if tangent.0 * way.u.0 + tangent.1 * way.u.1 > FOLLOWING {
                continue;
            }
            let t_in = way.time_to(a_in);
            let ahead = s_c - s0;
            first_way = first_way.min(ahead);
            let t_me = time_to(ahead, speed, cap, accel);
            // Through and clear of its way before it gets there: go first.
            let through = ahead + 2.0 * r_me + 2.0 * o.radius + self.keep;
            if time_to(through, speed, cap, accel) + MARGIN_TIME < t_in {
                continue;
            }
            // Arriving together: the lower id goes first.
            let first = if (t_me - t_in).abs() <= MARGIN_TIME {
                obs.me.id < o.id
            } else {
                t_me < t_in
            };
            if first {
                continue;
            }
            // Too near to stop short of it braking hard: committed, go on.
            let stop_at = ahead - CROSSING_STEP - self.lookahead / 4.0;
            if speed * speed / (2.0 * obs.me.max_accel) > stop_at.max(0.0) + 1e-9 {
                continue;
            }
            if stop_at < limit {
                limit = stop_at.max(0.0);
                waiting = Some(o.id);
            }
        }
        // Giving way, it stops short of the first way it crosses, not in
        // it (it would block the car that goes first there), if it still
        // can.
        let before = first_way - CROSSING_STEP - self.lookahead / 4.0;
        if waiting.is_some()
            && before < limit
            && speed * speed / (2.0 * obs.me.max_accel) <= before.max(0.0) + 1e-9
        {
            limit = before.max(0.0);
        }
        self.waited_for = match (waiting, self.waited_for) {
            (Some(id), Some((was, since))) if was == id => Some((id, since)),
            (Some(id), _) => Some((id, obs.time)),
            (None, _) => None,
        };
        limit
    }

    /// Where body `o`, going its `way`, first comes within the keep of the
    /// car's footprint on its route ahead, from progress `s0` up to `look`
    /// on: that pose's progress, how far along its way the body is then,
    /// and the route's direction there. `reach` bounds the centres'
    /// distance at which the shapes can be within the keep.
    fn crossing(
        &self,
        o: &Sensed,
        way: &Way,
        reach: f64,
        s0: f64,
        look: f64,
    ) -> Option<(f64, f64, (f64, f64))> {
        let foot = self.setup.car.shape;
        let u = way.u;
        let mut next = s0;
        for p in self.pursuit.poses() {
            if p.s < next {
                continue;
            }
            if p.s > s0 + look {
                break;
            }
            next = p.s + CROSSING_STEP;
            let d = (p.position[0] - o.position.x, p.position[1] - o.position.y);
            let along = d.0 * u.0 + d.1 * u.1;
            let across = (d.0 * u.1 - d.1 * u.0).abs();
            if across > reach || along < -reach || along > way.length + reach {
                continue;
            }
            // How far along its way the body's centre is within `reach` of
            // the pose's.
            let half = (reach * reach - across * across).max(0.0).sqrt();
            let mut a = (along - half).max(0.0);
            let a1 = (along + half).min(way.length);
            while a <= a1 {
                let at = Pose::new([o.position.x + u.0 * a, o.position.y + u.1 * a], o.heading);
                if mrsim_shape::gap(&foot, p.pose(), &o.shape, at) < 2.0 * self.keep {
                    return Some((p.s, a, (p.heading.cos(), p.heading.sin())));
                }
                a += CROSSING_STEP;
            }
        }
        None
    }

    /// Plans again from `rear` around the bodies standing near (module
    /// documentation, "Replanning").
    fn replan(&mut self, obs: &Observation, rear: Pose, within: f64) {
        self.last_try = obs.time;
        let standing: Vec<&Sensed> = obs
            .others
            .iter()
            .filter(|o| !self.known(o) && o.velocity.norm() < self.slow)
            .filter(|o| {
                (o.position.x - rear.position[0]).hypot(o.position.y - rear.position[1])
                    <= within + o.radius
            })
            .collect();
        let blocked: Vec<(Shape, Pose)> = standing
            .iter()
            .map(|o| {
                (
                    grown(&o.shape, self.keep),
                    Pose::new([o.position.x, o.position.y], o.heading),
                )
            })
            .collect();
        let map = self.setup.map(&self.scene, &blocked, rear);
        if let Ok(route) = self.setup.route(&map, rear) {
            self.pursuit.replace(&route.path, obs.time);
            self.replans += 1;
            self.around = standing
                .iter()
                .map(|o| (o.id, [o.position.x, o.position.y]))
                .collect();
        }
    }
}

impl Planner for CarRouted {
    fn plan(&mut self, obs: &Observation) -> Command {
        let me = &obs.me;
        let Kinematics::Ackermann {
            wheelbase: l,
            max_steering,
            max_steering_rate,
            max_reverse_speed,
        } = me.kinematics
        else {
            // Not a car after all: brake.
            return Command::Velocity(mrsim_planners::Vec2::zeros());
        };
        let (sh, ch) = me.heading.sin_cos();
        let rear = Pose::new(
            [me.position.x - l / 2.0 * ch, me.position.y - l / 2.0 * sh],
            me.heading,
        );
        let brake = me.max_accel / 2.0;
        let top = me.max_speed.max(max_reverse_speed);
        let look = top * top / (2.0 * brake) + 2.0 * self.setup.car.shape.circumradius();
        if self.pursuit.stuck(obs.time) && obs.time - self.last_try >= PATIENCE {
            self.replan(obs, rear, 2.0 * look);
        }
        let speed_now = me.velocity.dot(&mrsim_planners::Vec2::new(ch, sh));
        self.pursuit.set_lookahead(lookahead(l, speed_now));
        let t = self.pursuit.target(rear, obs.time);
        let steering = t.steering(l, max_steering);
        let (cap, sign) = match t.gear {
            Gear::Forward => (me.max_speed, 1.0),
            Gear::Reverse => (max_reverse_speed, -1.0),
        };
        if t.last && t.to_stop <= 1e-9 {
            self.gear = 0.0;
            return Command::Ackermann {
                speed: 0.0,
                steering,
            };
        }
        self.gear = sign;
        let creep = creep(l).min(cap);
        let stop = (2.0 * brake * t.to_stop).sqrt().max(creep);
        let lag = (steering - me.steering).abs();
        let steer = if lag > 1e-9 {
            self.lookahead / 4.0 * max_steering_rate / lag
        } else {
            f64::INFINITY
        };
        let way_limit = look.min(t.to_stop);
        let give_way = self.give_way(obs, sign * speed_now, cap, me.max_accel, way_limit);
        // The open road: the planner drives, to the route's point ahead.
        let open = if give_way >= way_limit && self.inner.plans_ackermann() {
            self.open_road(&t, speed_now)
        } else {
            None
        };
        self.planner_drove = false;
        if let Some(goal) = open {
            let mut o = *obs;
            o.goal = goal;
            o.goal_tolerance = 0.0;
            if let Command::Ackermann {
                speed: v,
                steering: d,
            } = self.inner.plan(&o)
                && v >= 0.0
            {
                self.planner_drove = true;
                return Command::Ackermann {
                    speed: v.min(stop),
                    steering: d,
                };
            }
        }
        // The pursuit drives: slowing for what is in its way, and to give way.
        let free = self.free(obs, rear, look, t.to_stop).min(give_way);
        let clear = if free >= look {
            f64::INFINITY
        } else {
            (2.0 * brake * free).sqrt()
        };
        let speed = cap.min(stop).min(steer.max(creep)).min(clear);
        Command::Ackermann {
            speed: sign * speed,
            steering,
        }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        vec![
            Diagnostic {
                name: "route_progress".into(),
                value: self.pursuit.progress(),
            },
            Diagnostic {
                name: "route_replans".into(),
                value: f64::from(self.replans),
            },
            Diagnostic {
                name: "route_gear".into(),
                value: self.gear,
            },
            Diagnostic {
                name: "route_planner".into(),
                value: f64::from(u8::from(self.planner_drove)),
            },
        ]
    }

    fn native_ackermann(&self) -> bool {
        true
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_route::drive::wrap;

    #[test]
    fn the_rear_axle_footprint_is_the_body_moved_forwards_by_half_the_wheelbase() {
        let body = Shape::Polygon(Polygon::rectangle(4.6, 1.6).expect("a rectangle"));
        let Shape::Polygon(p) = rear_footprint(&body, 1.4) else {
            panic!("a polygon");
        };
        let want = [[-0.9, -0.8], [3.7, -0.8], [3.7, 0.8], [-0.9, 0.8]];
        assert_eq!(p.points().len(), 4);
        for (q, w) in p.points().iter().zip(want) {
            assert!(
                (q[0] - w[0]).abs() < 1e-12 && (q[1] - w[1]).abs() < 1e-12,
                "{q:?}"
            );
        }
        // A disc: the octagon around it, every edge at the radius.
        let Shape::Polygon(o) = rear_footprint(&Shape::disc(1.0), 0.5) else {
            panic!("a polygon");
        };
        for (i, a) in o.points().iter().enumerate() {
            let b = o.points()[(i + 1) % 8];
            let mid = [(a[0] + b[0]) / 2.0 - 0.5, (a[1] + b[1]) / 2.0];
            assert!((mid[0].hypot(mid[1]) - 1.0).abs() < 1e-12, "{mid:?}");
        }
    }

    #[test]
    fn a_grown_rectangle_is_the_rectangle_wider_and_longer_by_twice_the_growth() {
        let r = Shape::Polygon(Polygon::rectangle(4.6, 1.6).expect("a rectangle"));
        let Shape::Polygon(g) = grown(&r, 0.4) else {
            panic!("a polygon");
        };
        let want = [[-2.7, -1.2], [2.7, -1.2], [2.7, 1.2], [-2.7, 1.2]];
        for (q, w) in g.points().iter().zip(want) {
            assert!(
                (q[0] - w[0]).abs() < 1e-12 && (q[1] - w[1]).abs() < 1e-12,
                "{q:?}"
            );
        }
        // A triangle's every edge moves out by the growth.
        let t = Shape::Polygon(
            Polygon::new(&[[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]]).expect("a triangle"),
        );
        let Shape::Polygon(gt) = grown(&t, 0.25) else {
            panic!("a polygon");
        };
        let (a, b) = (gt.points()[1], gt.points()[2]);
        // The hypotenuse x + 2 y = 2, moved out by 0.25.
        for q in [a, b] {
            let d = (q[0] + 2.0 * q[1] - 2.0) / 5f64.sqrt();
            assert!((d - 0.25).abs() < 1e-12, "{q:?}");
        }
        assert_eq!(grown(&Shape::disc(1.0), 0.5), Shape::disc(1.5));
    }

    #[test]
    fn a_car_takes_as_long_to_a_crossing_as_its_acceleration_says() {
        // From rest at 2.5 m/s^2 to 8 m/s: 12.8 m in 3.2 s, then at 8 m/s.
        assert!((time_to(12.8, 0.0, 8.0, 2.5) - 3.2).abs() < 1e-12);
        assert!((time_to(20.8, 0.0, 8.0, 2.5) - 4.2).abs() < 1e-12);
        assert!((time_to(8.0, 8.0, 8.0, 2.5) - 1.0).abs() < 1e-12);
        assert_eq!(time_to(1.0, 0.0, 8.0, 0.0), f64::INFINITY);
    }

    #[test]
    fn a_car_route_puts_the_centre_on_the_goal_at_the_goal_heading() {
        let src = include_str!("../../scenarios/cars/parking.toml");
        let s = mrsim_scenario::parse(src, "parking.toml")
            .expect("the parking scene")
            .scenario;
        let spec = &s.robots[0];
        let (setup, route) = RouteScene::of(&s).car_route(spec).expect("a route");
        let end = route.path.end();
        let goal = spec.goal_heading.expect("a goal heading").heading;
        assert!(wrap(end.heading - goal).abs() < 1e-9, "{end:?}");
        let (line, _) = centre_line(&route.path, setup.wheelbase, 0.1);
        let c = line.last().expect("points");
        assert!(
            (c[0] - spec.goal[0]).hypot(c[1] - spec.goal[1]) < 1e-9,
            "{c:?}"
        );
        // It starts at the rear axle of the car as it stands.
        let st = route.path.start();
        let h = spec.start_heading();
        let back = [spec.start[0] - 1.4 * h.cos(), spec.start[1] - 1.4 * h.sin()];
        assert!((st.position[0] - back[0]).hypot(st.position[1] - back[1]) < 1e-9);
        // Its radius is the car's least, by the factor.
        let least = spec.ackermann.expect("a car").min_turning_radius();
        assert!((route.path.radius() - RADIUS_FACTOR * least).abs() < 1e-12);
        eprintln!(
            "parking: {} poses expanded, length {:.2}, {} gear changes",
            route.expanded,
            route.path.length(),
            route.path.gear_changes()
        );
    }
}
