//! The world's car (`kinematics = "ackermann"`) against the bicycle's
//! geometry: the circle it drives at full lock, every limit held whatever
//! it is asked, no path ever tighter than its minimum turning radius, and
//! the commands of other drives braking it.

use mrsim_world::{Applied, World};

/// ir-sim's car (a 4.6 x 1.6 m body, wheelbase 3 m), steering to 30
/// degrees at 60 degrees/s, 4 m/s and 2 m/s², at the origin heading to
/// `goal` (its start heading), with the given extra `[[robot]]` lines; dt
/// = 0.1 s, `substeps` substeps a tick.
fn world(goal: [f64; 2], substeps: u32, robot: &str) -> World {
    let dt = if substeps == 1 { 0.01 } else { 0.1 };
    let src = format!(
        "[world]\ndt = {dt}\nsubsteps = {substeps}\nduration = 100.0\n\n\
         [[robot]]\nname = \"car\"\nstart = [0.0, 0.0]\ngoal = [{}, {}]\n\
         kinematics = \"ackermann\"\nshape = {{ kind = \"rectangle\", length = 4.6, width = 1.6 }}\n\
         wheelbase = 3.0\nmax_steering_deg = 30\nmax_steering_rate_deg = 60\n\
         max_speed = 4.0\nmax_accel = 2.0\n{robot}\n",
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

/// The car's speed along its heading (its centre moves at v e + (v
/// tan(delta) / 2) e_perp, whose component along e is v).
fn speed(w: &World) -> f64 {
    let s = w.states()[0];
    s.velocity[0] * s.heading.cos() + s.velocity[1] * s.heading.sin()
}

/// The centre of the circle through three points and its radius.
fn circle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> ([f64; 2], f64) {
    let d = 2.0 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]));
    let n = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
    let x = (n(a) * (b[1] - c[1]) + n(b) * (c[1] - a[1]) + n(c) * (a[1] - b[1])) / d;
    let y = (n(a) * (c[0] - b[0]) + n(b) * (a[0] - c[0]) + n(c) * (b[0] - a[0])) / d;
    ([x, y], (a[0] - x).hypot(a[1] - y))
}

/// The least-squares circle (Kasa's algebraic fit: x^2 + y^2 + D x + E y
/// + F = 0) through `points`: its centre and radius.
fn fit_circle(points: &[[f64; 2]]) -> ([f64; 2], f64) {
    // Normal equations of the 3 unknowns (D, E, F).
    let mut m = [[0.0f64; 4]; 3];
    for p in points {
        let row = [p[0], p[1], 1.0];
        let rhs = -(p[0] * p[0] + p[1] * p[1]);
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += row[i] * row[j];
            }
            m[i][3] += row[i] * rhs;
        }
    }
    // Gauss-Jordan elimination.
    for i in 0..3 {
        let pivot = m[i][i];
        for v in m[i].iter_mut() {
            *v /= pivot;
        }
        let row = m[i];
        for (k, other) in m.iter_mut().enumerate() {
            if k != i {
                let f = other[i];
                for (v, p) in other.iter_mut().zip(row) {
                    *v -= f * p;
                }
            }
        }
    }
    let (d, e, f) = (m[0][3], m[1][3], m[2][3]);
    let centre = [-d / 2.0, -e / 2.0];
    (centre, (centre[0].powi(2) + centre[1].powi(2) - f).sqrt())
}

#[test]
fn at_full_steering_the_car_turns_on_the_radius_of_its_wheelbase_and_steering_limit() {
    // Asked 2 m/s and far more steering than it has: after 1 s the speed
    // and after 0.5 s the steering are at their marks. A full turn at
    // R = L / tan(30 deg) = 5.196 m takes 2 pi R / 2 = 16.3 s; the
    // circles are fitted to the recorded path from t = 2 s over 170 ticks
    // (a full turn and a little more). The rear axle's points (the centre
    // less L/2 along the heading) lie on R; the body's centre, L/2 ahead
    // of it, on sqrt(R^2 + (L/2)^2) = 5.408 m.
    let mut w = world([10.0, 0.0], 10, "");
    w.set_command(0, Applied::Ackermann([2.0, 10.0]));
    steps(&mut w, 20);
    let (mut centres, mut rears) = (Vec::new(), Vec::new());
    for _ in 0..170 {
        steps(&mut w, 1);
        let s = w.states()[0];
        centres.push(s.position);
        let (sn, cs) = s.heading.sin_cos();
        rears.push([s.position[0] - 1.5 * cs, s.position[1] - 1.5 * sn]);
    }
    let r = 3.0 / 30f64.to_radians().tan();
    let (rc, rr) = fit_circle(&rears);
    assert!((rr - r).abs() < 1e-4, "rear axle's circle {rr} vs {r}");
    let (cc, cr) = fit_circle(&centres);
    let centre_r = (r * r + 1.5f64.powi(2)).sqrt();
    assert!(
        (cr - centre_r).abs() < 1e-4,
        "centre's circle {cr} vs {centre_r}"
    );
    // One circle, one centre; and every point on it, not only on average.
    assert!((rc[0] - cc[0]).hypot(rc[1] - cc[1]) < 1e-4);
    for p in &rears {
        assert!(((p[0] - rc[0]).hypot(p[1] - rc[1]) - r).abs() < 1e-4);
    }
    // It turns counter-clockwise (positive steering) at v tan(delta) / L.
    let s = w.states()[0];
    assert!((s.angular_velocity - 2.0 * 30f64.to_radians().tan() / 3.0).abs() < 1e-9);
    assert!((s.steering - 30f64.to_radians()).abs() < 1e-12);
}

#[test]
fn the_world_clamps_steering_rate_steering_speed_and_reverse_speed_whatever_is_asked() {
    let max = 30f64.to_radians();
    let mut w = world([10.0, 0.0], 10, "");
    // One tick of 0.1 s from rest: the steering moves 6 degrees (60
    // degrees/s), the speed 0.2 m/s (2 m/s²), however much more is asked.
    w.set_command(0, Applied::Ackermann([1e9, 1e9]));
    steps(&mut w, 1);
    assert!((w.states()[0].steering - 6f64.to_radians()).abs() < 1e-12);
    assert!((speed(&w) - 0.2).abs() < 1e-5, "{}", speed(&w));
    // Held there: full lock and 4 m/s, never more.
    for _ in 0..40 {
        steps(&mut w, 1);
        assert!(w.states()[0].steering <= max + 1e-15);
        assert!(speed(&w) <= 4.0 + 1e-5, "{}", speed(&w));
    }
    assert!((w.states()[0].steering - max).abs() < 1e-15);
    assert!((speed(&w) - 4.0).abs() < 1e-5);
    // Backwards, with no reverse: down to a stop and no further, the
    // wheels swept to the other lock at the same rate (60 degrees in 1 s).
    w.set_command(0, Applied::Ackermann([-1e9, -1e9]));
    steps(&mut w, 5);
    assert!((w.states()[0].steering - 0.0).abs() < 1e-12);
    for _ in 0..40 {
        steps(&mut w, 1);
        assert!(speed(&w) >= -1e-5, "{}", speed(&w));
    }
    assert!(speed(&w).abs() < 1e-5);
    assert!((w.states()[0].steering + max).abs() < 1e-15);
    // A car that may reverse at 1.5 m/s: to -1.5 and no further.
    let mut w = world([10.0, 0.0], 10, "max_reverse_speed = 1.5");
    w.set_command(0, Applied::Ackermann([-1e9, 0.0]));
    for _ in 0..30 {
        steps(&mut w, 1);
        assert!(speed(&w) >= -1.5 - 1e-5, "{}", speed(&w));
    }
    assert!((speed(&w) + 1.5).abs() < 1e-5);
    // NaN asks a stop and keeps the wheels.
    w.set_command(0, Applied::Ackermann([f64::NAN, f64::NAN]));
    steps(&mut w, 10);
    assert!(speed(&w).abs() < 1e-5 && w.states()[0].steering == 0.0);
}

#[test]
fn a_velocity_lag_slows_the_car_as_it_does_the_other_drives() {
    // T = 0.5 s: the first substep (0.01 s) from rest towards 1 m/s gives
    // 0.02 m/s, the tick (1 - (1 - 0.02)^10) = 0.183 m/s.
    let mut w = world([10.0, 0.0], 10, "velocity_lag = 0.5");
    w.set_command(0, Applied::Ackermann([1.0, 0.0]));
    steps(&mut w, 1);
    let want = 1.0 - 0.98f64.powi(10);
    assert!((speed(&w) - want).abs() < 1e-5, "{} vs {want}", speed(&w));
}

#[test]
fn a_force_or_velocity_reaching_a_car_brakes_it_and_a_car_command_brakes_the_others() {
    // A car at 4 m/s, its wheels at 10 degrees, asked a velocity: it
    // stops within 2 s (2 m/s²), the wheels held.
    let mut w = world([10.0, 0.0], 10, "");
    w.set_command(0, Applied::Ackermann([4.0, 10f64.to_radians()]));
    steps(&mut w, 30);
    w.set_command(0, Applied::Velocity([4.0, 4.0]));
    steps(&mut w, 20);
    assert!(speed(&w).abs() < 1e-5, "{}", speed(&w));
    assert!((w.states()[0].steering - 10f64.to_radians()).abs() < 1e-12);
    w.set_command(0, Applied::Force([100.0, 0.0]));
    steps(&mut w, 5);
    assert!(speed(&w).abs() < 1e-5, "{}", speed(&w));
    // A holonomic robot and a unicycle asked a car's command brake.
    for drive in ["holonomic", "unicycle"] {
        let src = format!(
            "[world]\ndt = 0.1\nsubsteps = 10\nduration = 10.0\n\n\
             [[robot]]\nname = \"r\"\nstart = [0.0, 0.0]\ngoal = [9.0, 0.0]\n\
             kinematics = \"{drive}\"\nmax_speed = 1.0\nmax_accel = 2.0\n"
        );
        let scenario = mrsim_scenario::parse(&src, "inline.toml")
            .expect("valid")
            .scenario;
        let mut w = World::new(&scenario).expect("world");
        let cmd = if drive == "holonomic" {
            Applied::Velocity([1.0, 0.0])
        } else {
            Applied::Unicycle([1.0, 0.0])
        };
        w.set_command(0, cmd);
        steps(&mut w, 10);
        let s = w.states()[0];
        assert!(
            (s.velocity[0] - 1.0).abs() < 1e-5,
            "{drive}: {:?}",
            s.velocity
        );
        w.set_command(0, Applied::Ackermann([1.0, 0.3]));
        steps(&mut w, 10);
        let s = w.states()[0];
        assert!(
            s.velocity[0].hypot(s.velocity[1]) < 1e-5,
            "{drive}: {:?}",
            s.velocity
        );
    }
}

#[test]
fn a_car_starts_facing_its_goal_with_its_body_turned_so() {
    // Goal up and to the right: heading 45 degrees, and the rectangle's
    // corner that leads is ahead along it (the collider turned with it).
    let w = world([10.0, 10.0], 10, "");
    let s = w.states()[0];
    assert!((s.heading - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    assert_eq!((s.steering, s.angular_velocity), (0.0, 0.0));
}

/// A small deterministic generator (64-bit LCG, the high bits) for the
/// random commands below.
struct Lcg(u64);

impl Lcg {
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

#[test]
fn no_path_of_a_car_is_ever_tighter_than_its_minimum_turning_radius() {
    // A tick of one substep (dt = 0.01 s): within it speed and steering
    // are constant and the rear axle drives one arc, of length |v| h, over
    // which the heading turns by v tan(delta) h / L; a path no tighter
    // than R_min = L / tan(30 deg) turns it by at most |v| h / R_min. 30,000
    // ticks of commands drawn anew every second, speeds and steering far
    // beyond the limits either way, reverse allowed: every tick's turn is
    // checked against the speed the world publishes, and the circle
    // through every three rear-axle points 1 s apart on a stretch driven
    // one way against R_min (to 0.1%: positions are rapier's f32, and a
    // radius through three points 1-8 m apart is known to a few 1e-4).
    let r_min = 3.0 / 30f64.to_radians().tan();
    let h = 0.01;
    let mut w = world([10.0, 0.0], 1, "max_reverse_speed = 2.0");
    let mut rng = Lcg(7);
    let rear = |w: &World| {
        let s = w.states()[0];
        let (sn, cs) = s.heading.sin_cos();
        [s.position[0] - 1.5 * cs, s.position[1] - 1.5 * sn]
    };
    let (mut heading, mut tightest, mut turned) = (w.states()[0].heading, f64::INFINITY, 0.0);
    let mut history: Vec<([f64; 2], f64)> = Vec::new();
    for tick in 0..30_000 {
        if tick % 100 == 0 {
            let v = rng.uniform(-6.0, 8.0);
            let d = rng.uniform(-2.0, 2.0);
            w.set_command(0, Applied::Ackermann([v, d]));
        }
        steps(&mut w, 1);
        let now = w.states()[0].heading;
        let v = speed(&w);
        let dtheta = (now - heading).abs();
        assert!(
            dtheta <= v.abs() * h / r_min * (1.0 + 1e-9) + 1e-15,
            "tick {tick}: turned {dtheta} at {v} m/s"
        );
        turned += dtheta;
        heading = now;
        history.push((rear(&w), v));
        if history.len() > 200 {
            let n = history.len();
            let (a, b, c) = (history[n - 201].0, history[n - 101].0, history[n - 1].0);
            let window = &history[n - 201..];
            let one_way = window.iter().all(|h| h.1 > 0.5) || window.iter().all(|h| h.1 < -0.5);
            if one_way {
                tightest = tightest.min(circle(a, b, c).1);
            }
        }
    }
    // The commands did turn it, hard and often.
    assert!(turned > 50.0, "{turned}");
    assert!(tightest >= r_min * (1.0 - 1e-3), "{tightest} vs {r_min}");
    assert!(tightest < 1.05 * r_min, "never near full lock: {tightest}");
}
