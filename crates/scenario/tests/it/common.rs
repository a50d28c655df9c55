//! Helpers shared by the scenario tests.
#![allow(dead_code)]

use mrsim_scenario::{Loaded, ScenarioError, parse};

/// A small valid scenario; tests edit it with `with`.
pub const BASE: &str = r#"name = "base"
description = "test scenario"

[world]
dt = 0.1
substeps = 10
duration = 30.0
deadline = 1.0
arena = { min = [-10.0, -10.0], max = [10.0, 10.0] }

[defaults]
mass = 1.0
max_speed = 1.0
max_accel = 2.0
goal_tolerance = 0.1
field_of_view_deg = 360

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [5.0, 0.0]

[[robot]]
name = "r1"
start = [0.0, 3.0]
goal = [5.0, 3.0]
radius = 0.3

[[obstacle]]
name = "o1"
start = [-5.0, -5.0]
radius = 0.5
motion = { model = "constant-velocity", velocity = [1.0, 0.0] }

[[wall]]
segment = [[-8.0, 8.0], [8.0, 8.0]]
"#;

/// `src` with the one occurrence of `old` replaced by `new`.
pub fn with(src: &str, old: &str, new: &str) -> String {
    assert_eq!(src.matches(old).count(), 1, "`{old}` must occur once");
    src.replacen(old, new, 1)
}

/// The 1-based line of the one occurrence of `needle` in `src`.
pub fn line_of(src: &str, needle: &str) -> usize {
    assert_eq!(src.matches(needle).count(), 1, "`{needle}` must occur once");
    let at = src.find(needle).unwrap();
    src[..at].matches('\n').count() + 1
}

/// Parses `src`, which must be refused.
pub fn refuse(src: &str) -> ScenarioError {
    match parse(src, "t.toml") {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => e,
    }
}

/// Parses `src`, which must be refused at the line holding `needle`, with a
/// message containing `words`.
pub fn refused_at(src: &str, needle: &str, words: &str) -> ScenarioError {
    let e = refuse(src);
    let line = line_of(src, needle);
    assert_eq!(e.line(), Some(line), "wrong line for `{e}`");
    let shown = e.to_string();
    assert!(shown.starts_with(&format!("t.toml:{line}")), "{shown}");
    assert!(shown.contains(words), "`{shown}` lacks `{words}`");
    e
}

/// Parses `src`, which must be accepted.
pub fn accept(src: &str) -> Loaded {
    match parse(src, "t.toml") {
        Ok(l) => l,
        Err(e) => panic!("refused: {e}\n{src}"),
    }
}
