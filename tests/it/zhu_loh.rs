//! Zhu & Loh section 4 (figs 4.2, 4.3) through the real binary with
//! `scenarios/papers/zhu-loh-fov.toml`: the collision rate against the view
//! distance (`defaults.sensing_range`), each crossing a lockstep run in
//! process (`--transport inproc`), seeds 1..N (`world.seed`), so the rates
//! are the same on every machine.
//!
//! The paper's claim that holds: widening the view helps only up to a
//! point; beyond about 2 m the collision rate stops improving. The claim
//! that needs a timing model: the paper's "average allowable maximum speed"
//! falls as the view widens because vision computation time grows with it;
//! without a model planning costs no simulated time and our AAMS is lower
//! only with a 1 m view, with a `per-body` compute model it peaks at an
//! inner view (the last test).

use crate::common::*;

/// Every obstacle's motion for one model at a time (docs/planners.md, "Zhu & Loh").
const PURSUE: &str = "{ model = \"intentional\", behavior = \"pursue\", target = \"r0\", max_speed = 0.3, max_accel = 1.0 }";
const RANDOM: &str =
    "{ model = \"random\", accel_sigma = 0.8, alpha1 = 0.8, beta1 = 0.5, max_speed = 0.6 }";

/// One crossing: true if the robot collided with anything.
fn collided(view: f64, speed: f64, motion: Option<&str>, seed: u32) -> bool {
    let out = fresh_dir("zhu-loh");
    let file = root().join("scenarios/papers/zhu-loh-fov.toml");
    let sets = [
        format!("defaults.sensing_range={view}"),
        format!("robot.*.max_speed={speed}"),
        format!("world.seed={seed}"),
    ];
    let mut extra: Vec<String> = ["--quiet", "--no-report", "--transport", "inproc"]
        .map(String::from)
        .to_vec();
    for s in sets {
        extra.extend(["--set".to_string(), s]);
    }
    if let Some(m) = motion {
        extra.extend(["--set".to_string(), format!("obstacle.*.motion={m}")]);
    }
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    assert_ok(&run(&file, &out, &run_id("zl"), &extra));
    let n = metrics(&out)["collisions_total"]
        .as_u64()
        .expect("collisions");
    let _ = std::fs::remove_dir_all(&out);
    n > 0
}

/// The fraction of seeds 1..=n whose crossing collided, over two threads.
fn collision_rate(view: f64, speed: f64, motion: Option<&str>, n: u32) -> f64 {
    let hits: u32 = std::thread::scope(|s| {
        let half = [(1..=n).step_by(2), (2..=n).step_by(2)].map(|seeds| {
            s.spawn(move || {
                seeds
                    .map(|seed| u32::from(collided(view, speed, motion, seed)))
                    .sum::<u32>()
            })
        });
        half.into_iter()
            .map(|h| h.join().expect("runs"))
            .sum::<u32>()
    });
    f64::from(hits) / f64::from(n)
}

/// At 2 m/s a 1 m view is too short: the hostile pursuers catch the robot
/// in every one of 20 seeds, and in the file's mixed field 8 of 20 collide
/// (0.4); from 2 m on, none in either.
#[test]
fn at_2_m_s_a_view_of_2_m_or_more_avoids_what_a_1_m_view_runs_into() {
    for (field, motion, at_1) in [("pursuers", Some(PURSUE), 1.0), ("mixed", None, 0.4)] {
        let r1 = collision_rate(1.0, 2.0, motion, 20);
        assert!((r1 - at_1).abs() < 1e-9, "{field}, 1 m view: {r1}");
        for view in [2.0, 4.0, 8.0, 16.0] {
            let r = collision_rate(view, 2.0, motion, 20);
            assert_eq!(r, 0.0, "{field}, {view} m view");
        }
    }
}

/// At 1 m/s, where every view collides now and then, the rate pooled over
/// random obstacles, pursuers and the file's mixed field (30 seeds each;
/// constant-velocity obstacles are avoided at every view and speed, so they
/// would only dilute it) does not fall beyond a 2 m
/// view: at 4, 8 and 16 m it is within 0.05 of the 2 m rate or above it
/// (measured 0.133 at 2 m; 0.144, 0.122, 0.111 beyond). A view that kept
/// paying would show here as a rate falling with the distance.
#[test]
fn at_1_m_s_widening_the_view_beyond_2_m_does_not_lower_the_collision_rate() {
    let pooled = |view: f64| {
        [Some(RANDOM), Some(PURSUE), None]
            .map(|m| collision_rate(view, 1.0, m, 30))
            .iter()
            .sum::<f64>()
            / 3.0
    };
    let at_2 = pooled(2.0);
    assert!(at_2 > 0.05, "2 m view: {at_2}");
    for view in [4.0, 8.0, 16.0] {
        let r = pooled(view);
        assert!(r > at_2 - 0.05, "{view} m view: {r} against {at_2} at 2 m");
    }
}

/// The paper's cause made a model: vision time that grows with the bodies
/// in view (`per-body`, 10 ms plus 10 ms per body sensed, at 10 Hz). Over
/// 10 seeds of the file's mixed field the average allowable maximum speed
/// rises from a 1 m view to a 4 m one (a short view sees hazards too late)
/// and falls at 16 m (twelve bodies in view: 130 ms a plan, commands late
/// and stale), an interior maximum as in the paper's fig. 4.3 (measured
/// 1.70, 1.95, 0.00 m/s at 1, 4, 16 m).
#[test]
fn with_vision_time_growing_with_the_bodies_seen_the_allowable_speed_peaks_at_an_inner_view() {
    let out = fresh_dir("zhu-loh-aams");
    let file = root().join("scenarios/papers/zhu-loh-fov.toml");
    let done = mrsim()
        .arg("sweep")
        .arg(&file)
        .args(["--set", "defaults.sensing_range=1,4,16"])
        .args(["--set", "robot.*.max_speed=0.5,1,1.5,2"])
        .args([
            "--set",
            "defaults.timing.compute={ model = \"per-body\", base_ms = 10.0, per_body_ms = 10.0 }",
        ])
        .args([
            "--seeds",
            "10",
            "--jobs",
            "2",
            "--allowable",
            "robot.*.max_speed",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("start mrsim sweep");
    assert_ok(&done);
    let text = std::fs::read_to_string(out.join("allowable.csv")).expect("allowable.csv");
    // view -> mean allowable speed (the view is the first column, the mean
    // the second last).
    let aams: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let n = f.len();
            (f[0].parse().expect("view"), f[n - 2].parse().expect("mean"))
        })
        .collect();
    let at = |v: f64| aams.iter().find(|a| a.0 == v).expect("view swept").1;
    let (near, mid, far) = (at(1.0), at(4.0), at(16.0));
    assert!(
        mid > near && mid > far,
        "AAMS at 1, 4, 16 m: {near}, {mid}, {far}"
    );
    let _ = std::fs::remove_dir_all(&out);
}
