//! CrowdNav's benchmark reproduced (Chen et al., "Crowd-Robot Interaction",
//! ICRA 2019): scenarios/crowdnav/circle-crossing.toml over CrowdNav's
//! test cases (case k: seed 1000 + k, its people placed as CrowdNav places
//! them), the robot on `orca`, the people on ORCA, invisible to them and
//! visible, each case one episode (`end_on = ["collision", "timeout"]`),
//! run in this process in lockstep.
//!
//! `MRSIM_CROWDNAV_CASES=N` runs the first N cases (default: the test
//! set's 500).

use crate::common::*;
use mrsim::{InProcess, Registry, ScenarioSource};
use mrsim_scenario::crowdnav::{CircleCrossing, TEST_SEED_OFFSET};
use std::path::Path;
use std::sync::Arc;

/// The line after which the shipped file lists test case 0's people.
const PEOPLE: &str = "# The people of test case ";

/// CrowdNav's discomfort distance, m (`env.config`'s `discomfort_dist`).
const DISCOMFORT: f64 = 0.2;

fn shipped() -> String {
    std::fs::read_to_string(root().join("scenarios/crowdnav/circle-crossing.toml"))
        .expect("the shipped scene")
}

/// The shipped scene with test case `k`'s people, who see the robot or not.
fn case(k: u32, visible: bool) -> String {
    let text = shipped();
    let (head, _) = text.split_once(PEOPLE).expect("the people's marker");
    let mut blocks = Vec::new();
    let seed = TEST_SEED_OFFSET + k;
    let mut s = head.replace("seed = 1000\n", &format!("seed = {seed}\n"));
    s.push_str(&format!(
        "{PEOPLE}{k} (seed {seed}), as mrsim_scenario::crowdnav::CircleCrossing places them.\n"
    ));
    let motion = "{ model = \"orca\", neighbor_dist = 10.0, max_neighbors = 10, \
                  time_horizon = 5.0, time_horizon_obst = 5.0, radius_margin = 0.01 }";
    for (i, p) in CircleCrossing::default().people(seed).iter().enumerate() {
        blocks.push(format!(
            "[[person]]\nname = \"h{i}\"\nstart = [{:?}, {:?}]\ngoal = [{:?}, {:?}]\n\
             radius = 0.3\npreferred_speed = 1.0\nsees_robots = {visible}\nmotion = {motion}\n",
            p.start[0], p.start[1], p.goal[0], p.goal[1]
        ));
    }
    s.push_str(&blocks.join("\n"));
    s
}

/// What the episodes of one setting came to.
#[derive(Debug, Default)]
struct Tally {
    episodes: u32,
    success: u32,
    collision: u32,
    timeout: u32,
    /// Times to goal of the successes, s.
    times: Vec<f64>,
    /// Ticks (steps) within the discomfort distance of a person, not the
    /// episode's last (CrowdNav's `Danger` steps).
    danger: u64,
    /// Ticks (steps) of every episode.
    steps: u64,
}

impl Tally {
    fn rate(&self, k: u32) -> f64 {
        f64::from(k) / f64::from(self.episodes)
    }

    fn mean_time(&self) -> f64 {
        self.times.iter().sum::<f64>() / self.times.len().max(1) as f64
    }

    fn discomfort(&self) -> f64 {
        self.danger as f64 / self.steps.max(1) as f64
    }
}

/// Runs test case `k` in `dir` and adds it to `t`.
fn episode(dir: &Path, k: u32, visible: bool, t: &mut Tally) {
    let file = dir.join(format!("case-{k}.toml"));
    std::fs::write(&file, case(k, visible)).expect("write the case");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(file),
            ..Default::default()
        },
        registry: Arc::new(Registry::builtin()),
        out: Some(dir.join(format!("run-{k}"))),
        render: false,
        plan_timeout: None,
    })
    .expect("the run");
    let m = metrics(&result.dir);
    let robot = &m["robots"]["robot"];
    t.episodes += 1;
    match robot["outcome"].as_str() {
        Some("success") => {
            t.success += 1;
            t.times
                .push(robot["time_to_goal"].as_f64().expect("a success's time"));
        }
        Some("collision") => t.collision += 1,
        Some("timeout") => t.timeout += 1,
        other => panic!("case {k}: outcome {other:?}: {m:#}"),
    }
    let ticks = m["ticks"].as_u64().expect("ticks");
    t.steps += ticks;
    let rows = trajectory(&result.dir);
    let me: Vec<&Row> = track(&rows, "robot");
    for tick in 1..ticks {
        let Some(r) = me.iter().find(|r| r.tick == tick) else {
            continue;
        };
        let near = rows
            .iter()
            .filter(|p| p.tick == tick && p.kind == "person")
            .any(|p| norm(p.x - r.x, p.y - r.y) - 0.6 < DISCOMFORT);
        t.danger += u64::from(near);
    }
    let _ = std::fs::remove_dir_all(&result.dir);
}

fn sweep(cases: u32, visible: bool) -> Tally {
    let dir = fresh_dir(if visible {
        "crowdnav-visible"
    } else {
        "crowdnav-invisible"
    });
    let mut t = Tally::default();
    for k in 0..cases {
        episode(&dir, k, visible, &mut t);
    }
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!(
        "crowdnav {} over {cases} cases: success {:.3}, collision {:.3}, timeout {:.3}, \
         time to goal {:.2} s, discomfort frequency {:.3}",
        if visible { "visible" } else { "invisible" },
        t.rate(t.success),
        t.rate(t.collision),
        t.rate(t.timeout),
        t.mean_time(),
        t.discomfort(),
    );
    t
}

fn cases() -> u32 {
    std::env::var("MRSIM_CROWDNAV_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(500)
}

#[test]
fn the_shipped_scene_holds_crowdnav_s_test_case_0() {
    assert_eq!(
        shipped(),
        case(0, false),
        "regenerate the people from the generator"
    );
}

/// The 95 % Wilson score interval of `k` successes in `n` trials.
fn wilson(k: u32, n: u32) -> (f64, f64) {
    let z = 1.959_963_985;
    let (k, n) = (f64::from(k), f64::from(n));
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    (centre - half, centre + half)
}

/// The 95 % interval of the mean of `xs` (normal approximation).
fn mean_interval(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let half = 1.959_963_985 * (var / n).sqrt();
    (mean - half, mean + half)
}

/// Does the interval `(lo, hi)` meet the values a figure printed with two
/// decimals stands for, `[paper - 0.005, paper + 0.005]`?
fn meets(paper: f64, (lo, hi): (f64, f64)) -> bool {
    paper + 0.005 >= lo && paper - 0.005 <= hi
}

/// The paper's ORCA rows (Chen et al. 2019, Tables I and II): with the
/// robot invisible to the people success 0.43, collision 0.57, time to goal
/// 10.86 s; with it visible success 0.99.
#[test]
fn crowdnav_s_orca_robot_among_people_who_do_and_do_not_see_it() {
    let n = cases();
    let invisible = sweep(n, false);
    let visible = sweep(n, true);

    let rate = |name: &str, t: &Tally, k: u32, paper: f64| {
        let ci = wilson(k, t.episodes);
        eprintln!(
            "  {name}: {:.3} (95 % [{:.3}, {:.3}]), paper {paper}",
            t.rate(k),
            ci.0,
            ci.1
        );
        assert!(
            meets(paper, ci),
            "{name}: {k} of {} ({:.3}), 95 % interval [{:.3}, {:.3}], misses the paper's {paper}",
            t.episodes,
            t.rate(k),
            ci.0,
            ci.1
        );
    };
    rate("invisible success", &invisible, invisible.success, 0.43);
    rate("invisible collision", &invisible, invisible.collision, 0.57);
    rate("visible success", &visible, visible.success, 0.99);

    assert!(
        invisible.times.len() >= 2,
        "too few successes for a time: {invisible:?}"
    );
    let ci = mean_interval(&invisible.times);
    eprintln!(
        "  invisible time to goal: {:.2} s (95 % [{:.2}, {:.2}]), paper 10.86 s",
        invisible.mean_time(),
        ci.0,
        ci.1
    );
    assert!(
        meets(10.86, ci),
        "invisible time to goal {:.2} s, 95 % interval [{:.2}, {:.2}], misses the paper's 10.86 s",
        invisible.mean_time(),
        ci.0,
        ci.1
    );

    // People who see the robot take half of each avoidance: the robot's
    // detours, and so its times, are the shorter.
    assert!(
        visible.times.len() >= 2,
        "too few successes for a time: {visible:?}"
    );
    let seen = mean_interval(&visible.times);
    eprintln!(
        "  visible time to goal: {:.2} s (95 % [{:.2}, {:.2}])",
        visible.mean_time(),
        seen.0,
        seen.1
    );
    assert!(
        seen.1 < ci.0,
        "visible time to goal {:.2} s [{:.2}, {:.2}] not below the invisible {:.2} s [{:.2}, {:.2}]",
        visible.mean_time(),
        seen.0,
        seen.1,
        invisible.mean_time(),
        ci.0,
        ci.1
    );
}
