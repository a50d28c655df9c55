//! People in a whole world: ORCA people step as the `orca` planner's
//! agents under RVO2's `doStep`, a person who does not see robots walks as
//! if there were none, and people are bodies of kind person.

use mrsim_planners::orca::Orca;
use mrsim_planners::{
    BodyKind, Command, Kinematics, Observation, Planner, SelfState, Sensed, Shape, Vec2,
};
use mrsim_proto::body_kind;
use mrsim_world::World;
use mrsim_world::physics::Contact;

/// `n` people on a circle of radius `r` about the origin, each start
/// moved by up to `jitter` in x and y (a fixed-seed generator), each
/// going to its antipode; and one robot far away.
fn circle(
    n: usize,
    r: f64,
    jitter: f64,
    max_neighbors: usize,
) -> (String, Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let mut state: u64 = 12345;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut src = String::from(
        "[world]\ndt = 0.25\nsubsteps = 1\nduration = 40.0\n\n\
         [[robot]]\nname = \"far\"\nstart = [100.0, 100.0]\ngoal = [100.0, 100.0]\n",
    );
    let (mut starts, mut goals) = (Vec::new(), Vec::new());
    for i in 0..n {
        let a = i as f64 * std::f64::consts::TAU / n as f64;
        let on = [r * a.cos(), r * a.sin()];
        let start = [on[0] + uniform() * jitter, on[1] + uniform() * jitter];
        let goal = [-on[0], -on[1]];
        src += &format!(
            "\n[[person]]\nname = \"h{i}\"\nstart = [{:?}, {:?}]\ngoal = [{:?}, {:?}]\n\
             radius = 0.3\npreferred_speed = 1.0\n\
             motion = {{ model = \"orca\", neighbor_dist = 10.0, max_neighbors = {max_neighbors}, \
             time_horizon = 5.0, time_horizon_obst = 5.0 }}\n",
            start[0], start[1], goal[0], goal[1]
        );
        starts.push(start);
        goals.push(goal);
    }
    (src, starts, goals)
}

/// RVO2's `doStep` over agents planned by the `orca` planner: every agent
/// plans on the same state, then each takes its new velocity exactly and
/// moves p += v dt. Ids are the world's (the robot is body 0).
struct Rvo2Step {
    planners: Vec<Orca>,
    position: Vec<Vec2>,
    velocity: Vec<Vec2>,
    goals: Vec<Vec2>,
    dt: f64,
    tick: u64,
}

impl Rvo2Step {
    fn step(&mut self) {
        let n = self.position.len();
        let mut next = Vec::with_capacity(n);
        for i in 0..n {
            let others: Vec<Sensed> = (0..n)
                .filter(|&j| j != i)
                .map(|j| {
                    Sensed::disc(
                        1 + j as u32,
                        BodyKind::Person,
                        self.position[j],
                        self.velocity[j],
                        0.3,
                    )
                })
                .collect();
            let obs = Observation {
                tick: self.tick,
                time: self.tick as f64 * self.dt,
                dt: self.dt,
                me: SelfState {
                    id: 1 + i as u32,
                    position: self.position[i],
                    velocity: self.velocity[i],
                    radius: 0.3,
                    shape: Shape::disc(0.3),
                    mass: 1.0,
                    damping: 0.0,
                    max_speed: 1.0,
                    max_accel: 1e12,
                    heading: 0.0,
                    angular_velocity: 0.0,
                    steering: 0.0,
                    kinematics: Kinematics::Holonomic,
                },
                goal: self.goals[i],
                goal_tolerance: 0.1,
                goal_hold_ticks: 1,
                others: &others,
                walls: &[],
                path: None,
                scan: None,
            };
            match self.planners[i].plan(&obs) {
                Command::Velocity(v) => next.push(v),
                other => panic!("orca answers a velocity, not {other:?}"),
            }
        }
        for ((v, p), nv) in self.velocity.iter_mut().zip(&mut self.position).zip(&next) {
            *v = *nv;
            *p += nv * self.dt;
        }
        self.tick += 1;
    }
}

#[test]
fn orca_people_walk_step_for_step_as_orca_agents_under_rvo2s_do_step() {
    let n = 12;
    let (src, starts, goals) = circle(n, 5.0, 0.1, 5);
    let loaded = mrsim_scenario::parse(&src, "circle.toml").expect("valid scenario");
    let mut world = World::new(&loaded.scenario).expect("world");
    let mut reference = Rvo2Step {
        planners: (0..n).map(|_| Orca::new(10.0, 5, 5.0, 5.0, 1.0)).collect(),
        position: starts.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
        velocity: vec![Vec2::zeros(); n],
        goals: goals.iter().map(|g| Vec2::new(g[0], g[1])).collect(),
        dt: 0.25,
        tick: 0,
    };
    let mut contacts: Vec<Contact> = Vec::new();
    for tick in 0..120 {
        world.step(&mut contacts);
        reference.step();
        for i in 0..n {
            let s = world.states()[1 + i];
            assert_eq!(s.kind, body_kind::PERSON);
            let want = reference.position[i];
            assert_eq!(s.position, [want.x, want.y], "person {i} at tick {tick}");
            let v = reference.velocity[i];
            assert_eq!(s.velocity, [v.x, v.y], "person {i} at tick {tick}");
        }
    }
    // 30 s: everyone has crossed the 10 m circle and come to rest at its
    // antipode (the comparison above is not of people standing still).
    for (i, g) in goals.iter().enumerate() {
        let p = world.states()[1 + i].position;
        assert!(
            (p[0] - g[0]).hypot(p[1] - g[1]) < 0.3,
            "person {i} at {p:?}, goal {g:?}"
        );
    }
}

const CROSSING: &str = r#"
[world]
dt = 0.1
substeps = 10
duration = 12.0

[[robot]]
name = "r0"
start = ROBOT
goal = ROBOT
radius = 0.3

[[person]]
name = "h0"
start = [-4.0, 0.0]
goal = [4.0, 0.0]
sees_robots = SEES

[[person]]
name = "h1"
start = [-4.0, 2.0]
goal = [4.0, 2.0]
sees_robots = SEES
"#;

/// The people's positions, tick by tick, and the robot's, with the robot
/// starting at `robot` and the people seeing robots or not.
fn crossing(robot: &str, sees: bool) -> (Vec<[[f64; 2]; 2]>, Vec<[f64; 2]>) {
    let src = CROSSING
        .replace("ROBOT", robot)
        .replace("SEES", &sees.to_string());
    let loaded = mrsim_scenario::parse(&src, "crossing.toml").expect("valid scenario");
    let mut world = World::new(&loaded.scenario).expect("world");
    let mut contacts: Vec<Contact> = Vec::new();
    let (mut people, mut robot) = (Vec::new(), Vec::new());
    for _ in 0..120 {
        world.step(&mut contacts);
        let s = world.states();
        people.push([s[1].position, s[2].position]);
        robot.push(s[0].position);
    }
    (people, robot)
}

fn nearest(track: &[[[f64; 2]; 2]], k: usize, p: [f64; 2]) -> f64 {
    track
        .iter()
        .map(|t| (t[k][0] - p[0]).hypot(t[k][1] - p[1]))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn people_who_do_not_see_robots_walk_through_a_robots_place_as_if_it_were_not_there() {
    let (blind, _) = crossing("[0.0, 0.0]", false);
    let (alone, _) = crossing("[50.0, 50.0]", false);
    // The same walk to the last bit, with the robot in the way or not.
    assert_eq!(blind, alone);
    // h0 walks straight through where the robot stood.
    assert!(nearest(&blind, 0, [0.0, 0.0]) < 0.01);
    // Seeing it, h0 walks around it instead.
    let (seeing, _) = crossing("[0.0, 0.0]", true);
    assert_ne!(seeing, blind);
    assert!(
        nearest(&seeing, 0, [0.0, 0.0]) > 0.4,
        "{}",
        nearest(&seeing, 0, [0.0, 0.0])
    );
}

#[test]
fn a_person_at_its_last_point_stays_and_cyclic_waypoints_start_over() {
    let src = r#"
[world]
dt = 0.1
duration = 30.0

[[robot]]
name = "r0"
start = [50.0, 50.0]
goal = [50.0, 50.0]

[[person]]
name = "stays"
start = [0.0, 0.0]
goal = [3.0, 0.0]

[[person]]
name = "loops"
start = [0.0, 10.0]
waypoints = [[3.0, 10.0], [3.0, 13.0], [0.0, 13.0], [0.0, 10.0]]
cyclic = true
"#;
    let loaded = mrsim_scenario::parse(src, "route.toml").expect("valid scenario");
    let mut world = World::new(&loaded.scenario).expect("world");
    let mut contacts: Vec<Contact> = Vec::new();
    let mut far_corner_visits = 0;
    let mut near_far_corner = false;
    for _ in 0..300 {
        world.step(&mut contacts);
        let p = world.states()[2].position;
        let near = (p[0] - 3.0).hypot(p[1] - 13.0) < 0.3;
        if near && !near_far_corner {
            far_corner_visits += 1;
        }
        near_far_corner = near;
    }
    let stays = world.states()[1];
    assert!((stays.position[0] - 3.0).abs() < 0.05 && stays.position[1].abs() < 1e-9);
    assert!(stays.velocity[0].abs() < 0.05, "{:?}", stays.velocity);
    // A loop of 12 m at 1 m/s, 30 s: the far corner twice at least.
    assert!(far_corner_visits >= 2, "{far_corner_visits}");
}

/// One tick's world of `people` (TOML tables) and a robot far away.
fn world_of(people: &str, dt: f64) -> World {
    let src = format!(
        "[world]\ndt = {dt:?}\nsubsteps = 1\nduration = 60.0\n\n\
         [[robot]]\nname = \"far\"\nstart = [100.0, 100.0]\ngoal = [100.0, 100.0]\n{people}"
    );
    let loaded = mrsim_scenario::parse(&src, "people.toml").expect("valid scenario");
    World::new(&loaded.scenario).expect("world")
}

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12
}

#[test]
fn a_lone_social_force_person_relaxes_to_its_desired_speed_as_computed_by_hand() {
    // From rest towards +x at v0 = 1, tau = 0.5, dt = 0.1, no one near,
    // no wall: a = (v0 - v) / tau, v += 0.1 a, x += 0.1 v.
    let mut world = world_of(
        "[[person]]\nname = \"h\"\nstart = [0.0, 0.0]\ngoal = [10.0, 0.0]\n\
         motion = { model = \"social-force\" }\n",
        0.1,
    );
    let mut contacts: Vec<Contact> = Vec::new();
    // v: 0.2, 0.36, 0.488; x: 0.02, 0.056, 0.1048.
    for (v, x) in [(0.2, 0.02), (0.36, 0.056), (0.488, 0.1048)] {
        world.step(&mut contacts);
        let s = world.states()[1];
        assert!(close(s.velocity, [v, 0.0]), "{:?}", s.velocity);
        assert!(close(s.position, [x, 0.0]), "{:?}", s.position);
    }
}

#[test]
fn two_social_force_people_at_rest_repel_as_moussaids_interaction_computed_by_hand() {
    // h0 at the origin heading +x, h1 one metre to its left, both at
    // rest: the interaction direction is the unit vector to the other,
    // theta = 0, B = 0.35, so the social force is -exp(-1 / 0.35) towards
    // the other, weighted 5.1; the desired force (1, 0) / 0.5.
    let mut world = world_of(
        "[[person]]\nname = \"h0\"\nstart = [0.0, 0.0]\ngoal = [10.0, 0.0]\n\
         motion = { model = \"social-force\" }\n\
         [[person]]\nname = \"h1\"\nstart = [0.0, 1.0]\ngoal = [0.0, 11.0]\n\
         motion = { model = \"social-force\" }\n",
        0.1,
    );
    let mut contacts: Vec<Contact> = Vec::new();
    world.step(&mut contacts);
    let push = 5.1 * (-1.0f64 / 0.35).exp();
    let a0 = [2.0, -push];
    let s = world.states();
    assert!(
        close(s[1].velocity, [0.1 * a0[0], 0.1 * a0[1]]),
        "{:?}",
        s[1].velocity
    );
    assert!(
        close(s[1].position, [0.01 * a0[0], 0.01 * a0[1]]),
        "{:?}",
        s[1].position
    );
    // h1, heading +y: pushed the other way, along its own walk.
    let a1 = [0.0, 2.0 + push];
    assert!(
        close(s[2].velocity, [0.1 * a1[0], 0.1 * a1[1]]),
        "{:?}",
        s[2].velocity
    );
}

/// The largest distance between two of the first `n` people over a walk
/// of `ticks` ticks.
fn spread(world: &mut World, n: usize, ticks: usize) -> f64 {
    let mut contacts: Vec<Contact> = Vec::new();
    let mut widest: f64 = 0.0;
    for _ in 0..ticks {
        world.step(&mut contacts);
        let s = world.states();
        for i in 1..=n {
            for j in i + 1..=n {
                let (a, b) = (s[i].position, s[j].position);
                widest = widest.max((a[0] - b[0]).hypot(a[1] - b[1]));
            }
        }
    }
    widest
}

#[test]
fn a_group_walks_together_where_the_same_people_alone_drift_apart() {
    // Three people of speeds 0.8, 1.0 and 1.3 m/s walk side by side for 20 s
    // towards goals 40 m on (none arrives).
    let people = |group: &str| {
        [(0.8, 0.0), (1.0, 0.8), (1.3, -0.8)]
            .iter()
            .enumerate()
            .map(|(k, (v, y))| {
                format!(
                    "[[person]]\nname = \"h{k}\"\nstart = [0.0, {y:?}]\ngoal = [40.0, {y:?}]\n\
                     preferred_speed = {v:?}\n{group}motion = {{ model = \"social-force\" }}\n"
                )
            })
            .collect::<String>()
    };
    let together = spread(&mut world_of(&people("group = \"g\"\n"), 0.1), 3, 200);
    let alone = spread(&mut world_of(&people(""), 0.1), 3, 200);
    // Alone, the fastest is 10 m ahead of the slowest after 20 s.
    assert!(alone > 8.0, "alone {alone}");
    // Together, pedsim's coherence holds each within about a metre of
    // the group's centre.
    assert!(together < 3.0, "together {together}");
}
