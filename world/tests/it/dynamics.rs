//! The world's own dynamics against numbers computed by hand: the force
//! model m r'' + b r' = f over one tick, the velocity lag's first-order
//! response, the max_accel and max_speed clamps, and the 1 mm contact rule
//! with its 10 mm hysteresis. Each world has dt = 0.1 s and 10 substeps
//! (h = 0.01 s), integrated by semi-implicit Euler: per substep
//! v += h a(v), then x += h v (rapier, f32).

use mrsim_world::physics::{Contact, Owner};
use mrsim_world::{Applied, World};

/// One robot at the origin with the given `[[robot]]` extra lines, and
/// `obstacles` appended as they are.
fn world(robot: &str, obstacles: &str) -> World {
    let src = format!(
        "[world]\ndt = 0.1\nsubsteps = 10\nduration = 10.0\n\n\
         [[robot]]\nname = \"r0\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n{robot}\n{obstacles}"
    );
    let loaded = mrsim_scenario::parse(&src, "inline.toml").expect("valid scenario");
    World::new(&loaded.scenario).expect("world")
}

/// Steps `n` ticks; returns every contact that started.
fn steps(w: &mut World, n: usize) -> Vec<Contact> {
    let mut all = Vec::new();
    let mut c = Vec::new();
    for _ in 0..n {
        w.step(&mut c);
        all.extend_from_slice(&c);
    }
    all
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn a_force_moves_the_robot_by_m_r_dd_plus_b_r_d_equals_f_over_one_tick() {
    // m = 2, b = 0.5, f = (1, 0) from rest. Per substep
    //   v <- v (1 - h b/m) + h f/m = 0.9975 v + 0.005,
    // so after 10 substeps v = (f/b)(1 - 0.9975^10) = 2 (1 - 0.9752794)
    //   = 0.0494412 m/s (the exact ODE: 2 (1 - e^-0.025) = 0.0493807),
    // and x = h sum_{k=1..10} v_k = 0.02 (10 - 0.9975 (1 - 0.9975^10)/0.0025)
    //   = 0.02 (10 - 9.8635261) = 0.0027295 m.
    let mut w = world(
        "mass = 2.0\ndamping = 0.5\nmax_speed = 100.0\nmax_accel = 100.0",
        "",
    );
    w.set_command(0, Applied::Force([1.0, 0.0]));
    steps(&mut w, 1);
    let s = w.states()[0];
    assert!(close(s.velocity[0], 0.0494412, 1e-6), "{:?}", s.velocity);
    assert!(close(s.position[0], 0.0027295, 1e-6), "{:?}", s.position);
    assert!(s.velocity[1].abs() < 1e-9 && s.position[1].abs() < 1e-9);
    // Damping alone slows it: f = 0 from v0, v <- 0.9975 v per substep.
    let v0 = s.velocity[0];
    w.set_command(0, Applied::Force([0.0, 0.0]));
    steps(&mut w, 1);
    let v1 = w.states()[0].velocity[0];
    assert!(close(v1, v0 * 0.9975f64.powi(10), 1e-6), "{v1}");
}

#[test]
fn a_velocity_command_is_followed_with_the_lags_first_order_response() {
    // T = 0.5 s, v_cmd = (1, 0) from rest: per substep
    //   v <- v + h (1 - v)/T = 0.98 v + 0.02,
    // so v = 1 - 0.98^k after k substeps: 0.1829272 after one tick and
    // 0.6358303 after five (t = T; the exact lag: 1 - e^-1 = 0.6321206).
    let mut w = world(
        "mass = 1.0\nvelocity_lag = 0.5\nmax_speed = 100.0\nmax_accel = 100.0",
        "",
    );
    w.set_command(0, Applied::Velocity([1.0, 0.0]));
    steps(&mut w, 1);
    assert!(close(w.states()[0].velocity[0], 0.1829272, 1e-6));
    steps(&mut w, 4);
    let v = w.states()[0].velocity[0];
    assert!(close(v, 0.6358303, 1e-6), "{v}");
    assert!(close(v, 1.0 - (-1f64).exp(), 0.01), "{v}");
}

#[test]
fn acceleration_then_speed_are_clamped_to_the_robots_limits() {
    // A force of 1000 N on 1 kg, max_accel 2, max_speed 0.5, diagonal:
    // the acceleration is 2 m/s² along (1, 1)/sqrt 2, so the speed grows by
    // 0.02 per substep: 0.2 after one tick, 0.4 after two, and stops at 0.5
    // in the third (substep 25). Distance after one tick:
    // h sum_{k=1..10} 0.02 k = 0.011 m.
    let mut w = world("mass = 1.0\nmax_speed = 0.5\nmax_accel = 2.0", "");
    w.set_command(0, Applied::Force([1000.0, 1000.0]));
    let speed = |w: &World| w.states()[0].velocity[0].hypot(w.states()[0].velocity[1]);
    steps(&mut w, 1);
    let s = w.states()[0];
    assert!(close(speed(&w), 0.2, 1e-6), "{}", speed(&w));
    assert!(close(s.velocity[0], s.velocity[1], 1e-7), "direction kept");
    assert!(close(s.position[0].hypot(s.position[1]), 0.011, 1e-6));
    steps(&mut w, 1);
    assert!(close(speed(&w), 0.4, 1e-6), "{}", speed(&w));
    steps(&mut w, 1);
    assert!(close(speed(&w), 0.5, 1e-6), "{}", speed(&w));
    steps(&mut w, 5);
    assert!(close(speed(&w), 0.5, 1e-6), "never above max_speed");
    // A velocity command beyond both limits: same clamps.
    let mut w = world("mass = 1.0\nmax_speed = 0.5\nmax_accel = 2.0", "");
    w.set_command(0, Applied::Velocity([0.0, 1e300]));
    steps(&mut w, 1);
    assert!(close(w.states()[0].velocity[1], 0.2, 1e-6));
}

/// An obstacle of radius 0.3 m on a waypoint path along y = 0 at 0.1 m/s
/// (1 mm per substep) facing the robot (radius 0.2 m, at rest, braking), its
/// surface gap from the robot going through `gaps_mm` in turn, from 20.5 mm.
fn approaches(gaps_mm: &[f64]) -> Vec<Contact> {
    let x = |gap_mm: f64| 0.5 + gap_mm / 1000.0;
    let points: Vec<String> = gaps_mm
        .iter()
        .map(|g| format!("[{:.6}, 0.0]", x(*g)))
        .collect();
    let obstacle = format!(
        "[[obstacle]]\nname = \"o\"\nstart = [{:.6}, 0.0]\nradius = 0.3\n\
         motion = {{ model = \"waypoints\", points = [{}], speed = 0.1 }}",
        x(20.5),
        points.join(", ")
    );
    let mut w = world("radius = 0.2\nmax_speed = 1.0\nmax_accel = 5.0", &obstacle);
    let path: f64 = std::iter::once(20.5)
        .chain(gaps_mm.iter().copied())
        .collect::<Vec<_>>()
        .windows(2)
        .map(|p| (p[1] - p[0]).abs())
        .sum();
    // Long enough to run the whole path (path mm at 10 mm per tick).
    let contacts = steps(&mut w, (path / 10.0).ceil() as usize + 2);
    let robot = w.states()[0].position;
    assert!(robot[0].abs() < 1e-4, "the robot was pushed to {robot:?}");
    contacts
}

#[test]
fn a_gap_of_half_a_millimetre_is_a_collision_and_one_and_a_half_is_not() {
    let hit = approaches(&[0.5, 30.5]);
    assert_eq!(hit.len(), 1, "{hit:?}");
    assert_eq!((hit[0].a, hit[0].b), (Owner::Robot(0), Owner::Obstacle(0)));
    assert!(hit[0].gap > 0.0 && hit[0].gap <= 1e-3, "{:?}", hit[0]);
    assert!(approaches(&[1.5, 30.5]).is_empty());
}

#[test]
fn a_pair_that_touched_counts_again_only_after_separating_by_more_than_10_mm() {
    // Out to 5.5 mm and back: still the same contact (hysteresis).
    assert_eq!(approaches(&[0.5, 5.5, 0.5, 30.5]).len(), 1);
    // Out to 15.5 mm and back: apart, so a second collision.
    assert_eq!(approaches(&[0.5, 15.5, 0.5, 30.5]).len(), 2);
}
