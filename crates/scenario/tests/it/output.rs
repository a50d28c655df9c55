//! `[output]`: the trajectory's format and how often it records.

use crate::common::*;
use mrsim_scenario::{OutputConfig, TrajectoryFormat, parse_with_overrides};

fn with_output(table: &str) -> String {
    format!("{BASE}\n[output]\n{table}\n")
}

#[test]
fn without_an_output_table_the_trajectory_is_csv_at_every_tick() {
    let l = accept(BASE);
    assert_eq!(l.scenario.output, OutputConfig::default());
    assert_eq!(l.scenario.output.trajectory, TrajectoryFormat::Csv);
    assert_eq!(l.scenario.output.every, 1);
}

#[test]
fn a_default_output_is_left_out_of_the_resolved_json() {
    let json = serde_json::to_string(&accept(BASE).scenario).expect("json");
    assert!(!json.contains("\"output\""), "{json}");
    let set = accept(&with_output("trajectory = \"parquet\"\nevery = 5"));
    let json = serde_json::to_string(&set.scenario).expect("json");
    assert!(
        json.contains(r#""output":{"trajectory":"parquet","every":5}"#),
        "{json}"
    );
    let back: mrsim_scenario::Scenario = serde_json::from_str(&json).expect("reads back");
    assert_eq!(back.output, set.scenario.output);
}

#[test]
fn each_format_is_accepted() {
    for (word, format) in [
        ("csv", TrajectoryFormat::Csv),
        ("parquet", TrajectoryFormat::Parquet),
        ("none", TrajectoryFormat::None),
    ] {
        let l = accept(&with_output(&format!("trajectory = \"{word}\"")));
        assert_eq!(l.scenario.output.trajectory, format, "{word}");
    }
}

#[test]
fn an_unknown_format_is_refused_at_its_line() {
    let src = with_output("trajectory = \"hdf5\"");
    refused_at(&src, "hdf5", "unknown variant `hdf5`");
}

#[test]
fn every_below_one_is_refused_at_its_line() {
    for bad in ["0", "-3"] {
        let src = with_output(&format!("every = {bad}"));
        refused_at(
            &src,
            "every =",
            "every must be a whole number of ticks >= 1",
        );
    }
}

#[test]
fn every_that_is_not_a_whole_number_is_refused() {
    let src = with_output("every = 2.5");
    refused_at(&src, "every =", "");
}

#[test]
fn an_unknown_output_key_is_refused_at_its_line() {
    let src = with_output("format = \"csv\"");
    refused_at(&src, "format", "unknown field `format`");
}

#[test]
fn output_keys_can_be_set_from_the_command_line() {
    let pairs = [
        ("output.trajectory".to_string(), "none".to_string()),
        ("output.every".to_string(), "10".to_string()),
    ];
    let l = parse_with_overrides(BASE, "t.toml", &pairs).expect("valid");
    assert_eq!(l.scenario.output.trajectory, TrajectoryFormat::None);
    assert_eq!(l.scenario.output.every, 10);
}

#[test]
fn every_kth_tick_is_recorded() {
    let o = OutputConfig {
        trajectory: TrajectoryFormat::Csv,
        every: 3,
        ..OutputConfig::default()
    };
    let recorded: Vec<u64> = (0..10).filter(|&t| o.records(t)).collect();
    assert_eq!(recorded, [0, 3, 6, 9]);
    assert!((0..10).all(|t| OutputConfig::default().records(t)));
}

#[test]
fn mcap_is_off_unless_asked_for_and_asked_for_in_the_file_or_with_set() {
    let l = parse_with_overrides(BASE, "t.toml", &[]).expect("valid");
    assert!(!l.scenario.output.mcap);
    let with = format!("{BASE}\n[output]\nmcap = true\n");
    assert!(
        parse_with_overrides(&with, "t.toml", &[])
            .expect("valid")
            .scenario
            .output
            .mcap
    );
    let pairs = [("output.mcap".to_string(), "true".to_string())];
    assert!(
        parse_with_overrides(BASE, "t.toml", &pairs)
            .expect("valid")
            .scenario
            .output
            .mcap
    );
    let bad = format!("{BASE}\n[output]\nmcap = \"yes\"\n");
    let err = parse_with_overrides(&bad, "t.toml", &[]).expect_err("a string is no bool");
    assert!(err.to_string().contains("t.toml:"), "{err}");
}
