//! People (pedestrians), moved by the world like the scripted obstacles
//! ([`crate::motion`]): no agent, no process, so that a crowd of
//! thousands costs the world's time only.
//!
//! Every tick the world calls [`Crowd::begin_tick`] with every body's state
//! at the start of the tick (robots, obstacles, people: the snapshot's
//! order), then [`Crowd::advance`] once per physics substep. A person's
//! model chooses its velocity once per tick and holds it over the
//! substeps (p += v h), as RVO2's `doStep` does over its time step:
//!
//! - **Route.** A person walks to its `waypoints` in order (a `goal` is
//!   the one point). A point counts as reached once the person's centre
//!   is within its radius of it (CrowdNav's `reached_destination`); then
//!   the next, and after the last the first again if `cyclic`. Else the
//!   person stays with the last point as its goal, and so comes to rest
//!   there.
//! - **Preferred velocity** (RVO2's Circle example, as the `orca`
//!   planner reads it): towards the goal at `preferred_speed`, and the
//!   goal vector itself once the goal is nearer than `preferred_speed`
//!   (so the person slows into its goal and stops there).
//! - **`orca`**: RVO2's `computeNewVelocity` for the person
//!   ([`mrsim_planners::orca::Walker`], the `orca` planner's own
//!   half-planes, neighbour selection and linear programs), speed limit
//!   `preferred_speed` (CrowdNav's human: `max_speed = v_pref`), time step
//!   the tick, among the other people (who avoid in turn: half the
//!   avoidance each, RVO2's reciprocity), the scripted obstacles (which do
//!   not: all of it) and, when the person `sees_robots`, the robots (taken
//!   for RVO2 agents that avoid in turn, as CrowdNav's humans take its
//!   robot: half). A person who does not see robots walks as if there
//!   were none (CrowdNav's invisible robot). The walls are RVO2's
//!   obstacles. The new velocity is the person's velocity over the tick.
//!
//! - **Behaviours** (HuNavSim's, the guide's people chapter): a person
//!   that sees robots reacts to the nearest one within its behaviour's
//!   `detect_dist` and its field of view, for `duration` seconds of such
//!   ticks: surprised, it stands facing the robot; scared, it slows and a
//!   force (under orca, its preferred velocity) pushes it away, the robot
//!   fully avoided; curious, it walks up to the robot and stands facing it
//!   within `stop_dist`; threatening, it walks to the point `front_dist`
//!   ahead of the robot. Impassive, it always takes robots for obstacles:
//!   under the social force a robot's disc repels as a wall does, under
//!   orca it is a still obstacle avoided within the tick only.
//!
//! Each person's velocity is a function of the tick's snapshot and its
//! own plan alone, so the people are split across worker threads (one for
//! each 512 people, at most one a core) and any split gives the same
//! velocities, bit for bit; the behaviours' timers are counted before, in
//! order, on the world's thread.
//!
//! People are kinematic: nothing pushes them; a contact of a robot with a
//! person is the robot's (the world counts it), contacts among people are
//! nobody's.

use mrsim_planners::Vec2;
use mrsim_planners::orca::{Neighbor, Walker, WalkerParams};
use mrsim_proto::BodyState;
use mrsim_scenario::{Behavior, PersonMotion, PersonSpec, Scenario, SocialForceParams};
use mrsim_spatial::{Disc, NeighbourGrid, within};

/// The moving state of one person.
#[derive(Debug, Clone)]
pub struct Person {
    /// Current position.
    pub position: [f64; 2],
    /// Velocity over the current tick.
    pub velocity: [f64; 2],
    /// Facing, rad: along its velocity while it walks, else where it
    /// last walked or what it turned to.
    pub heading: f64,
    /// The index of the point walked to.
    next: usize,
    /// Seconds its behaviour has acted (HuNavSim's timer).
    reacted: f64,
}

/// How a person treats robots this tick.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Robots {
    /// As people (regular).
    People,
    /// As obstacles (impassive).
    Obstacles,
    /// Not at all (not seen, or replaced by the behaviour's own rule).
    Unseen,
    /// Robot `j` fully avoided and repelling with weight `factor`
    /// (scared).
    Scary(usize, f64),
}

/// What person `k` walks to this tick, how fast, and how it treats robots.
#[derive(Debug, Clone, Copy)]
struct Plan {
    goal: Vec2,
    /// Within this of `goal`, arrived (the social force brakes).
    arrive: Option<f64>,
    speed: f64,
    robots: Robots,
}

/// HuNavSim's field of view: a robot is seen within this angle of the
/// heading (`lineOfSight`: pi / 2 + 0.17 rad).
const FIELD_OF_VIEW: f64 = std::f64::consts::FRAC_PI_2 + 0.17;
/// HuNavSim's view distance, m (`max_dist_view_`): a curious person walks
/// at `vel` times the robot's distance over it.
const VIEW_DIST: f64 = 10.0;
/// HuNavSim's `forceSigmaObstacle` (lightsfm's 0.2 m), the scared force's
/// range under ORCA (the social force takes `sigma_obstacle`).
const SCARY_SIGMA: f64 = 0.2;

/// Every person of a scenario and what moving them needs.
#[derive(Debug, Clone)]
pub struct Crowd {
    specs: Vec<PersonSpec>,
    /// By person index.
    pub people: Vec<Person>,
    /// One per worker of [`Crowd::begin_tick`].
    scratch: Vec<Scratch>,
    dt: f64,
    /// The body id of the first person (robots and obstacles come first).
    first: usize,
    robots: usize,
    grid: NeighbourGrid,
    /// The last tick's grid was built.
    gridded: bool,
    /// The people in the order they are walked (cell by cell), each with
    /// its cell.
    order: Vec<(u32, Option<(i64, i64)>)>,
    /// Every body's velocity at the tick's start in the grid's order
    /// (its slots: [`NeighbourGrid::around_cell`]).
    slot_velocity: Vec<Vec2>,
    /// Each person's plan of the tick (behaviours).
    plans: Vec<Planned>,
    /// Each person's new velocity and heading.
    moves: Vec<Move>,
    reach: f64,
    /// Every wall segment, the arena's included (the social force's).
    walls: Vec<mrsim_planners::Segment>,
    /// Each group's members, by person index.
    groups: Vec<Vec<usize>>,
    /// Each person's group, by index into `groups`.
    group_of: Vec<Option<usize>>,
}

/// A person's plan of the tick and what it faces if not where it walks,
/// or `Err(point)`: it stands facing `point` ([`Crowd::plan`]'s answer).
type Planned = Result<(Plan, Option<[f64; 2]>), [f64; 2]>;

/// What one worker of [`Crowd::begin_tick`] computes in: the bodies near
/// the person, its ORCA neighbours and RVO2's walker.
#[derive(Debug, Clone, Default)]
struct Scratch {
    walker: Walker,
    /// The person's neighbours: indices into `around`, ascending (so by
    /// body id).
    near: Vec<u32>,
    candidates: Vec<Neighbor>,
    /// The bodies around the cell searched last (or every body), by body
    /// id: each one's id, slot in the grid's order and disc, so that a
    /// person's neighbours are read from one run of memory, not picked
    /// out of the snapshot one by one.
    around: Vec<(u32, u32, Disc)>,
    /// The velocity of each body of `around`, in its order.
    moving: Vec<Vec2>,
    /// The velocities chosen, by person index.
    out: Vec<(u32, Move)>,
}

/// A person's new velocity and its new heading (none: it keeps the one
/// it has).
type Move = ([f64; 2], Option<f64>);

/// Fewest people a worker of [`Crowd::begin_tick`] is given: below it the
/// crowd is stepped on the world's own thread.
const PEOPLE_PER_WORKER: usize = 512;

/// Most workers the crowd's step is split across.
const MAX_WORKERS: usize = 8;

fn v(p: [f64; 2]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

impl Crowd {
    /// The people of `scenario`, at their starts.
    pub fn new(scenario: &Scenario) -> Self {
        let walls: Vec<mrsim_planners::Segment> = scenario
            .all_walls()
            .iter()
            .map(|w| mrsim_planners::Segment {
                a: v(w[0]),
                b: v(w[1]),
            })
            .collect();
        let reach = scenario
            .people
            .iter()
            .map(|p| match p.motion {
                PersonMotion::Orca { neighbor_dist, .. } => neighbor_dist,
                PersonMotion::SocialForce(f) => f.neighbor_dist,
            })
            .fold(0.0, f64::max);
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut names: std::collections::HashMap<&str, usize> = Default::default();
        let group_of = scenario
            .people
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let g = p.group.as_deref()?;
                let i = *names.entry(g).or_insert_with(|| {
                    groups.push(Vec::new());
                    groups.len() - 1
                });
                groups[i].push(k);
                Some(i)
            })
            .collect();
        Self {
            people: scenario
                .people
                .iter()
                .map(|p| Person {
                    position: p.start,
                    velocity: [0.0, 0.0],
                    heading: facing(p.start, p.waypoints[0]),
                    next: 0,
                    reacted: 0.0,
                })
                .collect(),
            specs: scenario.people.clone(),
            scratch: {
                let workers = std::thread::available_parallelism()
                    .map_or(1, |n| n.get())
                    .clamp(1, MAX_WORKERS)
                    .min(scenario.people.len().div_ceil(PEOPLE_PER_WORKER).max(1));
                let walker = if scenario.people.is_empty() {
                    Walker::default()
                } else {
                    Walker::new(&walls)
                };
                vec![
                    Scratch {
                        walker,
                        ..Scratch::default()
                    };
                    workers
                ]
            },
            dt: scenario.world.dt,
            first: scenario.robots.len() + scenario.obstacles.len(),
            robots: scenario.robots.len(),
            grid: NeighbourGrid::default(),
            gridded: false,
            order: Vec::new(),
            slot_velocity: Vec::new(),
            plans: Vec::new(),
            moves: Vec::new(),
            reach,
            walls: if scenario.people.is_empty() {
                Vec::new()
            } else {
                walls.clone()
            },
            groups,
            group_of,
        }
    }

    /// True if there is nobody to move.
    pub fn is_empty(&self) -> bool {
        self.people.is_empty()
    }

    /// Person `k`'s spec.
    pub fn spec(&self, k: usize) -> &PersonSpec {
        &self.specs[k]
    }

    /// The goal person `k` walks to now.
    pub fn goal(&self, k: usize) -> [f64; 2] {
        let s = &self.specs[k];
        s.waypoints[self.people[k].next.min(s.waypoints.len() - 1)]
    }

    /// Chooses every person's velocity for the tick that starts now from
    /// `bodies`, every body's state at its start (robots, obstacles,
    /// people, by body id).
    pub fn begin_tick(&mut self, bodies: &[BodyState]) {
        if self.people.is_empty() {
            return;
        }
        // Route: a point reached, the next.
        for (p, s) in self.people.iter_mut().zip(&self.specs) {
            let g = s.waypoints[p.next];
            let d = (g[0] - p.position[0]).hypot(g[1] - p.position[1]);
            if d < s.radius {
                if p.next + 1 < s.waypoints.len() {
                    p.next += 1;
                } else if s.cyclic {
                    p.next = 0;
                }
            }
        }
        let grid = self.grid.build(
            bodies
                .iter()
                .map(|b| [b.position[0], b.position[1], b.radius]),
            self.reach,
        );
        self.gridded = grid;
        // Behaviours: each person's plan, its timers counted, in order.
        let n = self.people.len();
        let mut plans = std::mem::take(&mut self.plans);
        plans.clear();
        for k in 0..n {
            plans.push(self.plan(k, bodies));
        }
        // Velocities: each person's from the tick's start alone, so the
        // people are split across the workers (threads) and every split
        // gives the same velocities, bit for bit.
        // They are visited cell by cell (the grid's order), so that one
        // search of a cell's 3 x 3 neighbourhood serves every person in
        // it; without a grid, in order, each among every body.
        let mut order = std::mem::take(&mut self.order);
        order.clear();
        self.slot_velocity.clear();
        if grid {
            self.slot_velocity.extend(
                self.grid
                    .in_cell_order()
                    .map(|(j, _)| v(bodies[j as usize].velocity)),
            );
            let people = self.first as u32..(self.first + n) as u32;
            order.extend(
                self.grid
                    .in_cell_order()
                    .filter(|(j, _)| people.contains(j))
                    .map(|(j, c)| (j - people.start, Some(c))),
            );
        } else {
            order.extend((0..n as u32).map(|k| (k, None)));
        }
        let mut moves = std::mem::take(&mut self.moves);
        moves.clear();
        moves.resize(n, ([0.0, 0.0], None));
        let mut scratch = std::mem::take(&mut self.scratch);
        let chunk = n.div_ceil(scratch.len()).max(1);
        {
            let this = &*self;
            let plans = &plans;
            if scratch.len() == 1 {
                this.walk(&order, plans, bodies, &mut scratch[0]);
            } else {
                std::thread::scope(|scope| {
                    for (part, s) in order.chunks(chunk).zip(&mut scratch) {
                        scope.spawn(move || this.walk(part, plans, bodies, s));
                    }
                });
            }
        }
        for s in &mut scratch {
            for &(k, m) in &s.out {
                moves[k as usize] = m;
            }
        }
        self.order = order;
        self.scratch = scratch;
        for (p, (nv, heading)) in self.people.iter_mut().zip(&moves) {
            p.velocity = *nv;
            if let Some(h) = heading {
                p.heading = *h;
            }
        }
        self.plans = plans;
        self.moves = moves;
    }

    /// The new velocities of the people of `part` (each with its grid cell,
    /// or `None`: among every body), under their `plans`, into `s.out`.
    fn walk(
        &self,
        part: &[(u32, Option<(i64, i64)>)],
        plans: &[Planned],
        bodies: &[BodyState],
        s: &mut Scratch,
    ) {
        s.out.clear();
        let mut searched: Option<Option<(i64, i64)>> = None;
        for &(k, cell) in part {
            let k = k as usize;
            let (plan, face) = match plans[k] {
                Ok(plan) => plan,
                // Standing to look (surprised; curious, near).
                Err(face) => {
                    let heading = facing(self.people[k].position, face);
                    s.out.push((k as u32, ([0.0, 0.0], Some(heading))));
                    continue;
                }
            };
            let motion = self.specs[k].motion;
            let reach = match motion {
                PersonMotion::Orca { neighbor_dist, .. } => neighbor_dist,
                PersonMotion::SocialForce(f) => f.neighbor_dist,
            };
            let p = &self.people[k];
            if searched != Some(cell) {
                match cell {
                    // The grid's answer for the person's position: its
                    // cell's neighbourhood.
                    Some(c) => {
                        self.grid.around_cell(c, &mut s.around);
                        s.moving.clear();
                        s.moving.extend(
                            s.around
                                .iter()
                                .map(|&(_, slot, _)| self.slot_velocity[slot as usize]),
                        );
                    }
                    // Without a grid, every body.
                    None => {
                        s.around.clear();
                        s.around.extend(bodies.iter().enumerate().map(|(j, b)| {
                            (j as u32, j as u32, [b.position[0], b.position[1], b.radius])
                        }));
                        s.moving.clear();
                        s.moving.extend(bodies.iter().map(|b| v(b.velocity)));
                    }
                }
                searched = Some(cell);
            }
            s.near.clear();
            match cell {
                // Within reach.
                Some(_) => s.near.extend(
                    (0..s.around.len() as u32)
                        .filter(|&i| within(&s.around[i as usize].2, p.position, reach)),
                ),
                None => s.near.extend(0..s.around.len() as u32),
            }
            let nv = match motion {
                PersonMotion::Orca { .. } => self.orca(k, bodies, &plan, s),
                PersonMotion::SocialForce(f) => self.social_force(k, bodies, &f, &plan, s),
            };
            // Facing what it looks at, else where it walks.
            let heading = match face {
                Some(target) => Some(facing(p.position, target)),
                None if nv.x != 0.0 || nv.y != 0.0 => Some(nv.y.atan2(nv.x)),
                None => None,
            };
            s.out.push((k as u32, ([nv.x, nv.y], heading)));
        }
    }

    /// The nearest robot person `k` perceives for its behaviour (within
    /// `detect_dist` and its field of view, HuNavSim's `isRobotVisible`),
    /// by body id.
    fn perceived(&self, k: usize, bodies: &[BodyState], detect: f64) -> Option<usize> {
        let p = &self.people[k];
        let mut best: Option<(f64, usize)> = None;
        for (j, b) in bodies.iter().enumerate().take(self.robots) {
            let d = [b.position[0] - p.position[0], b.position[1] - p.position[1]];
            let dist = d[0].hypot(d[1]);
            if dist > detect || wrap(d[1].atan2(d[0]) - p.heading).abs() > FIELD_OF_VIEW {
                continue;
            }
            if best.is_none_or(|(bd, _)| dist < bd) {
                best = Some((dist, j));
            }
        }
        best.map(|(_, j)| j)
    }

    /// Person `k`'s plan for this tick under its behaviour, with what it
    /// faces if not where it walks; or `Err(point)`: it stands facing
    /// `point`. Counts the behaviour's time.
    fn plan(&mut self, k: usize, bodies: &[BodyState]) -> Planned {
        let s = &self.specs[k];
        let regular = Plan {
            goal: v(self.goal(k)),
            arrive: None,
            speed: s.preferred_speed,
            robots: if !s.sees_robots {
                Robots::Unseen
            } else if s.behavior == Behavior::Impassive {
                Robots::Obstacles
            } else {
                Robots::People
            },
        };
        let Some(reaction) = s.behavior.reaction() else {
            return Ok((regular, None));
        };
        if !s.sees_robots {
            return Ok((regular, None));
        }
        let Some(j) = self.perceived(k, bodies, reaction.detect_dist) else {
            return Ok((regular, None));
        };
        // HuNavSim's TimeExpiredCondition, ticked while the robot is seen.
        let p = &mut self.people[k];
        p.reacted += self.dt;
        if p.reacted >= reaction.duration {
            if !reaction.once {
                p.reacted = 0.0;
            }
            return Ok((regular, None));
        }
        let r = &bodies[j];
        let (me, robot) = (v(p.position), v(r.position));
        let dist = (robot - me).norm();
        match s.behavior {
            Behavior::Regular | Behavior::Impassive => Ok((regular, None)),
            Behavior::Surprised(_) => Err(r.position),
            Behavior::Scared {
                vel,
                other_force_factor,
                ..
            } => Ok((
                Plan {
                    speed: vel,
                    robots: Robots::Scary(j, other_force_factor),
                    ..regular
                },
                None,
            )),
            Behavior::Curious { vel, stop_dist, .. } => {
                if dist <= stop_dist {
                    return Err(r.position);
                }
                Ok((
                    Plan {
                        goal: robot,
                        arrive: Some(r.radius),
                        speed: (vel * dist / VIEW_DIST).min(vel),
                        robots: Robots::Unseen,
                    },
                    None,
                ))
            }
            Behavior::Threatening {
                vel, front_dist, ..
            } => {
                // Ahead of the robot: along its velocity, or its heading
                // when it stands.
                let rv = v(r.velocity);
                let ahead = if rv.norm() > 1e-9 {
                    rv / rv.norm()
                } else {
                    Vec2::new(r.heading.cos(), r.heading.sin())
                };
                let face = (dist <= 0.6).then_some(r.position);
                Ok((
                    Plan {
                        goal: robot + ahead * front_dist,
                        arrive: Some(0.05),
                        speed: vel,
                        robots: Robots::Unseen,
                    },
                    face,
                ))
            }
        }
    }

    /// Person `k`'s preferred velocity (RVO2's, see the module
    /// documentation).
    fn preferred(&self, k: usize, plan: &Plan) -> Vec2 {
        let to_goal = plan.goal - v(self.people[k].position);
        let d = to_goal.norm();
        if d > plan.speed {
            to_goal * (plan.speed / d)
        } else {
            to_goal
        }
    }

    /// Person `k`'s ORCA velocity among the bodies of `s.near`.
    fn orca(&self, k: usize, bodies: &[BodyState], plan: &Plan, s: &mut Scratch) -> Vec2 {
        let Scratch {
            walker,
            near,
            candidates,
            around,
            moving,
            ..
        } = s;
        let spec = &self.specs[k];
        let PersonMotion::Orca {
            neighbor_dist,
            max_neighbors,
            time_horizon,
            time_horizon_obst,
            radius_margin,
        } = spec.motion
        else {
            return Vec2::zeros();
        };
        let me = self.first + k;
        candidates.clear();
        for &i in near.iter() {
            let (id, _, [x, y, radius]) = around[i as usize];
            let j = id as usize;
            if j == me {
                continue;
            }
            // Obstacles (the bodies between the robots and the people) do
            // not avoid: all of it is the person's.
            let mut share = if (self.robots..self.first).contains(&j) {
                1.0
            } else {
                0.5
            };
            let (mut velocity, mut time_horizon) = (moving[i as usize], None);
            if j < self.robots {
                match plan.robots {
                    Robots::People => {}
                    Robots::Unseen => continue,
                    // An obstacle that stands where it is, kept off only
                    // within the tick: no way made for it.
                    Robots::Obstacles => {
                        share = 1.0;
                        velocity = Vec2::zeros();
                        time_horizon = Some(self.dt);
                    }
                    // All of the avoidance is the scared person's.
                    Robots::Scary(..) => share = 1.0,
                }
            }
            candidates.push(Neighbor {
                id,
                position: Vec2::new(x, y),
                velocity,
                radius,
                share,
                time_horizon,
            });
        }
        let params = WalkerParams {
            neighbor_dist,
            max_neighbors,
            time_horizon,
            time_horizon_obst,
            radius_margin,
        };
        let p = &self.people[k];
        let mut pref = self.preferred(k, plan);
        if let Robots::Scary(j, factor) = plan.robots {
            // The goal's direction plus HuNavSim's scary force in units
            // of it, at the scared speed.
            let away = v(p.position) - v(bodies[j].position);
            let d = (away.norm() - spec.radius).max(1e-3);
            let dir = unit(pref) + unit(away) * (factor * SCARY_SIGMA / d);
            pref = unit(dir) * plan.speed;
        }
        walker.velocity(
            v(p.position),
            v(p.velocity),
            spec.radius,
            plan.speed,
            pref,
            candidates,
            &params,
            self.dt,
        )
    }

    /// Person `k`'s velocity at the end of the tick under the social
    /// forces of the bodies of `s.near`, the walls and its group
    /// (see the module documentation).
    fn social_force(
        &self,
        k: usize,
        bodies: &[BodyState],
        f: &SocialForceParams,
        plan: &Plan,
        s: &Scratch,
    ) -> Vec2 {
        let Scratch {
            near,
            around,
            moving,
            ..
        } = s;
        let s = &self.specs[k];
        let me = self.first + k;
        let p = &self.people[k];
        let (position, velocity) = (v(p.position), v(p.velocity));
        // Desired force (H&M eq 2; libpedsim's `Twaypoint::getForce`):
        // towards the point walked to at the desired speed, relaxed within
        // the relaxation time; at the last point, reached, braking
        // (libpedsim's agent without a destination).
        let s_last = p.next + 1 == s.waypoints.len() && !s.cyclic;
        let to_goal = plan.goal - position;
        let arrived = match plan.arrive {
            Some(r) => to_goal.norm() <= r,
            None => s_last && to_goal.norm() < s.radius,
        };
        let e = if arrived {
            Vec2::zeros()
        } else {
            unit(to_goal)
        };
        let desired = (e * plan.speed - velocity) / f.relaxation_time;
        // Social force (Moussaid et al. 2009, as libpedsim's `socialForce`).
        let mut social = Vec2::zeros();
        for &i in near.iter() {
            let (j, _, [x, y, _]) = around[i as usize];
            let j = j as usize;
            if j == me || (j < self.robots && plan.robots != Robots::People) {
                continue;
            }
            let mut diff = Vec2::new(x, y) - position;
            if diff.norm_squared() >= f.neighbor_dist * f.neighbor_dist {
                continue;
            }
            if j < self.robots {
                diff /= f.robot_scale;
            }
            social += moussaid(diff, velocity - moving[i as usize]);
        }
        // Obstacle force: the nearest wall only (libpedsim's
        // `obstacleForce`), measured from the person's disc.
        let mut obstacle = Vec2::zeros();
        let mut nearest = f64::INFINITY;
        for w in &self.walls {
            let d = position - w.closest_point(position);
            if d.norm_squared() < nearest {
                nearest = d.norm_squared();
                obstacle = d;
            }
        }
        if plan.robots == Robots::Obstacles {
            // Impassive: a robot's disc is an obstacle like a wall.
            for &i in near.iter() {
                let j = around[i as usize].0 as usize;
                let Some(b) = bodies.get(j).filter(|_| j < self.robots) else {
                    continue;
                };
                let off = position - v(b.position);
                let surface = v(b.position) + unit(off) * b.radius;
                let d = position - surface;
                if d.norm_squared() < nearest {
                    nearest = d.norm_squared();
                    obstacle = d;
                }
            }
        }
        if nearest.is_finite() {
            let amount = (-(nearest.sqrt() - s.radius) / f.sigma_obstacle).exp();
            obstacle = unit(obstacle) * amount;
        }
        let group = self.group_force(k, e, f);
        let mut a = desired * f.force_desired
            + social * f.force_social
            + obstacle * f.force_obstacle
            + group;
        if let Robots::Scary(j, factor) = plan.robots {
            // HuNavSim's `avoidRobot`: factor sigma / (|d| - r) away.
            let away = position - v(bodies[j].position);
            let d = (away.norm() - s.radius).max(1e-3);
            a += unit(away) * (factor * f.sigma_obstacle / d);
        }
        // libpedsim's `move`: v += h a, capped at the desired speed.
        let nv = velocity + a * self.dt;
        let speed = nv.norm();
        if speed > plan.speed {
            nv * (plan.speed / speed)
        } else {
            nv
        }
    }

    /// pedsim's group forces on person `k` walking along the unit `e`
    /// (Moussaid et al. 2010, pedsim_simulator's `GroupGazeForce`,
    /// `GroupCoherenceForce` and `GroupRepulsionForce` in their paper
    /// versions), each times its weight.
    fn group_force(&self, k: usize, e: Vec2, f: &SocialForceParams) -> Vec2 {
        let Some(g) = self.group_of[k] else {
            return Vec2::zeros();
        };
        let members = &self.groups[g];
        let n = members.len();
        if n <= 1 {
            return Vec2::zeros();
        }
        let me = v(self.people[k].position);
        let com = members
            .iter()
            .fold(Vec2::zeros(), |c, &m| c + v(self.people[m].position))
            / n as f64;
        let mut force = Vec2::zeros();
        // Gaze: the others' centre of mass kept within 90 degrees of the
        // walking direction, by turning (slowing) against it.
        let others = (com * n as f64 - me) / (n - 1) as f64;
        let rel = others - me;
        if e.norm() > 0.0 && rel.norm() > 0.0 {
            let angle = (e.dot(&rel) / (e.norm() * rel.norm()))
                .clamp(-1.0, 1.0)
                .acos();
            let vision = std::f64::consts::FRAC_PI_2;
            if angle > vision {
                force -= e * ((angle - vision) * f.force_group_gaze);
            }
        }
        // Coherence: back towards the centre of mass once farther from it
        // than (n - 1) / 2.
        let rel = com - me;
        if rel.norm() >= (n as f64 - 1.0) / 2.0 {
            force += unit(rel) * f.force_group_coherence;
        }
        // Repulsion: away from each member nearer than the overlap
        // distance.
        for &m in members {
            if m == k {
                continue;
            }
            let d = me - v(self.people[m].position);
            if d.norm() < f.group_overlap {
                force += d * f.force_group_repulsion;
            }
        }
        force
    }

    /// Marks in `out`, one flag per person, the people who may be within
    /// `margin` of a robot's disc (`bodies`, the tick's start as given to
    /// [`Crowd::begin_tick`], robots first): every one that is, and others
    /// near. Asks the grid of the last [`Crowd::begin_tick`]; without one
    /// (or with a margin wider than its cells), marks everyone.
    pub fn near_robots(
        &self,
        bodies: &[BodyState],
        margin: f64,
        out: &mut Vec<bool>,
        near: &mut Vec<u32>,
    ) {
        out.clear();
        out.resize(self.people.len(), false);
        for b in bodies.iter().take(self.robots) {
            if !(self.gridded && self.grid.near(b.position, margin + b.radius, near)) {
                out.fill(true);
                return;
            }
            for &j in near.iter() {
                if let Some(flag) = (j as usize)
                    .checked_sub(self.first)
                    .and_then(|k| out.get_mut(k))
                {
                    *flag = true;
                }
            }
        }
    }

    /// The largest speed of any person over the current tick.
    pub fn top_speed(&self) -> f64 {
        self.people
            .iter()
            .map(|p| p.velocity[0] * p.velocity[0] + p.velocity[1] * p.velocity[1])
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// One physics substep of `h`: every person moves at its velocity.
    pub fn advance(&mut self, h: f64) {
        for p in &mut self.people {
            p.position[0] += p.velocity[0] * h;
            p.position[1] += p.velocity[1] * h;
        }
    }
}

/// The heading from `from` to `to`, rad.
fn facing(from: [f64; 2], to: [f64; 2]) -> f64 {
    (to[1] - from[1]).atan2(to[0] - from[0])
}

/// `d / |d|`, or zero for a zero vector (libpedsim's `normalized`).
fn unit(d: Vec2) -> Vec2 {
    let n = d.norm();
    if n > 0.0 { d / n } else { d }
}

/// The angle in (-pi, pi] (libpedsim's `Tangle`).
fn wrap(a: f64) -> f64 {
    let mut a = a;
    while a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    }
    while a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    }
    a
}

/// Moussaid et al. 2009's interaction of a pedestrian with another at
/// `diff` (the other's position less its own) whose velocity differs by
/// `vel_diff` (its own less the other's), as libpedsim's `socialForce`
/// computes it: the interaction direction t = normalise(lambda vel_diff +
/// diff / |diff|), lambda = 2, of length D; B = gamma D, gamma = 0.35;
/// theta the angle from t to diff; the force -exp(-|diff| / B - (n' B
/// theta)^2) t - sign(theta) exp(-|diff| / B - (n B theta)^2) t_left, with
/// n = 2, n' = 3. Zero when t is undefined (both vectors zero).
pub fn moussaid(diff: Vec2, vel_diff: Vec2) -> Vec2 {
    const LAMBDA: f64 = 2.0;
    const GAMMA: f64 = 0.35;
    const N: f64 = 2.0;
    const N_PRIME: f64 = 3.0;
    let direction = unit(diff);
    let interaction = vel_diff * LAMBDA + direction;
    let length = interaction.norm();
    if length == 0.0 {
        return Vec2::zeros();
    }
    let t = interaction / length;
    // The angle from t to the direction, in (-pi, pi]: libpedsim takes it
    // as the difference of the two vectors' angles, wrapped; one atan2 of
    // their cross and dot products is the same angle.
    let theta = match (t.x * direction.y - t.y * direction.x).atan2(t.dot(&direction)) {
        a if a == -std::f64::consts::PI => std::f64::consts::PI,
        a => a,
    };
    let b = GAMMA * length;
    let d = diff.norm();
    let velocity_amount = -(-d / b - (N_PRIME * b * theta).powi(2)).exp();
    let sign = if theta == 0.0 { 0.0 } else { theta.signum() };
    let angle_amount = -sign * (-d / b - (N * b * theta).powi(2)).exp();
    let left = Vec2::new(-t.y, t.x);
    t * velocity_amount + left * angle_amount
}
