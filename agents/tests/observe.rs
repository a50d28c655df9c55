//! What a robot senses: differenced velocities (Zhu & Loh eqs 2.9-2.12)
//! and seeded position noise, after sensing range and field of view.

use mrsim_agents::observe::Observer;
use mrsim_proto::{BodyState, SnapshotHeader, body_kind};
use mrsim_scenario::Scenario;

fn scenario(extra: &str, seed: u64) -> Scenario {
    let src = format!(
        r#"
[world]
dt = 0.1
seed = {seed}

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [10.0, 0.0]
{extra}

[[obstacle]]
name = "o1"
start = [3.0, 0.0]
motion = {{ model = "static" }}

[[obstacle]]
name = "o2"
start = [-3.0, 0.0]
motion = {{ model = "static" }}
"#
    );
    mrsim_scenario::parse(&src, "inline.toml")
        .expect("valid scenario")
        .scenario
}

fn body(id: u32, kind: u32, position: [f64; 2], velocity: [f64; 2]) -> BodyState {
    BodyState {
        id,
        kind,
        flags: 0,
        _pad: 0,
        position,
        velocity,
        radius: 0.0,
        ..Default::default()
    }
}

/// Tick `k`: the robot at rest at the origin, o1 moving at (1, 2) m/s with
/// acceleration (0, 4) m/s² from (3, 0), o2 behind the robot; the snapshot
/// reports o1's velocity as (9, 9) so that the truth is recognisable.
fn snapshot(k: u64) -> (SnapshotHeader, Vec<BodyState>) {
    let t = k as f64 * 0.1;
    let header = SnapshotHeader {
        tick: k,
        sim_time: t,
        ..SnapshotHeader::default()
    };
    let bodies = vec![
        body(0, body_kind::ROBOT, [0.0, 0.0], [0.0, 0.0]),
        body(
            1,
            body_kind::OBSTACLE,
            [3.0 + t, 2.0 * t + 2.0 * t * t],
            [9.0, 9.0],
        ),
        body(2, body_kind::OBSTACLE, [-3.0, 0.0], [0.0, 0.0]),
    ];
    (header, bodies)
}

/// The sensed (position, velocity, acceleration) of every body over `ticks` ticks.
type Seen = Vec<Vec<(u32, [f64; 2], [f64; 2], [f64; 2])>>;

fn observe(sc: &Scenario, ticks: u64) -> Seen {
    let mut obs = Observer::new(sc, 0);
    let spec = sc.robots[0].clone();
    (0..ticks)
        .map(|k| {
            let (h, b) = snapshot(k);
            let o = obs.observe(&h, &b, &spec, None);
            o.others
                .iter()
                .map(|s| {
                    (
                        s.id,
                        [s.position.x, s.position.y],
                        [s.velocity.x, s.velocity.y],
                        [s.acceleration.x, s.acceleration.y],
                    )
                })
                .collect()
        })
        .collect()
}

fn close(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
}

#[test]
fn the_truth_gives_the_snapshots_velocity() {
    let seen = observe(&scenario("", 1), 3);
    assert_eq!(seen[2].len(), 2);
    assert!(close(seen[2][0].2, [9.0, 9.0]));
    assert!(close(seen[2][0].3, [0.0, 0.0]));
}

#[test]
fn differenced_velocities_come_from_successive_positions() {
    let seen = observe(&scenario("velocity_source = \"differenced\"", 1), 4);
    // First sighting: nothing known; second: velocity; third on: both.
    assert!(close(seen[0][0].2, [0.0, 0.0]));
    // Between t = 0 and 0.1: ((3.1 - 3) / 0.1, (0.22 - 0) / 0.1).
    assert!(close(seen[1][0].2, [1.0, 2.2]), "{:?}", seen[1][0]);
    assert!(close(seen[1][0].3, [0.0, 0.0]));
    // t = 0.2 -> 0.3: y from 0.48 to 0.78; velocity (1, 3), acceleration (0, 4).
    assert!(close(seen[3][0].2, [1.0, 3.0]), "{:?}", seen[3][0]);
    assert!(close(seen[3][0].3, [0.0, 4.0]), "{:?}", seen[3][0]);
}

#[test]
fn the_field_of_view_applies_before_the_estimate() {
    // Facing the goal (+x) with 90 degrees: o2 behind is never sensed.
    let seen = observe(
        &scenario(
            "velocity_source = \"differenced\"\nfield_of_view_deg = 90",
            1,
        ),
        3,
    );
    for tick in &seen {
        assert_eq!(tick.iter().map(|s| s.0).collect::<Vec<_>>(), vec![1]);
    }
}

#[test]
fn position_noise_has_its_sigma_and_repeats_with_the_seed() {
    let sigma = 0.05;
    let extra = format!("position_noise = {sigma}");
    let n = 2000;
    let a = observe(&scenario(&extra, 3), n);
    assert_eq!(a, observe(&scenario(&extra, 3), n));
    assert_ne!(a, observe(&scenario(&extra, 4), n));
    // Errors of o2 (at rest at (-3, 0)), both axes: sample variance within
    // 4 standard errors (sigma² sqrt(2 / N)) of sigma².
    let errs: Vec<f64> = a
        .iter()
        .flat_map(|t| {
            let p = t[1].1;
            [p[0] + 3.0, p[1]]
        })
        .collect();
    let m = errs.len() as f64;
    let var = errs.iter().map(|e| e * e).sum::<f64>() / m;
    let want = sigma * sigma;
    assert!(
        (var - want).abs() < 4.0 * want * (2.0 / m).sqrt(),
        "variance {var}, want {want}"
    );
    // Without noise the positions are exact.
    let exact = observe(&scenario("", 3), 2);
    assert!(close(exact[1][1].1, [-3.0, 0.0]));
}

#[test]
fn noisy_differenced_velocities_scatter_by_sqrt2_sigma_over_dt() {
    // o2 is at rest: each differenced velocity component is the difference
    // of two independent noises over dt, of standard deviation sqrt(2) sigma / dt.
    let sigma = 0.01;
    let sc = scenario(
        &format!("position_noise = {sigma}\nvelocity_source = \"differenced\""),
        5,
    );
    let seen = observe(&sc, 3001);
    let vs: Vec<f64> = seen[1..].iter().flat_map(|t| t[1].2).collect();
    let m = vs.len() as f64;
    let var = vs.iter().map(|v| v * v).sum::<f64>() / m;
    let want = 2.0 * sigma * sigma / 0.01;
    // Successive differences share a noise sample (lag-1 correlation -1/2),
    // which makes the sample variance's own variance 1 + 2 (1/2)² = 1.5
    // times the independent case's: 4 standard errors of that size.
    assert!(
        (var - want).abs() < 4.0 * 1.5f64.sqrt() * want * (2.0 / m).sqrt(),
        "variance {var}, want {want}"
    );
}

#[test]
fn a_turned_rectangle_obstacle_arrives_with_its_shape_heading_and_circumscribed_radius() {
    let src = r#"
[world]
dt = 0.1

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [10.0, 0.0]
sensor = { kind = "lidar", beams = 4, fov_deg = 360, range = 8.0 }

[[obstacle]]
name = "box"
start = [3.0, 0.0]
shape = { kind = "rectangle", length = 2.0, width = 1.0 }
heading_deg = 90
motion = { model = "static" }

[[obstacle]]
name = "post"
start = [-3.0, 0.0]
radius = 0.4
motion = { model = "static" }
"#;
    let sc = mrsim_scenario::parse(src, "inline.toml")
        .expect("valid scenario")
        .scenario;
    // The snapshot as the world publishes it: each body's circumscribed
    // radius and heading (an obstacle's fixed one).
    let bodies: Vec<BodyState> = std::iter::once((body_kind::ROBOT, [0.0, 0.0], 0.25, 0.0))
        .chain(
            sc.obstacles
                .iter()
                .map(|o| (body_kind::OBSTACLE, o.start, o.radius, o.heading)),
        )
        .enumerate()
        .map(|(id, (kind, position, radius, heading))| BodyState {
            radius,
            heading,
            ..body(id as u32, kind, position, [0.0, 0.0])
        })
        .collect();
    let mut obs = Observer::new(&sc, 0);
    let spec = sc.robots[0].clone();
    let o = obs.observe(&SnapshotHeader::default(), &bodies, &spec, None);
    let (b, post) = (&o.others[0], &o.others[1]);
    assert_eq!((b.id, b.kind), (1, mrsim_planners::BodyKind::Obstacle));
    assert_eq!(
        b.shape,
        mrsim_planners::Shape::Polygon(mrsim_planners::Polygon::rectangle(2.0, 1.0).unwrap())
    );
    assert!(
        (b.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "{}",
        b.heading
    );
    // Half the diagonal of 2 x 1.
    assert!((b.radius - 1.25f64.sqrt()).abs() < 1e-12, "{}", b.radius);
    // Its corners in the world: the length along y, the width along x.
    let corners = b.placed().expect("a polygon");
    for (c, want) in corners
        .points()
        .iter()
        .zip([[3.5, -1.0], [3.5, 1.0], [2.5, 1.0], [2.5, -1.0]])
    {
        assert!(
            (c[0] - want[0]).abs() < 1e-12 && (c[1] - want[1]).abs() < 1e-12,
            "{c:?}"
        );
    }
    // From the robot's centre its near side, x = 2.5, is 2.5 away (its
    // disc's 1.88); the disc obstacle is a disc.
    assert!((b.distance_to(o.me.position) - 2.5).abs() < 1e-12);
    assert_eq!(post.shape, mrsim_planners::Shape::disc(0.4));
    assert_eq!((post.radius, post.heading), (0.4, 0.0));
    // The scan meets the box's side too (beams -pi, -pi/2, 0, pi/2): 2.5
    // ahead, the post's disc 2.6 behind.
    let scan = o.scan.expect("a scan");
    assert!((scan.ranges[2] - 2.5).abs() < 1e-4, "{:?}", scan.ranges);
    assert!((scan.ranges[0] - 2.6).abs() < 1e-4, "{:?}", scan.ranges);
}
