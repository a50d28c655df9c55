//! HuNavSim's six behaviours on constructed scenes, each against what its
//! definition says: a scared person keeps farther from a robot than a
//! regular one, a threatening one gets in front of the robot, a curious
//! one walks up to the robot and later walks on, a surprised one stops
//! while the robot is near, an impassive one does not make way.

use mrsim_world::physics::Contact;
use mrsim_world::{Applied, World};

/// One tick of the scene: the person's position, velocity and heading,
/// and the robot's position.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tick {
    at: [f64; 2],
    vel: [f64; 2],
    heading: f64,
    robot: [f64; 2],
}

/// A robot of radius 0.3 from `robot` driven at `robot_vel` (holonomic)
/// and one person walking from `start` to `goal` with `extra` lines
/// (its behaviour, its motion), `ticks` ticks of 0.1 s.
fn walk(
    robot: [f64; 2],
    robot_vel: [f64; 2],
    start: [f64; 2],
    goal: [f64; 2],
    extra: &str,
    ticks: usize,
) -> Vec<Tick> {
    let src = format!(
        "[world]\ndt = 0.1\nsubsteps = 1\nduration = 200.0\n\n\
         [[robot]]\nname = \"r0\"\nstart = [{:?}, {:?}]\ngoal = [100.0, 100.0]\nradius = 0.3\n\
         max_speed = 2.0\n\n\
         [[person]]\nname = \"h\"\nstart = [{:?}, {:?}]\ngoal = [{:?}, {:?}]\n{extra}\n",
        robot[0], robot[1], start[0], start[1], goal[0], goal[1]
    );
    let loaded = mrsim_scenario::parse(&src, "behaviours.toml").expect("valid scenario");
    let mut world = World::new(&loaded.scenario).expect("world");
    world.set_command(0, Applied::Velocity(robot_vel));
    let mut contacts: Vec<Contact> = Vec::new();
    (0..ticks)
        .map(|_| {
            world.step(&mut contacts);
            let s = world.states();
            Tick {
                at: s[1].position,
                vel: s[1].velocity,
                heading: s[1].heading,
                robot: s[0].position,
            }
        })
        .collect()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn closest(track: &[Tick]) -> f64 {
    track
        .iter()
        .map(|t| dist(t.at, t.robot))
        .fold(f64::INFINITY, f64::min)
}

const SF: &str = "motion = { model = \"social-force\" }\n";
const ORCA: &str = "motion = { model = \"orca\" }\n";

/// A person passing 0.5 m beside a robot standing at the origin.
fn pass_by(extra: &str) -> Vec<Tick> {
    walk([0.0, 0.0], [0.0, 0.0], [-6.0, 0.5], [6.0, 0.5], extra, 200)
}

#[test]
fn a_scared_person_keeps_farther_from_a_robot_than_a_regular_one() {
    for motion in [SF, ORCA] {
        let regular = closest(&pass_by(motion));
        let scared = closest(&pass_by(&format!("behavior = \"scared\"\n{motion}")));
        println!(
            "{}: regular {regular:.3} m, scared {scared:.3} m",
            motion.trim()
        );
        assert!(
            scared > regular + 0.5,
            "{motion}: regular {regular}, scared {scared}"
        );
    }
}

#[test]
fn a_threatening_person_gets_in_front_of_a_moving_robot() {
    // The robot drives +x along y = 0 at 0.5 m/s; the person walks -x
    // along y = 3, towards the robot's side.
    let drive = |extra: &str| walk([-5.0, 0.0], [0.5, 0.0], [3.0, 3.0], [-7.0, 3.0], extra, 120);
    // In the robot's way: within a body's width of its line, ahead of it
    // by less than 2 m.
    let in_the_way = |t: &Tick| {
        let ahead = t.at[0] - t.robot[0];
        (t.at[1] - t.robot[1]).abs() < 0.6 && ahead > 0.0 && ahead < 2.0
    };
    for motion in [SF, ORCA] {
        let regular = drive(motion);
        let threatening = drive(&format!("behavior = \"threatening\"\n{motion}"));
        let blocking = threatening.iter().filter(|t| in_the_way(t)).count();
        println!("{}: blocking {blocking} ticks", motion.trim());
        assert_eq!(
            regular.iter().filter(|t| in_the_way(t)).count(),
            0,
            "{motion}"
        );
        // At least 3 s of the 12 s in the robot's way.
        assert!(blocking >= 30, "{motion}: {blocking} ticks in the way");
    }
}

#[test]
fn a_curious_person_walks_up_to_a_robot_stops_at_its_distance_then_walks_on() {
    // The robot stands at the origin; the person's route passes 3 m
    // from it. HuNavSim's defaults: seen within 10 m, stop 1.5 m from it,
    // 40 s.
    for motion in [SF, ORCA] {
        let regular = walk([0.0, 0.0], [0.0, 0.0], [-8.0, 3.0], [8.0, 3.0], motion, 800);
        let curious = walk(
            [0.0, 0.0],
            [0.0, 0.0],
            [-8.0, 3.0],
            [8.0, 3.0],
            &format!("behavior = \"curious\"\n{motion}"),
            800,
        );
        let near_r = closest(&regular);
        assert!(near_r > 2.5, "{motion}: regular {near_r}");
        // It stood 1.5 m from the robot (HuNavSim's stop distance, less
        // at most the last tick's step) looking at it.
        let standing: Vec<&Tick> = curious.iter().filter(|t| t.vel == [0.0, 0.0]).collect();
        let first = curious
            .iter()
            .position(|t| t.vel == [0.0, 0.0])
            .unwrap_or(0);
        println!(
            "{}: regular {near_r:.3} m; curious stood {} ticks from {:.1} s, {:.3} m from the robot",
            motion.trim(),
            standing.len(),
            first as f64 * 0.1,
            standing.first().map_or(0.0, |t| dist(t.at, t.robot)),
        );
        assert!(standing.len() > 100, "{motion}: {}", standing.len());
        for t in &standing {
            let d = dist(t.at, t.robot);
            assert!(d > 1.4 && d <= 1.5, "{motion}: stood {d} m from the robot");
            let to_robot = (t.robot[1] - t.at[1]).atan2(t.robot[0] - t.at[0]);
            assert!((t.heading - to_robot).abs() < 1e-9, "{t:?}");
        }
        // Then, its 40 s over, it walked on to its goal.
        let end = curious.last().map(|t| t.at).unwrap_or_default();
        assert!(dist(end, [8.0, 3.0]) < 0.5, "{motion}: ends at {end:?}");
    }
}

#[test]
fn a_surprised_person_stops_and_faces_the_robot_while_it_is_near() {
    // The robot stands at the origin, on the person's way: the person
    // stops once within 4 m of it, for HuNavSim's 30 s, then walks on.
    for motion in [SF, ORCA] {
        let track = walk(
            [0.0, 0.0],
            [0.0, 0.0],
            [-8.0, 0.5],
            [8.0, 0.5],
            &format!("behavior = \"surprised\"\n{motion}"),
            600,
        );
        let stopped: Vec<&Tick> = track.iter().filter(|t| t.vel == [0.0, 0.0]).collect();
        println!("{}: stopped {} ticks", motion.trim(), stopped.len());
        // 30 s of 0.1 s ticks, give or take the tick it starts on.
        assert!(
            (299..=301).contains(&stopped.len()),
            "{motion}: {}",
            stopped.len()
        );
        for t in &stopped {
            let d = dist(t.at, t.robot);
            assert!(
                d <= 4.0 && d > 3.8,
                "{motion}: stopped {d} m from the robot"
            );
            let to_robot = (t.robot[1] - t.at[1]).atan2(t.robot[0] - t.at[0]);
            assert!((t.heading - to_robot).abs() < 1e-9, "{t:?}");
        }
        // A regular person does not stop.
        let regular = walk([0.0, 0.0], [0.0, 0.0], [-8.0, 0.5], [8.0, 0.5], motion, 100);
        assert!(
            regular.iter().skip(1).all(|t| t.vel != [0.0, 0.0]),
            "{motion}"
        );
    }
}

#[test]
fn an_impassive_person_does_not_make_way_where_a_regular_one_does() {
    // The robot stands 0.3 m beside the person's straight line, in its
    // way; how far off its line the person is while still more than a
    // metre short of the robot.
    let route = |extra: &str| walk([0.0, 0.3], [0.0, 0.0], [-6.0, 0.0], [6.0, 0.0], extra, 200);
    let early = |track: &[Tick]| {
        track
            .iter()
            .filter(|t| t.at[0] < -1.0)
            .map(|t| t.at[1].abs())
            .fold(0.0, f64::max)
    };
    for motion in [SF, ORCA] {
        let regular = route(motion);
        let impassive = route(&format!("behavior = \"impassive\"\n{motion}"));
        let (dr, di) = (early(&regular), early(&impassive));
        println!(
            "{}: off its line a metre short of the robot: regular {dr:.3} m, impassive {di:.3} m; \
             closest {:.3} / {:.3}",
            motion.trim(),
            closest(&regular),
            closest(&impassive)
        );
        assert!(dr > 0.2, "{motion}: regular {dr}");
        assert!(di < dr / 2.0, "{motion}: regular {dr}, impassive {di}");
        // It does not walk into the robot either (contact at 0.6 m, less
        // one tick's step into it).
        assert!(
            closest(&impassive) > 0.5,
            "{motion}: {}",
            closest(&impassive)
        );
    }
}

#[test]
fn a_person_who_does_not_see_robots_walks_as_a_regular_one_whatever_its_behavior() {
    let blind = |b: &str| pass_by(&format!("sees_robots = false\n{b}{SF}"));
    let regular = blind("");
    for b in ["impassive", "surprised", "scared", "curious", "threatening"] {
        assert_eq!(blind(&format!("behavior = \"{b}\"\n")), regular, "{b}");
    }
}
