//! Scripted obstacles in a whole world: random and intentional motion
//! repeat with the scenario's seed, and a pursuer closes on its robot.

use mrsim_world::World;
use mrsim_world::physics::Contact;

const SCENARIO: &str = r#"
[world]
dt = 0.1
duration = 5.0
seed = SEED

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [1.0, 0.0]

[[obstacle]]
name = "wanderer"
start = [5.0, 5.0]
radius = 0.2
motion = { model = "random", accel_sigma = 1.0, alpha1 = 0.5, beta1 = 1.0, max_speed = 1.0 }

[[obstacle]]
name = "hunter"
start = [6.0, 0.0]
radius = 0.2
motion = { model = "intentional", behavior = "pursue", target = "r0", max_speed = 1.0, max_accel = 2.0 }
"#;

fn obstacle_track(seed: u64, ticks: usize) -> Vec<[f64; 2]> {
    let src = SCENARIO.replace("SEED", &seed.to_string());
    let loaded = mrsim_scenario::parse(&src, "inline.toml").expect("valid scenario");
    let mut world = World::new(&loaded.scenario).expect("world");
    let mut contacts: Vec<Contact> = Vec::new();
    let mut out = Vec::new();
    for _ in 0..ticks {
        world.step(&mut contacts);
        out.extend(world.states()[1..].iter().map(|s| s.position));
    }
    out
}

#[test]
fn the_same_seed_moves_the_obstacles_the_same_and_another_seed_differently() {
    assert_eq!(obstacle_track(7, 30), obstacle_track(7, 30));
    assert_ne!(obstacle_track(7, 30), obstacle_track(8, 30));
}

#[test]
fn a_pursuer_in_the_world_closes_on_its_robot() {
    let track = obstacle_track(1, 30);
    let hunter = track[track.len() - 1];
    // 3 s at up to 1 m/s from 6 m away (the robot stands still, braking).
    assert!(hunter[0] < 4.0 && hunter[0] > 2.0, "{hunter:?}");
}
