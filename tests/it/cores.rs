//! The cores in lockstep through the real binary: the world's model of the
//! cores decides when the planners whose compute is CPU work read and send
//! (deterministic over shared memory and in process), a core per robot
//! gives what the timing model gives alone, and sharing the cores makes
//! the misses the robots' own cores did not.

use crate::common::*;
use std::path::Path;

/// Four orca robots crossing in pairs and one obstacle at 10 Hz, every
/// robot's `[defaults.timing]` being `timing`, and `cpus` the body of a
/// `[world.cpus]` table (none if empty).
fn crossing(cpus: &str, timing: &str, duration: f64) -> String {
    let cpus = if cpus.is_empty() {
        String::new()
    } else {
        format!("[world.cpus]\n{cpus}\n")
    };
    format!(
        r#"name = "cored-crossing"
[world]
dt = 0.1
substeps = 10
duration = {duration}
seed = 7
stall_timeout = 10.0

{cpus}
[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 4.0
planner = "orca"

[defaults.timing]
{timing}

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [6.0, 0.0]

[[robot]]
name = "r1"
start = [6.0, 0.3]
goal = [0.0, 0.3]

[[robot]]
name = "r2"
start = [3.0, -3.0]
goal = [3.0, 3.0]

[[robot]]
name = "r3"
start = [3.2, 3.0]
goal = [3.2, -3.0]

[[obstacle]]
name = "o1"
start = [1.5, 2.0]
radius = 0.3
motion = {{ model = "random", accel_sigma = 0.5, alpha1 = 0.8, beta1 = 0.5, max_speed = 0.4 }}
"#
    )
}

/// Runs `text` into `dir/tag` with `extra` arguments; the run folder.
fn go(dir: &Path, text: &str, tag: &str, extra: &[&str]) -> std::path::PathBuf {
    let f = dir.join(format!("{tag}.toml"));
    std::fs::write(&f, text).expect("write scenario");
    let out = dir.join(tag);
    let mut args = vec!["--quiet", "--no-report"];
    args.extend(extra);
    assert_ok(&run(&f, &out, &run_id(tag), &args));
    out
}

fn bytes(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()))
}

/// Per robot: (deadline_misses, commands_late).
fn misses(dir: &Path) -> Vec<(u64, u64)> {
    let m = metrics(dir);
    (0..4)
        .map(|i| {
            let r = &m["robots"][format!("r{i}")];
            (
                r["deadline_misses"].as_u64().expect("misses"),
                r["commands_late"].as_u64().expect("late"),
            )
        })
        .collect()
}

/// timing.csv's rows, sorted: (tick, robot, sent_ns, status).
fn calls(dir: &Path) -> Vec<(u64, String, u64, String)> {
    let text = std::fs::read_to_string(dir.join("timing.csv")).expect("timing.csv");
    let mut rows: Vec<_> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().expect("tick"),
                f[1].to_string(),
                f[2].parse().expect("sent_ns"),
                f[3].to_string(),
            )
        })
        .collect();
    rows.sort();
    rows
}

const VARIED: &str = r#"compute = { model = "uniform", min_ms = 10.0, max_ms = 70.0, cpu = true }
observation_delay_ms = 100.0
actuation_delay_ms = 20.0
snapshot_loss = 0.1
command_loss = 0.05"#;

#[test]
fn shared_cores_give_the_same_trajectory_and_misses_over_shared_memory_and_in_process() {
    let dir = fresh_dir("cores-twice");
    for cpus in [
        "count = 1",
        "count = 1\nscheduler = \"fifo\"\nworld_ms = 5",
        "count = 1\nscheduler = \"deadline\"",
    ] {
        let timing = format!("{VARIED}\nreservation = {{ runtime_ms = 25, period_ms = 100 }}");
        let text = crossing(cpus, &timing, 6.0);
        let a = go(&dir, &text, "a", &["--transport", "inproc"]);
        let b = go(&dir, &text, "b", &["--transport", "inproc"]);
        let c = go(&dir, &text, "c", &[]);
        let ma = misses(&a);
        assert!(
            ma.iter().any(|&(_, l)| l > 0),
            "{cpus}: one core for four makes late commands: {ma:?}"
        );
        for other in [&b, &c] {
            assert_eq!(
                bytes(&a, "trajectory.csv"),
                bytes(other, "trajectory.csv"),
                "{cpus}"
            );
            assert_eq!(calls(&a), calls(other), "{cpus}");
            assert_eq!(ma, misses(other), "{cpus}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_core_per_robot_gives_what_the_timing_model_gives_alone() {
    let dir = fresh_dir("cores-own");
    let alone = crossing("", &VARIED.replace(", cpu = true", ""), 6.0);
    let cored = crossing("count = 4", VARIED, 6.0);
    let a = go(&dir, &alone, "alone", &["--transport", "inproc"]);
    let b = go(&dir, &cored, "cored", &["--transport", "inproc"]);
    assert_eq!(bytes(&a, "trajectory.csv"), bytes(&b, "trajectory.csv"));
    assert_eq!(calls(&a), calls(&b));
    assert_eq!(misses(&a), misses(&b));
    // Without [world.cpus], cpu = true is a core of its own per agent too.
    let own = crossing("", VARIED, 6.0);
    let c = go(&dir, &own, "own", &["--transport", "inproc"]);
    assert_eq!(bytes(&a, "trajectory.csv"), bytes(&c, "trajectory.csv"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn four_planners_of_40_ms_on_one_core_miss_where_each_on_its_own_core_does_not() {
    let dir = fresh_dir("cores-share");
    let timing = "compute = { ms = 40, cpu = true }";
    let own = go(
        &dir,
        &crossing("count = 4", timing, 3.0),
        "own",
        &["--transport", "inproc"],
    );
    assert_eq!(misses(&own), vec![(0, 0); 4]);
    // 160 ms of work per 100 ms tick on one core: under fair every call
    // takes 160 ms, so every command is late and no robot moves.
    let one = go(
        &dir,
        &crossing("count = 1", timing, 3.0),
        "one",
        &["--transport", "inproc"],
    );
    assert!(
        misses(&one).iter().all(|&(m, l)| m == 30 && l > 0),
        "{:?}",
        misses(&one)
    );
    // Under fifo the two of highest priority keep their deadlines (40 +
    // 40 ms), the other two miss; rate-monotonic at equal periods is by
    // name.
    let fifo = go(
        &dir,
        &crossing("count = 1\nscheduler = \"fifo\"", timing, 3.0),
        "fifo",
        &["--transport", "inproc"],
    );
    let m = misses(&fifo);
    assert_eq!((m[0].0, m[1].0), (0, 0), "{m:?}");
    assert!(m[2].0 > 0 && m[3].0 > 0, "{m:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `mrsim rerun RUN --out OUT [extra]`.
fn rerun(recorded: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    mrsim()
        .arg("rerun")
        .arg(recorded)
        .arg("--out")
        .arg(out)
        .arg("--no-report")
        .args(extra)
        .output()
        .expect("start mrsim rerun")
}

#[test]
fn rerun_replays_recorded_times_and_another_scheduler_re_decides_them_from_the_model() {
    let dir = fresh_dir("cores-rerun");
    // Four planners of 40 ms CPU work on "one core", run in realtime: the
    // record has the times the machine gave them.
    let text = crossing("count = 1", "compute = { ms = 40, cpu = true }", 3.0)
        .replace("seed = 7", "seed = 7\nmode = \"realtime\"");
    let rec = go(&dir, &text, "realtime", &[]);
    let again = dir.join("again");
    let out = rerun(&rec, &again, &[]);
    assert_ok(&out);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("rerun (recorded times)"), "{said}");
    assert!(!said.contains("modelled"), "{said}");
    assert_eq!(
        bytes(&rec, "trajectory.csv"),
        bytes(&again, "trajectory.csv")
    );
    // Another scheduler: the model decides, as a lockstep run of it would.
    let cf = dir.join("fifo");
    let out = rerun(&rec, &cf, &["--set", "world.cpus.scheduler=fifo"]);
    assert_ok(&out);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("modelled counterfactual"), "{said}");
    assert!(said.contains("r0, r1, r2, r3"), "{said}");
    let lockstep = crossing(
        "count = 1\nscheduler = \"fifo\"",
        "compute = { ms = 40, cpu = true }",
        3.0,
    );
    let direct = go(&dir, &lockstep, "lockstep", &["--transport", "inproc"]);
    assert_eq!(misses(&cf), misses(&direct));
    assert_eq!(calls(&cf), calls(&direct));
    assert_eq!(
        bytes(&cf, "trajectory.csv"),
        bytes(&direct, "trajectory.csv")
    );
    let _ = std::fs::remove_dir_all(&dir);
}
