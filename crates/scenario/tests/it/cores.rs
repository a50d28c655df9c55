//! `[world.cpus]` and the timing keys of CPU work (`compute.cpu`,
//! `priority`, `reservation`): resolved, reachable with overrides, every
//! bad value refused at its line.

use crate::common::*;
use mrsim_scenario::timing::{Compute, Priority, Reservation};
use mrsim_scenario::{Cpus, Scheduler, parse_with_overrides};

/// BASE with `cpus` as its `[world.cpus]` table (if not empty) and `timing`
/// as its `[defaults.timing]` table.
fn cored(cpus: &str, timing: &str) -> String {
    let mut src = BASE.to_string();
    if !cpus.is_empty() {
        src = with(
            &src,
            "[defaults]\n",
            &format!("[world.cpus]\n{cpus}\n\n[defaults]\n"),
        );
    }
    with(
        &src,
        "field_of_view_deg = 360\n",
        &format!("field_of_view_deg = 360\n\n[defaults.timing]\n{timing}\n"),
    )
}

fn sets(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn a_scenario_without_cpus_or_cpu_resolves_and_serialises_as_before() {
    let l = accept(&cored("", "compute = { model = \"fixed\", ms = 20 }"));
    assert_eq!(l.scenario.world.cpus, None);
    let t = l.scenario.robots[0].timing.clone().unwrap();
    assert!(!t.cpu && t.priority.is_none() && t.reservation.is_none());
    let json = serde_json::to_string(&l.scenario).unwrap();
    for key in ["cpus", "\"cpu\"", "priority", "reservation"] {
        assert!(!json.contains(key), "{key} in {json}");
    }
}

#[test]
fn world_cpus_gives_count_scheduler_and_world_ms_with_their_defaults() {
    let l = accept(&cored("count = 2", "compute = { ms = 20, cpu = true }"));
    assert_eq!(
        l.scenario.world.cpus,
        Some(Cpus {
            count: 2,
            scheduler: Scheduler::Fair,
            world_ms: 0.0
        })
    );
    let l = accept(&cored(
        "count = 4\nscheduler = \"fifo\"\nworld_ms = 1.5",
        "compute = { ms = 20, cpu = true }",
    ));
    assert_eq!(
        l.scenario.world.cpus,
        Some(Cpus {
            count: 4,
            scheduler: Scheduler::Fifo,
            world_ms: 1.5
        })
    );
}

#[test]
fn cpu_is_a_key_of_every_compute_model_and_fixed_without_model() {
    for (compute, model) in [
        ("{ ms = 20, cpu = true }", Compute::Fixed { ms: 20.0 }),
        (
            "{ model = \"fixed\", ms = 20, cpu = true }",
            Compute::Fixed { ms: 20.0 },
        ),
        (
            "{ model = \"uniform\", min_ms = 1, max_ms = 3, cpu = true }",
            Compute::Uniform {
                min_ms: 1.0,
                max_ms: 3.0,
            },
        ),
        (
            "{ model = \"lognormal\", median_ms = 5, sigma = 0.2, cpu = true }",
            Compute::Lognormal {
                median_ms: 5.0,
                sigma: 0.2,
            },
        ),
        (
            "{ model = \"per-body\", base_ms = 2, per_body_ms = 1, cpu = true }",
            Compute::PerBody {
                base_ms: 2.0,
                per_body_ms: 1.0,
            },
        ),
        ("{ model = \"none\", cpu = true }", Compute::None),
    ] {
        let l = accept(&cored("count = 1", &format!("compute = {compute}")));
        let t = l.scenario.robots[1].timing.clone().unwrap();
        assert_eq!((t.compute, t.cpu), (model, true), "{compute}");
    }
    let l = accept(&cored("", "compute = { ms = 20, cpu = false }"));
    assert!(!l.scenario.robots[0].timing.clone().unwrap().cpu);
}

#[test]
fn priority_and_reservation_resolve_per_robot_and_a_robot_table_overrides_defaults() {
    let src = cored(
        "count = 2\nscheduler = \"deadline\"",
        "compute = { ms = 20, cpu = true }\npriority = 10\nreservation = { runtime_ms = 25, period_ms = 100 }",
    );
    let src = with(
        &src,
        "radius = 0.3\n",
        "radius = 0.3\n\n[robot.timing]\npriority = \"rate-monotonic\"\nreservation = { runtime_ms = 50 }\n",
    );
    let l = accept(&src);
    let r0 = l.scenario.robots[0].timing.clone().unwrap();
    assert_eq!(r0.priority, Some(Priority::Level(10)));
    assert_eq!(
        r0.reservation,
        Some(Reservation {
            runtime_ms: 25.0,
            period_ms: 100.0
        })
    );
    let r1 = l.scenario.robots[1].timing.clone().unwrap();
    assert_eq!(r1.priority, Some(Priority::RateMonotonic));
    assert_eq!(
        r1.reservation,
        Some(Reservation {
            runtime_ms: 50.0,
            period_ms: 100.0
        })
    );
    assert!(r1.cpu);
    // And back from the resolved scenario's JSON.
    let json = serde_json::to_string(&l.scenario).unwrap();
    let back: mrsim_scenario::Scenario = serde_json::from_str(&json).unwrap();
    assert_eq!(back, l.scenario);
}

#[test]
fn every_cores_key_is_reachable_with_an_override() {
    let src = cored("count = 2", "compute = { ms = 20 }");
    let l = parse_with_overrides(
        &src,
        "t.toml",
        &sets(&[
            ("world.cpus.count", "3"),
            ("world.cpus.scheduler", "deadline"),
            ("world.cpus.world_ms", "2"),
            ("defaults.timing.compute.cpu", "true"),
            (
                "defaults.timing.reservation",
                "{ runtime_ms = 10, period_ms = 100 }",
            ),
            ("robot.r1.timing.reservation.runtime_ms", "30"),
            ("robot.r0.timing.priority", "7"),
        ]),
    )
    .unwrap();
    assert_eq!(
        l.scenario.world.cpus,
        Some(Cpus {
            count: 3,
            scheduler: Scheduler::Deadline,
            world_ms: 2.0
        })
    );
    let r0 = l.scenario.robots[0].timing.clone().unwrap();
    assert!(r0.cpu);
    assert_eq!(r0.priority, Some(Priority::Level(7)));
    assert_eq!(r0.reservation.unwrap().runtime_ms, 10.0);
    let r1 = l.scenario.robots[1].timing.clone().unwrap();
    assert_eq!(r1.reservation.unwrap().runtime_ms, 30.0);
    // A file without the table gets it from overrides alone.
    let l = parse_with_overrides(BASE, "t.toml", &sets(&[("world.cpus.count", "2")])).unwrap();
    assert_eq!(l.scenario.world.cpus.unwrap().count, 2);
}

#[test]
fn a_bad_core_count_or_scheduler_or_world_time_is_refused_at_its_line() {
    let t = "compute = { ms = 20, cpu = true }";
    refused_at(
        &cored("count = 0", t),
        "count = 0",
        "count must be a whole number >= 1, got 0",
    );
    refused_at(&cored("count = -2", t), "count = -2", "got -2");
    refused_at(
        &cored("count = 2\nscheduler = \"rr\"", t),
        "scheduler",
        "unknown scheduler `rr` (known: fair, fifo, deadline)",
    );
    refused_at(
        &cored("count = 2\nworld_ms = -1", t),
        "world_ms",
        "world_ms must be >= 0, got -1",
    );
    refused_at(
        &cored("scheduler = \"fair\"", t),
        "[world.cpus]",
        "missing `count`",
    );
    refused_at(&cored("count = 2\ncores = 3", t), "cores", "unknown field");
    refused_at(
        &cored("count = 1.5", t),
        "count = 1.5",
        "floating point `1.5`",
    );
}

#[test]
fn a_priority_outside_one_to_ninety_nine_or_an_unknown_name_is_refused_at_its_line() {
    for (p, words) in [
        ("0", "got 0"),
        ("100", "got 100"),
        ("\"highest\"", "got \"highest\""),
        ("1.5", "1..99 or \"rate-monotonic\""),
    ] {
        let src = cored("count = 1", &format!("priority = {p}"));
        refused_at(&src, "priority", words);
    }
}

#[test]
fn a_reservation_without_both_numbers_or_with_runtime_above_its_period_is_refused_at_its_line() {
    for (r, words) in [
        (
            "{ runtime_ms = 0, period_ms = 100 }",
            "timing.reservation.runtime_ms must be > 0, got 0",
        ),
        (
            "{ runtime_ms = 10, period_ms = -1 }",
            "timing.reservation.period_ms must be > 0",
        ),
        ("{ runtime_ms = 10 }", "needs `period_ms`"),
        (
            "{ runtime_ms = 120, period_ms = 100 }",
            "runtime_ms (120) must be <= period_ms (100)",
        ),
        (
            "{ runtime_ms = 1, period_ms = 2, budget = 3 }",
            "unknown field",
        ),
    ] {
        let src = cored("count = 1", &format!("reservation = {r}"));
        refused_at(&src, "reservation", words);
    }
}

#[test]
fn deadline_with_a_cpu_robot_without_reservation_is_refused_at_its_cpu_key() {
    let src = cored(
        "count = 2\nscheduler = \"deadline\"",
        "compute = { ms = 20, cpu = true }",
    );
    let e = refused_at(
        &src,
        "cpu = true",
        "needs timing.reservation = { runtime_ms, period_ms }",
    );
    assert!(e.to_string().contains("robot `r0`"), "{e}");
    // A wait takes no core and needs none; fair and fifo need none either.
    accept(&cored(
        "count = 2\nscheduler = \"deadline\"",
        "compute = { ms = 20 }",
    ));
    accept(&cored(
        "count = 2\nscheduler = \"fifo\"",
        "compute = { ms = 20, cpu = true }",
    ));
    // Chosen by an override, named by it.
    let e = parse_with_overrides(
        &cored("count = 2", "compute = { ms = 20, cpu = true }"),
        "t.toml",
        &sets(&[("world.cpus.scheduler", "deadline")]),
    )
    .unwrap_err();
    assert!(e.to_string().contains("needs timing.reservation"), "{e}");
}

#[test]
fn cpu_work_without_world_cpus_is_accepted_as_a_core_per_agent() {
    let l = accept(&cored("", "compute = { ms = 20, cpu = true }"));
    assert!(l.scenario.world.cpus.is_none());
    assert!(
        l.scenario
            .robots
            .iter()
            .all(|r| r.timing.as_ref().unwrap().cpu)
    );
}
