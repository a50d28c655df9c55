//! A user's own planner, both ways the guide shows: the example agent
//! (`examples/my_agent.rs`) joins a live run as the scenario's `external`
//! robot, and a planner registered by name runs in-process through the
//! library (`mrsim::run_in_process`). The Rust block of the guide's chapter
//! (docs/own-planner.md) is the example file, byte for byte, and its
//! commands are the ones run here.

use crate::common::*;
use mrsim::{Command, InProcess, Observation, Planner, Registry, RunError, ScenarioSource, Vec2};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::Arc;

/// The guide's chapter "Your own planner".
fn guide_chapter() -> String {
    std::fs::read_to_string(root().join("docs/own-planner.md")).expect("docs/own-planner.md")
}

/// The first fenced block of `lang` after `heading` in `text`.
fn block(text: &str, heading: &str, lang: &str) -> String {
    let from = text.find(heading).expect("heading");
    let fence = format!("```{lang}\n");
    let open = text[from..].find(&fence).expect("code block") + from + fence.len();
    let close = text[open..].find("\n```").expect("closing fence") + open;
    text[open..=close].to_string()
}

/// The example binary cargo built beside the test (target/release/examples):
/// `cargo test` builds the examples, `cargo test --test it` alone does
/// not.
fn example_binary() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary");
    let dir = exe.parent().and_then(Path::parent).expect("target dir");
    let bin = dir.join("examples").join("my_agent");
    assert!(
        bin.is_file(),
        "{} is not built: `cargo test --release` builds it (with `--test it` alone, \
         first `cargo build --release --example my_agent`)",
        bin.display()
    );
    bin
}

#[test]
fn the_guide_shows_the_example_agent_byte_for_byte() {
    let example =
        std::fs::read_to_string(root().join("examples/my_agent.rs")).expect("the example");
    assert_eq!(block(&guide_chapter(), "\n## Rust\n", "rust"), example);
}

#[test]
fn the_example_agent_drives_the_external_robot_to_its_goal_in_a_live_run() {
    // The guide's two commands, as printed, but with a run id and an
    // output folder of this test's own.
    let commands = block(&guide_chapter(), "\n## Rust\n", "sh");
    let lines: Vec<Vec<&str>> = commands
        .lines()
        .map(|l| {
            l.split('#')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect()
        })
        .filter(|w: &Vec<&str>| !w.is_empty())
        .collect();
    assert_eq!(lines.len(), 2, "{commands}");
    let (world_cmd, agent_cmd) = (&lines[0], &lines[1]);
    assert_eq!(world_cmd[..2], ["mrsim", "run"], "{commands}");
    let cargo = ["cargo", "run", "--release", "--example", "my_agent", "--"];
    assert_eq!(agent_cmd[..cargo.len()], cargo, "{commands}");
    let id = run_id("mine");
    let ours = |w: &&str| {
        if *w == "mine" {
            id.clone()
        } else {
            w.to_string()
        }
    };
    let out = fresh_dir("own-planner");

    let mut world = mrsim()
        .current_dir(root())
        .args(world_cmd[1..].iter().map(ours))
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start mrsim run");
    let mut agent = std::process::Command::new(example_binary())
        .current_dir(root())
        .args(agent_cmd[cargo.len()..].iter().map(ours))
        .stdout(Stdio::piped())
        .spawn()
        .expect("start the example");
    let agent_status = wait_timeout(&mut agent, 120);
    let world_status = wait_timeout(&mut world, 60);
    let world_out = world.wait_with_output().expect("world output");
    assert!(
        agent_status.is_some_and(|s| s.success()),
        "the example agent: {agent_status:?}"
    );
    assert!(
        world_status.is_some_and(|s| s.success()),
        "mrsim run: {world_status:?}\n{}",
        String::from_utf8_lossy(&world_out.stderr)
    );
    let m = metrics(&out);
    let me = &m["robots"]["me"];
    assert_eq!(me["planner"], "external");
    assert_eq!(me["reached_goal"], true, "{me}");
    assert_eq!(me["commands_rejected"], 0, "{me}");
    assert_eq!(m["agents_lost"], 0);
    assert_eq!(m["robots"]["other"]["reached_goal"], true);
    assert_clean(&id);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn an_external_robot_is_refused_in_process_with_exit_status_2() {
    let out = fresh_dir("external-inproc");
    let o = run(
        &root().join("examples/my_agent.toml"),
        &out,
        &run_id("extin"),
        &["--transport", "inproc"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("`me`") && err.contains("external"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_sweep_over_a_scenario_with_an_external_robot_is_refused_with_exit_status_2() {
    let out = fresh_dir("external-sweep");
    let o = mrsim()
        .arg("sweep")
        .arg(root().join("examples/my_agent.toml"))
        .args(["--seeds", "1", "--out"])
        .arg(out.join("s"))
        .output()
        .expect("mrsim sweep");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("`me`") && err.contains("external"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn mrsim_planners_lists_external() {
    let o = mrsim().arg("planners").output().expect("mrsim planners");
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.lines().any(|l| l.starts_with("external ")), "{text}");
}

/// `homing` under a name of this program's.
fn with_my_homing() -> Arc<Registry> {
    let mut r = Registry::builtin();
    r.register("my-homing", "homing, registered by the test", |p| {
        Ok(Box::new(mrsim_planners::homing::Homing::from_params(p)?))
    })
    .expect("a new name");
    Arc::new(r)
}

/// Runs crossing.toml in-process with every robot's planner `planner`.
fn crossing(
    planner: &str,
    registry: Arc<Registry>,
    out: &Path,
) -> Result<mrsim::RunResult, RunError> {
    mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(root().join("scenarios/crossing.toml")),
            set: vec![format!("planner={planner}")],
            ..Default::default()
        },
        registry,
        out: Some(out.to_path_buf()),
        render: false,
        plan_timeout: None,
    })
}

#[test]
fn a_registered_copy_of_homing_reproduces_homings_run_byte_for_byte() {
    let (a, b) = (fresh_dir("homing"), fresh_dir("my-homing"));
    let builtin = crossing("homing", Arc::new(Registry::builtin()), &a).expect("homing");
    let mine = crossing("my-homing", with_my_homing(), &b).expect("my-homing");
    let read = |d: &Path| std::fs::read(d.join("trajectory.csv")).expect("trajectory.csv");
    assert_eq!(read(&builtin.dir), read(&mine.dir), "trajectories differ");
    assert_eq!(builtin.metrics.ticks, mine.metrics.ticks);
    assert_eq!(builtin.metrics.success_rate, mine.metrics.success_rate);
    assert_eq!(builtin.metrics.robots.len(), 8);
    for (name, h) in &builtin.metrics.robots {
        let m = &mine.metrics.robots[name];
        assert_eq!(m.planner, "my-homing");
        assert_eq!(
            (
                h.reached_goal,
                h.time_to_goal,
                h.path_length,
                h.collisions,
                h.min_clearance
            ),
            (
                m.reached_goal,
                m.time_to_goal,
                m.path_length,
                m.collisions,
                m.min_clearance
            ),
            "{name}"
        );
    }
    for d in [a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Asserts that the run of `dir` was stopped (interrupted) after a number
/// of ticks in `ticks`, with its metrics.json written.
fn assert_stopped_with_outputs(dir: &Path, ticks: std::ops::RangeInclusive<u64>) {
    let m: mrsim::RunMetrics = serde_json::from_str(
        &std::fs::read_to_string(dir.join("metrics.json")).expect("metrics.json"),
    )
    .expect("metrics");
    assert!(m.interrupted);
    assert!(ticks.contains(&m.ticks), "{}", m.ticks);
}

/// Homing, until the robot with index `robot` fails at tick `at`: a
/// panic, or a NaN command. The others never fail.
struct FailsAt {
    at: u64,
    robot: u32,
    panics: bool,
}

impl Planner for FailsAt {
    fn plan(&mut self, obs: &Observation) -> Command {
        if obs.tick == self.at && obs.me.id == self.robot {
            if self.panics {
                panic!("planner bug at tick {}", obs.tick);
            }
            return Command::Velocity(Vec2::new(f64::NAN, 0.0));
        }
        Command::Velocity((obs.goal - obs.me.position).cap_magnitude(obs.me.max_speed))
    }
}

#[test]
fn a_planner_that_panics_or_returns_nan_stops_a_lockstep_run_naming_the_robot_and_the_tick() {
    for panics in [true, false] {
        let mut r = Registry::builtin();
        // Robot 5 of the crossing is b1.
        r.register_simple("fails", "b1 fails at tick 7", move || FailsAt {
            at: 7,
            robot: 5,
            panics,
        })
        .expect("a new name");
        let out = fresh_dir("fails");
        let err = crossing("fails", Arc::new(r), &out).expect_err("the run must fail");
        let RunError::Planner { failure, dir } = &err else {
            panic!("{err}");
        };
        assert_eq!(failure.tick, 7, "{err}");
        assert_eq!(failure.robot, "b1", "{err}");
        let text = err.to_string();
        assert!(
            text.contains(&format!("robot `{}` at tick 7", failure.robot)),
            "{text}"
        );
        assert!(
            text.contains(if panics {
                "panicked: planner bug at tick 7"
            } else {
                "non-finite"
            }),
            "{text}"
        );
        // The outputs so far are written, and end near the failing tick.
        assert_stopped_with_outputs(dir, 7..=9);
        assert!(!trajectory(dir).is_empty());
        let _ = std::fs::remove_dir_all(&out);
    }
}

/// Homing, except that robot b1 (index 5) does not return from its plan at
/// tick `at` until the test lets it go (as a planner caught in an endless
/// loop; released at the end so its thread ends).
struct HangsAt {
    at: u64,
    release: Arc<std::sync::atomic::AtomicBool>,
}

impl Planner for HangsAt {
    fn plan(&mut self, obs: &Observation) -> Command {
        if obs.tick == self.at && obs.me.id == 5 {
            while !self.release.load(std::sync::atomic::Ordering::SeqCst) {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        }
        Command::Velocity((obs.goal - obs.me.position).cap_magnitude(obs.me.max_speed))
    }
}

#[test]
fn a_planner_that_never_returns_stops_a_lockstep_run_after_the_plan_timeout_naming_robot_and_tick()
{
    let release = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let mut r = Registry::builtin();
    let held = release.clone();
    r.register_simple("hangs", "b1 hangs at tick 4", move || HangsAt {
        at: 4,
        release: held.clone(),
    })
    .expect("a new name");
    let out = fresh_dir("hangs");
    let result = mrsim::run_in_process(&InProcess {
        scenario: ScenarioSource {
            path: Some(root().join("scenarios/crossing.toml")),
            set: vec!["planner=hangs".to_string()],
            ..Default::default()
        },
        registry: Arc::new(r),
        out: Some(out.clone()),
        render: false,
        plan_timeout: Some(std::time::Duration::from_secs(1)),
    });
    release.store(true, std::sync::atomic::Ordering::SeqCst);
    let err = result.expect_err("the run must stop");
    let RunError::Planner { failure, dir } = &err else {
        panic!("{err}");
    };
    assert_eq!((failure.robot.as_str(), failure.tick), ("b1", 4), "{err}");
    let text = err.to_string();
    assert!(
        text.contains(
            "robot `b1` at tick 4: the planner did not return within the limit of 1.000 s"
        ),
        "{text}"
    );
    // The outputs so far are written, up to the tick it hung at.
    assert_stopped_with_outputs(dir, 4..=5);
    assert!(trajectory(dir).iter().any(|r| r.tick == 3));
    let _ = std::fs::remove_dir_all(&out);
}
