//! A synchronous, single-threaded stepping engine for learning
//! environments (Gymnasium, PettingZoo): the caller supplies the commands of
//! some robots, the *learners*, each tick; every other robot is driven inline
//! by its built-in planner (the agents crate's [`Observer`] and the planner
//! the scenario names, no transport, no threads); the [`World`] is stepped
//! once per [`Sim::step`].
//!
//! A learner's command goes through the world's actuator model exactly as
//! an agent's would (acceleration then speed clamped to the robot's limits),
//! so a policy cannot move a robot faster than the scenario allows.
//!
//! Observation vectors ([`Sim::observe_f32`], [`Sim::observe_f64`]) are of
//! fixed size `4 + 6 k` per learner, in the learner's frame: origin at its
//! centre, axes parallel to the world's (a disc has no orientation), so
//! `[goal_dx, goal_dy, vx, vy]` then, for each of the `k` nearest other
//! bodies (robots and obstacles within its sensing range, nearest centre
//! first, ties by id), `[dx, dy, dvx, dvy, radius, 1]`: its position and
//! velocity relative to the learner's, its radius, and 1 for "present";
//! missing neighbours are all zeros. A rectangle's or polygon's radius is
//! its circumscribed one (the vector stays of one size whatever the
//! shapes); the built-in robots' planners see every body's shape and
//! heading ([`mrsim_planners::Sensed`]).

use crate::error::Invalid;
use crate::validate::{ScenarioSource, Validated};
use mrsim_agents::observe::Observer;
use mrsim_planners::{Command, DesignatedPath, Planner, Registry, Segment, Vec2};
use mrsim_proto::{BodyState, SnapshotHeader};
use mrsim_scenario::Scenario;
use mrsim_world::physics::{Contact, Owner};
use mrsim_world::{Applied, World};
use std::sync::Arc;

/// Why a simulation could not be built or stepped.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The scenario (or a seed override of it) was refused.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// A learner named is not a robot of the scenario.
    #[error("no robot `{0}` in the scenario (learners must name robots)")]
    UnknownLearner(String),
    /// A robot was named twice as a learner.
    #[error("robot `{0}` is named twice as a learner")]
    DuplicateLearner(String),
    /// A built-in robot's planner could not be built.
    #[error("robot `{robot}`: {source}")]
    Planner {
        /// The robot.
        robot: String,
        /// Why.
        source: mrsim_planners::BuildError,
    },
    /// The world could not be built.
    #[error(transparent)]
    World(#[from] mrsim_world::WorldError),
    /// Not one command per learner.
    #[error("{got} commands for {expected} learners")]
    CommandCount {
        /// Commands given.
        got: usize,
        /// Learners.
        expected: usize,
    },
    /// A learner's command is NaN or infinite.
    #[error("robot `{robot}` at tick {tick}: non-finite command {value:?}")]
    NonFinite {
        /// The robot.
        robot: String,
        /// The tick it was meant for.
        tick: u64,
        /// The command.
        value: [f64; 2],
    },
    /// The output buffer has the wrong length.
    #[error("observation buffer of {got} values, {expected} needed")]
    BufferSize {
        /// Its length.
        got: usize,
        /// Learners times observation size.
        expected: usize,
    },
}

/// What happened to one learner in the last tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LearnerInfo {
    /// Collisions of this robot that started during the tick (with robots,
    /// obstacles or walls).
    pub collisions: u32,
    /// Distance from its centre to its goal after the tick.
    pub distance_to_goal: f64,
    /// Within its goal tolerance now (and of its goal heading, if it has
    /// one).
    pub at_goal: bool,
    /// Has been within its goal tolerance for `goal_hold_ticks` ticks
    /// running at some point (the world's goal test; stays true).
    pub reached: bool,
}

/// A robot driven by its built-in planner.
struct Builtin {
    index: usize,
    planner: Box<dyn Planner>,
    observer: Observer,
    path: Option<DesignatedPath>,
}

/// The values per learner in an observation vector with `k` neighbours.
pub fn observation_size(k: usize) -> usize {
    4 + 6 * k
}

/// The stepping engine; see the module documentation.
pub struct Sim {
    source: ScenarioSource,
    registry: Arc<Registry>,
    scenario: Scenario,
    world: World,
    learners: Vec<usize>,
    builtins: Vec<Builtin>,
    walls: Arc<[Segment]>,
    contacts: Vec<Contact>,
    /// Per robot: ticks running within the goal tolerance, and reached.
    hold: Vec<(u32, bool)>,
    info: Vec<LearnerInfo>,
    /// Scratch for the neighbour search: (squared centre distance, body).
    near: Vec<(f64, usize)>,
}

impl Sim {
    /// A simulation of `validated` in which the robots named `learners` take
    /// their commands from the caller (in this order) and the others follow
    /// their planners (built from `validated`'s registry; a learner's
    /// planner, `external` included, is never built).
    pub fn new(validated: Validated, learners: &[String]) -> Result<Self, SimError> {
        let source = validated.source().clone();
        let registry = validated.registry().clone();
        let (scenario, world) = validated.into_world();
        let mut learner_ids = Vec::with_capacity(learners.len());
        for name in learners {
            let i = scenario
                .robot_index(name)
                .ok_or_else(|| SimError::UnknownLearner(name.clone()))?;
            if learner_ids.contains(&i) {
                return Err(SimError::DuplicateLearner(name.clone()));
            }
            learner_ids.push(i);
        }
        let mut sim = Self {
            source,
            registry,
            walls: Arc::from([]),
            builtins: Vec::new(),
            contacts: Vec::new(),
            hold: Vec::new(),
            info: Vec::new(),
            near: Vec::new(),
            learners: learner_ids,
            scenario,
            world,
        };
        sim.rebuild_drivers()?;
        Ok(sim)
    }

    /// Starts the episode again from the scenario's initial state; with a
    /// seed, from the scenario loaded again with `world.seed` set to it (so
    /// generated starts, obstacle motion and sensing noise follow it).
    pub fn reset(&mut self, seed: Option<u64>) -> Result<(), SimError> {
        match seed {
            Some(seed) => {
                let mut source = self.source.clone();
                source.set.push(format!("world.seed={seed}"));
                let (scenario, world) =
                    Validated::with_registry(source, self.registry.clone())?.into_world();
                self.scenario = scenario;
                self.world = world;
            }
            None => self.world = World::new(&self.scenario)?,
        }
        self.rebuild_drivers()
    }

    /// Planners, observers and counters as at the start of an episode.
    fn rebuild_drivers(&mut self) -> Result<(), SimError> {
        let s = &self.scenario;
        self.walls = mrsim_agents::observe::walls_of(&s.walls, s.world.arena);
        let shapes = mrsim_agents::observe::shapes_of(s);
        self.builtins.clear();
        let scene = mrsim_agents::route::RouteScene::of(s);
        for (i, spec) in s.robots.iter().enumerate() {
            if self.learners.contains(&i) {
                continue;
            }
            let fail = |source| SimError::Planner {
                robot: spec.name.clone(),
                source,
            };
            let planner = mrsim_agents::build_planner_in(&self.registry, spec).map_err(fail)?;
            let planner = mrsim_agents::route::fit_route(planner, spec, &scene).map_err(|e| {
                fail(mrsim_planners::BuildError::Other(format!(
                    "route from start to goal: {e}"
                )))
            })?;
            let planner = mrsim_agents::fit_goal_heading(spec, planner);
            self.builtins.push(Builtin {
                index: i,
                planner,
                observer: Observer::for_robot(
                    &s.world,
                    Some(spec),
                    i,
                    s.body_count(),
                    self.walls.clone(),
                    shapes.clone(),
                ),
                path: (!spec.path.is_empty()).then(|| DesignatedPath {
                    points: spec.path.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
                    boundary: spec.boundary.unwrap_or(f64::INFINITY),
                }),
            });
        }
        self.hold = vec![(0, false); s.robots.len()];
        self.info = vec![LearnerInfo::default(); self.learners.len()];
        self.update_info();
        Ok(())
    }

    /// One tick: `commands[j]` for learner `j`, the built-in robots' plans,
    /// one world step. Returns each learner's [`LearnerInfo`].
    pub fn step(&mut self, commands: &[Applied]) -> Result<&[LearnerInfo], SimError> {
        if commands.len() != self.learners.len() {
            return Err(SimError::CommandCount {
                got: commands.len(),
                expected: self.learners.len(),
            });
        }
        for (&i, c) in self.learners.iter().zip(commands) {
            let v = match *c {
                Applied::Force(v)
                | Applied::Velocity(v)
                | Applied::Unicycle(v)
                | Applied::Ackermann(v) => v,
            };
            if !v.iter().all(|x| x.is_finite()) {
                return Err(SimError::NonFinite {
                    robot: self.scenario.robots[i].name.clone(),
                    tick: self.world.tick(),
                    value: v,
                });
            }
        }
        for (&i, c) in self.learners.iter().zip(commands) {
            self.world.set_command(i, *c);
        }
        let header = SnapshotHeader {
            tick: self.world.tick(),
            sim_time: self.world.time(),
            body_count: self.world.states().len() as u32,
            ..Default::default()
        };
        for b in &mut self.builtins {
            let spec = &self.scenario.robots[b.index];
            let obs = b
                .observer
                .observe(&header, self.world.states(), spec, b.path.as_ref());
            let cmd = match b.planner.plan(&obs) {
                Command::Force(f) => Applied::Force([f.x, f.y]),
                Command::Velocity(v) => Applied::Velocity([v.x, v.y]),
                Command::Unicycle { v, omega } => Applied::Unicycle([v, omega]),
                Command::Ackermann { speed, steering } => Applied::Ackermann([speed, steering]),
            };
            // A planner's NaN brakes its robot, as the world does with an
            // agent's non-finite command.
            let cmd = match cmd {
                Applied::Force(v)
                | Applied::Velocity(v)
                | Applied::Unicycle(v)
                | Applied::Ackermann(v)
                    if !v.iter().all(|x| x.is_finite()) =>
                {
                    Applied::BRAKE
                }
                c => c,
            };
            self.world.set_command(b.index, cmd);
        }
        self.world.step(&mut self.contacts);
        for info in &mut self.info {
            info.collisions = 0;
        }
        for c in &self.contacts {
            for o in [c.a, c.b] {
                if let Owner::Robot(r) = o
                    && let Some(j) = self.learners.iter().position(|&l| l == r)
                {
                    self.info[j].collisions += 1;
                }
            }
        }
        self.update_info();
        Ok(&self.info)
    }

    /// The goal test and distances after a tick (or at the start).
    fn update_info(&mut self) {
        let states = self.world.states();
        for (i, spec) in self.scenario.robots.iter().enumerate() {
            let h = &mut self.hold[i];
            if spec.at_goal(states[i].position, states[i].heading) && self.world.tick() > 0 {
                h.0 += 1;
                if h.0 >= spec.goal_hold_ticks.max(1) {
                    h.1 = true;
                }
            } else {
                h.0 = 0;
            }
        }
        for (j, &i) in self.learners.iter().enumerate() {
            let spec = &self.scenario.robots[i];
            let p = states[i].position;
            let d = (spec.goal[0] - p[0]).hypot(spec.goal[1] - p[1]);
            let info = &mut self.info[j];
            info.distance_to_goal = d;
            info.at_goal = spec.at_goal(p, states[i].heading);
            info.reached = self.hold[i].1;
        }
    }

    /// Fills `out` (learners × [`observation_size`]`(k)`, row by learner)
    /// with every learner's observation vector, as f32.
    pub fn observe_f32(&mut self, k: usize, out: &mut [f32]) -> Result<(), SimError> {
        self.observe_into(k, out, |x| x as f32)
    }

    /// [`Self::observe_f32`] as f64.
    pub fn observe_f64(&mut self, k: usize, out: &mut [f64]) -> Result<(), SimError> {
        self.observe_into(k, out, |x| x)
    }

    fn observe_into<T: Copy + Default>(
        &mut self,
        k: usize,
        out: &mut [T],
        conv: impl Fn(f64) -> T,
    ) -> Result<(), SimError> {
        let size = observation_size(k);
        let expected = size * self.learners.len();
        if out.len() != expected {
            return Err(SimError::BufferSize {
                got: out.len(),
                expected,
            });
        }
        let states = self.world.states();
        for (row, &i) in out.chunks_exact_mut(size).zip(&self.learners) {
            let spec = &self.scenario.robots[i];
            let me = &states[i];
            let (p, v) = (me.position, me.velocity);
            row[0] = conv(spec.goal[0] - p[0]);
            row[1] = conv(spec.goal[1] - p[1]);
            row[2] = conv(v[0]);
            row[3] = conv(v[1]);
            self.near.clear();
            for (b, s) in states.iter().enumerate() {
                if b == i {
                    continue;
                }
                let (dx, dy) = (s.position[0] - p[0], s.position[1] - p[1]);
                let d2 = dx * dx + dy * dy;
                if d2.sqrt() - s.radius - spec.radius > spec.sensing_range {
                    continue;
                }
                self.near.push((d2, b));
            }
            let cmp = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            if self.near.len() > k && k > 0 {
                self.near.select_nth_unstable_by(k - 1, cmp);
                self.near.truncate(k);
            }
            self.near.truncate(k);
            self.near.sort_unstable_by(cmp);
            let slots = row[4..].chunks_exact_mut(6);
            let mut taken = self.near.iter();
            for slot in slots {
                match taken.next() {
                    Some(&(_, b)) => {
                        let s: &BodyState = &states[b];
                        slot[0] = conv(s.position[0] - p[0]);
                        slot[1] = conv(s.position[1] - p[1]);
                        slot[2] = conv(s.velocity[0] - v[0]);
                        slot[3] = conv(s.velocity[1] - v[1]);
                        slot[4] = conv(s.radius);
                        slot[5] = conv(1.0);
                    }
                    None => slot.fill(T::default()),
                }
            }
        }
        Ok(())
    }

    /// The scenario of the current episode.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The world of the current episode (states, walls, tick, time).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The learners' robot indices, in command order.
    pub fn learners(&self) -> &[usize] {
        &self.learners
    }

    /// Each learner's [`LearnerInfo`] after the last tick.
    pub fn info(&self) -> &[LearnerInfo] {
        &self.info
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crossing(learners: &[&str]) -> Sim {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/crossing.toml");
        let v = Validated::new(ScenarioSource {
            path: Some(path.into()),
            ..Default::default()
        })
        .expect("crossing.toml is valid");
        let names: Vec<String> = learners.iter().map(|s| s.to_string()).collect();
        Sim::new(v, &names).expect("a sim of crossing")
    }

    fn episode(sim: &mut Sim, seed: u64, ticks: usize) -> Vec<f64> {
        sim.reset(Some(seed)).expect("reset");
        let mut trace = Vec::new();
        let mut obs = vec![0.0; observation_size(3)];
        for t in 0..ticks {
            let a = Applied::Velocity([0.5 + 0.01 * t as f64, 0.2]);
            sim.step(&[a]).expect("step");
            sim.observe_f64(3, &mut obs).expect("observe");
            trace.extend_from_slice(&obs);
            trace.extend(sim.world().states().iter().flat_map(|s| s.position));
        }
        trace
    }

    #[test]
    fn one_seed_gives_identical_episodes() {
        let mut sim = crossing(&["a0"]);
        let a = episode(&mut sim, 7, 60);
        let b = episode(&mut sim, 7, 60);
        assert_eq!(a, b);
        assert!(a.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn a_learners_command_is_held_to_the_robots_limits() {
        let mut sim = crossing(&["a0"]);
        let max_speed = sim.scenario().robots[0].max_speed;
        for _ in 0..30 {
            sim.step(&[Applied::Velocity([100.0, 0.0])]).expect("step");
            let v = sim.world().states()[0].velocity;
            assert!(v[0].hypot(v[1]) <= max_speed * (1.0 + 1e-6), "{v:?}");
        }
        let v = sim.world().states()[0].velocity;
        assert!(v[0] > 0.9 * max_speed, "it does speed up: {v:?}");
    }

    #[test]
    fn a_non_finite_command_is_refused_naming_robot_and_tick() {
        let mut sim = crossing(&["a1"]);
        sim.step(&[Applied::Velocity([0.0, 0.0])]).expect("step");
        let e = sim
            .step(&[Applied::Force([f64::NAN, 0.0])])
            .expect_err("NaN is refused")
            .to_string();
        assert!(e.contains("a1") && e.contains("tick 1"), "{e}");
        let e = sim.step(&[]).expect_err("one command per learner");
        assert!(matches!(
            e,
            SimError::CommandCount {
                got: 0,
                expected: 1
            }
        ));
    }

    #[test]
    fn the_observation_holds_the_goal_and_the_nearest_bodies_padded() {
        let mut sim = crossing(&["a0"]);
        let k = 10;
        let mut obs = vec![f32::NAN; observation_size(k)];
        sim.observe_f32(k, &mut obs).expect("observe");
        // a0 starts at (-4, 0), goal (7, 0); a1 is 1 m behind it.
        assert_eq!(&obs[..4], &[11.0, 0.0, 0.0, 0.0]);
        assert_eq!(&obs[4..10], &[-1.0, 0.0, 0.0, 0.0, 0.25, 1.0]);
        // Seven other robots: the last three slots are padding.
        assert!(obs[4 + 6 * 7..].iter().all(|&x| x == 0.0));
        assert_eq!(obs[4 + 6 * 6 + 5], 1.0);
        let mut short = vec![0.0f32; 3];
        assert!(matches!(
            sim.observe_f32(k, &mut short),
            Err(SimError::BufferSize { .. })
        ));
    }

    #[test]
    fn unknown_or_repeated_learners_are_refused() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/crossing.toml");
        let v = || {
            Validated::new(ScenarioSource {
                path: Some(path.into()),
                ..Default::default()
            })
            .expect("valid")
        };
        assert!(matches!(
            Sim::new(v(), &["zz".into()]),
            Err(SimError::UnknownLearner(_))
        ));
        assert!(matches!(
            Sim::new(v(), &["a0".into(), "a0".into()]),
            Err(SimError::DuplicateLearner(_))
        ));
    }

    #[test]
    fn built_in_robots_drive_to_their_goals_while_the_learner_stands_still() {
        let mut sim = crossing(&["a0"]);
        let ticks = (sim.scenario().world.duration / sim.scenario().world.dt) as usize;
        for _ in 0..ticks {
            sim.step(&[Applied::BRAKE]).expect("step");
        }
        let s = sim.world().states();
        let goal = sim.scenario().robots[7].goal;
        let d = (s[7].position[0] - goal[0]).hypot(s[7].position[1] - goal[1]);
        // b3 starts 11 m from its goal, behind three robots of its stream.
        assert!(d < 1.0, "b3 ends {d} m from its goal");
        assert!(!sim.info()[0].reached);
    }

    /// Stands still and keeps the bodies it sensed last.
    struct Seer(Arc<std::sync::Mutex<Vec<mrsim_planners::Sensed>>>);

    impl Planner for Seer {
        fn plan(&mut self, obs: &mrsim_planners::Observation) -> Command {
            if let Ok(mut seen) = self.0.lock() {
                *seen = obs.others.to_vec();
            }
            Command::Velocity(Vec2::zeros())
        }
    }

    #[test]
    fn a_built_in_robot_senses_a_turned_rectangle_and_the_learner_its_circumscribed_radius() {
        let dir = std::env::temp_dir().join(format!("mrsim-sim-box-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch folder");
        let path = dir.join("box.toml");
        std::fs::write(
            &path,
            r#"
[world]
dt = 0.1
[[robot]]
name = "learner"
start = [0.0, 2.0]
goal = [5.0, 2.0]
[[robot]]
name = "seer"
start = [0.0, 0.0]
goal = [0.0, -3.0]
planner = "seer"
[[obstacle]]
name = "box"
start = [3.0, 0.0]
shape = { kind = "rectangle", length = 2.0, width = 1.0 }
heading_deg = 30
motion = { model = "static" }
"#,
        )
        .expect("write the scenario");
        let seen = Arc::new(std::sync::Mutex::new(Vec::new()));
        let mut registry = Registry::builtin();
        let log = seen.clone();
        registry
            .register_simple("seer", "stands and notes", move || Seer(log.clone()))
            .expect("a new name");
        let v = Validated::with_registry(
            ScenarioSource {
                path: Some(path),
                ..Default::default()
            },
            Arc::new(registry),
        )
        .expect("valid");
        let mut sim = Sim::new(v, &["learner".into()]).expect("a sim");
        sim.step(&[Applied::Velocity([0.0, 0.0])]).expect("step");
        let seen = seen.lock().expect("what it sensed").clone();
        let b = seen.iter().find(|s| s.id == 2).expect("the box is sensed");
        let rect = mrsim_planners::Shape::Polygon(
            mrsim_planners::Polygon::rectangle(2.0, 1.0).expect("a rectangle"),
        );
        assert_eq!(b.shape, rect);
        assert!(
            (b.heading - 30f64.to_radians()).abs() < 1e-12,
            "{}",
            b.heading
        );
        assert!((b.radius - 1.25f64.sqrt()).abs() < 1e-12, "{}", b.radius);
        // The learner's vector: the box's radius slot is its circumscribed
        // radius (the seer, 2 m away, comes first; the box 3.6 m).
        let mut obs = vec![0.0; observation_size(2)];
        sim.observe_f64(2, &mut obs).expect("observe");
        assert!(
            (obs[10] - 3.0).abs() < 1e-6 && (obs[11] + 2.0).abs() < 1e-6,
            "{obs:?}"
        );
        assert!((obs[14] - 1.25f64.sqrt()).abs() < 1e-12, "{obs:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
