//! The world's unicycle model against numbers computed by hand. Each world
//! has dt = 0.1 s and 10 substeps (h = 0.01 s), ideal tracking
//! (velocity_lag = 0: each substep asks the whole change at once, so the
//! clamps decide), per substep: v += h a, omega += h alpha, theta += h
//! omega, then the disc moves h v (cos theta, sin theta) (rapier, f32).

use mrsim_world::{Applied, World};

/// One unicycle robot at the origin heading to `goal` (its start heading),
/// with the given extra `[[robot]]` lines.
fn world(goal: [f64; 2], robot: &str) -> World {
    let src = format!(
        "[world]\ndt = 0.1\nsubsteps = 10\nduration = 10.0\n\n\
         [[robot]]\nname = \"r0\"\nstart = [0.0, 0.0]\ngoal = [{}, {}]\n\
         kinematics = \"unicycle\"\n{robot}\n",
        goal[0], goal[1]
    );
    let loaded = mrsim_scenario::parse(&src, "inline.toml").expect("valid scenario");
    World::new(&loaded.scenario).expect("world")
}

fn steps(w: &mut World, n: usize) {
    let mut c = Vec::new();
    for _ in 0..n {
        w.step(&mut c);
    }
}

const LIMITS: &str =
    "max_speed = 1.0\nmax_accel = 2.0\nmax_angular_speed = 2.0\nmax_angular_accel = 4.0";

#[test]
fn a_unicycle_speeds_up_and_turns_at_its_acceleration_limits() {
    // From rest, asked (v, omega) = (1, 1): both accelerations clamp, so
    // after substep k: v_k = 2 h k = 0.02 k, omega_k = 4 h k = 0.04 k,
    // theta_k = h sum_{j<=k} omega_j = 0.0002 k (k + 1). After one tick
    // (k = 10): v = 0.2, omega = 0.4, theta = 0.022, and the position is
    // sum_k h v_k (cos theta_k, sin theta_k) = (0.0109989, 0.0001364).
    let mut w = world([5.0, 0.0], LIMITS);
    w.set_command(0, Applied::Unicycle([1.0, 1.0]));
    steps(&mut w, 1);
    let s = w.states()[0];
    let speed = s.velocity[0].hypot(s.velocity[1]);
    assert!((speed - 0.2).abs() < 1e-6, "{speed}");
    assert!(
        (s.angular_velocity - 0.4).abs() < 1e-12,
        "{}",
        s.angular_velocity
    );
    assert!((s.heading - 0.022).abs() < 1e-12, "{}", s.heading);
    // The velocity points along the heading.
    assert!((s.velocity[1].atan2(s.velocity[0]) - 0.022).abs() < 1e-5);
    let (mut x, mut y) = (0.0, 0.0);
    for k in 1..=10 {
        let (v, th) = (0.02 * k as f64, 0.0002 * (k * (k + 1)) as f64);
        x += 0.01 * v * th.cos();
        y += 0.01 * v * th.sin();
    }
    assert!((x - 0.0109989).abs() < 1e-7 && (y - 0.0001364).abs() < 1e-7);
    assert!((s.position[0] - x).abs() < 1e-6, "{:?} vs {x}", s.position);
    assert!((s.position[1] - y).abs() < 1e-6, "{:?} vs {y}", s.position);
}

#[test]
fn the_world_holds_a_unicycle_to_its_speed_and_turn_rate_limits_whatever_it_asks() {
    let mut w = world([5.0, 0.0], LIMITS);
    w.set_command(0, Applied::Unicycle([1e6, -1e6]));
    steps(&mut w, 20);
    let s = w.states()[0];
    let speed = s.velocity[0].hypot(s.velocity[1]);
    assert!((speed - 1.0).abs() < 1e-6, "{speed}");
    assert_eq!(s.angular_velocity, -2.0);
    // Backwards is limited the same way, and NaN asks nothing.
    w.set_command(0, Applied::Unicycle([-1e6, f64::NAN]));
    steps(&mut w, 20);
    let s = w.states()[0];
    let e = [s.heading.cos(), s.heading.sin()];
    let v = s.velocity[0] * e[0] + s.velocity[1] * e[1];
    assert!((v + 1.0).abs() < 1e-6, "{v}");
    // omega went from -2 to 0 at 4 rad/s² (0.5 s) and stayed there.
    assert_eq!(s.angular_velocity, 0.0);
}

#[test]
fn a_sideways_velocity_command_does_not_move_a_unicycle() {
    // Heading +x (goal ahead), asked to move along +y: no component along
    // the heading, so v stays 0, and omega is asked 0.
    let mut w = world([5.0, 0.0], LIMITS);
    w.set_command(0, Applied::Velocity([0.0, 1.0]));
    steps(&mut w, 5);
    let s = w.states()[0];
    assert_eq!(s.position, [0.0, 0.0]);
    assert_eq!(s.heading, 0.0);
}

#[test]
fn a_force_on_a_unicycle_pushes_it_along_its_heading_only() {
    // Heading +y (goal straight up), f = (1, 1), m = 2, b = 0.5: along the
    // heading f.e = 1, the holonomic test's numbers: v = 0.0494412 m/s and
    // y = 0.0027295 m after one tick; nothing along x.
    let mut w = world(
        [0.0, 5.0],
        "mass = 2.0\ndamping = 0.5\nmax_speed = 100.0\nmax_accel = 100.0",
    );
    assert!((w.states()[0].heading - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    w.set_command(0, Applied::Force([1.0, 1.0]));
    steps(&mut w, 1);
    let s = w.states()[0];
    assert!((s.velocity[1] - 0.0494412).abs() < 1e-6, "{:?}", s.velocity);
    assert!((s.position[1] - 0.0027295).abs() < 1e-6, "{:?}", s.position);
    assert!(s.position[0].abs() < 1e-9 && s.velocity[0].abs() < 1e-9);
}

#[test]
fn a_unicycle_command_brakes_a_holonomic_robot() {
    let src = "[world]\ndt = 0.1\nsubsteps = 10\n\n[[robot]]\nname = \"r0\"\n\
               start = [0.0, 0.0]\ngoal = [5.0, 0.0]\nmax_accel = 2.0\n";
    let loaded = mrsim_scenario::parse(src, "inline.toml").expect("valid scenario");
    let mut w = World::new(&loaded.scenario).expect("world");
    w.set_command(0, Applied::Velocity([1.0, 0.0]));
    steps(&mut w, 2);
    assert!(w.states()[0].velocity[0] > 0.3);
    w.set_command(0, Applied::Unicycle([1.0, 1.0]));
    steps(&mut w, 3);
    assert_eq!(w.states()[0].velocity, [0.0, 0.0]);
    assert_eq!(w.states()[0].heading, 0.0);
}
