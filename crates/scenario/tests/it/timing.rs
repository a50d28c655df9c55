//! `[defaults.timing]` and `[robot.timing]`: resolved per robot, reachable
//! with overrides, and every bad value refused at its line.

use crate::common::*;
use mrsim_scenario::parse_with_overrides;
use mrsim_scenario::timing::{Compute, Timing};

/// BASE with a `[defaults.timing]` table holding `body`.
fn timed(body: &str) -> String {
    with(
        BASE,
        "field_of_view_deg = 360\n",
        &format!("field_of_view_deg = 360\n\n[defaults.timing]\n{body}\n"),
    )
}

#[test]
fn a_scenario_without_timing_has_none_on_any_robot() {
    let l = accept(BASE);
    assert!(l.scenario.robots.iter().all(|r| r.timing.is_none()));
    let json = serde_json::to_string(&l.scenario).unwrap();
    assert!(!json.contains("timing"), "{json}");
}

#[test]
fn defaults_timing_reaches_every_robot_and_a_robot_table_overrides_it_key_by_key() {
    let src =
        timed("compute = { model = \"fixed\", ms = 30.0 }\nperiod_ticks = 2\nsnapshot_loss = 0.1");
    let src = with(
        &src,
        "radius = 0.3\n",
        "radius = 0.3\n\n[robot.timing]\ncompute = { model = \"uniform\", min_ms = 5, max_ms = 15 }\ncommand_loss = 0.5\n",
    );
    let l = accept(&src);
    let r0 = l.scenario.robots[0].timing.clone().unwrap();
    assert_eq!(
        r0,
        Timing {
            compute: Compute::Fixed { ms: 30.0 },
            period_ticks: 2,
            snapshot_loss: 0.1,
            ..Timing::default()
        }
    );
    let r1 = l.scenario.robots[1].timing.clone().unwrap();
    assert_eq!(
        r1.compute,
        Compute::Uniform {
            min_ms: 5.0,
            max_ms: 15.0
        }
    );
    assert_eq!(
        (r1.period_ticks, r1.snapshot_loss, r1.command_loss),
        (2, 0.1, 0.5)
    );
}

#[test]
fn every_timing_key_is_reachable_with_an_override() {
    let src = timed("compute = { model = \"fixed\", ms = 30.0 }");
    let sets: Vec<(String, String)> = [
        ("defaults.timing.compute.ms", "40"),
        ("defaults.timing.observation_delay_ms", "100"),
        ("defaults.timing.actuation_delay_ms", "20"),
        ("defaults.timing.period_ticks", "3"),
        ("defaults.timing.snapshot_loss", "0.25"),
        ("robot.r1.timing.command_loss", "0.5"),
        (
            "robot.r1.timing.compute",
            "{ model = \"per-body\", base_ms = 5, per_body_ms = 2 }",
        ),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    let l = parse_with_overrides(&src, "t.toml", &sets).unwrap();
    let r0 = l.scenario.robots[0].timing.clone().unwrap();
    assert_eq!(
        r0,
        Timing {
            compute: Compute::Fixed { ms: 40.0 },
            observation_delay_ms: 100.0,
            actuation_delay_ms: 20.0,
            period_ticks: 3,
            snapshot_loss: 0.25,
            command_loss: 0.0,
            ..Timing::default()
        }
    );
    let r1 = l.scenario.robots[1].timing.clone().unwrap();
    assert_eq!(
        r1.compute,
        Compute::PerBody {
            base_ms: 5.0,
            per_body_ms: 2.0
        }
    );
    assert_eq!(r1.command_loss, 0.5);
    // Without any timing in the file, an override alone makes the table.
    let sets = vec![("defaults.timing.period_ticks".to_string(), "2".to_string())];
    let l = parse_with_overrides(BASE, "t.toml", &sets).unwrap();
    assert_eq!(
        l.scenario.robots[0].timing.as_ref().unwrap().period_ticks,
        2
    );
}

#[test]
fn a_negative_time_is_refused_at_its_line() {
    let src = timed("compute = { model = \"fixed\", ms = -1.0 }");
    refused_at(&src, "ms = -1.0", "timing.compute.ms must be >= 0, got -1");
    let src = timed("actuation_delay_ms = -5");
    refused_at(&src, "actuation_delay_ms", "must be >= 0");
}

#[test]
fn a_loss_outside_zero_to_one_is_refused_at_its_line() {
    let src = timed("snapshot_loss = 1.5");
    refused_at(&src, "snapshot_loss", "probability, in [0, 1], got 1.5");
    let src = timed("command_loss = -0.1");
    refused_at(&src, "command_loss", "probability");
}

#[test]
fn period_ticks_zero_is_refused_at_its_line() {
    let src = timed("period_ticks = 0");
    refused_at(&src, "period_ticks", "whole number >= 1, got 0");
}

#[test]
fn an_unknown_compute_model_is_refused_at_its_line_with_the_known_ones() {
    let src = timed("compute = { model = \"gamma\", ms = 3 }");
    refused_at(
        &src,
        "gamma",
        "unknown timing.compute model `gamma` (known: none, fixed",
    );
}

#[test]
fn a_compute_model_missing_or_given_a_foreign_number_is_refused() {
    let src = timed("compute = { model = \"lognormal\", median_ms = 3 }");
    refused_at(&src, "lognormal", "needs `sigma`");
    let src = timed("compute = { model = \"fixed\", ms = 3, sigma = 1 }");
    refused_at(&src, "fixed", "takes no `sigma`");
    let src = timed("compute = { model = \"uniform\", min_ms = 9, max_ms = 3 }");
    refused_at(&src, "uniform", "max_ms (3) must be >= min_ms (9)");
    let src = timed("compute = { ms = 3, sigma = 1 }");
    refused_at(&src, "compute", "needs `model`");
}

#[test]
fn the_numbers_of_one_model_name_it_so_a_sweep_needs_no_model_in_the_file() {
    let src = timed("compute = { ms = 3 }");
    let t = accept(&src).scenario.robots[0].timing.clone().unwrap();
    assert_eq!(t.compute, Compute::Fixed { ms: 3.0 });
    let src = timed("compute = { min_ms = 1, max_ms = 4 }");
    let t = accept(&src).scenario.robots[0].timing.clone().unwrap();
    assert_eq!(
        t.compute,
        Compute::Uniform {
            min_ms: 1.0,
            max_ms: 4.0
        }
    );
    // `mrsim sweep --set defaults.timing.compute.ms=0,20,40` on a file
    // without timing.
    let sets = vec![("defaults.timing.compute.ms".to_string(), "40".to_string())];
    let l = parse_with_overrides(BASE, "t.toml", &sets).unwrap();
    assert_eq!(
        l.scenario.robots[0].timing.as_ref().unwrap().compute,
        Compute::Fixed { ms: 40.0 }
    );
}

#[test]
fn an_unknown_timing_key_is_refused_at_its_line() {
    let src = timed("latency_ms = 3");
    refused_at(&src, "latency_ms", "unknown field `latency_ms`");
}
