//! Random mutations of a valid scenario never panic the loader, and every
//! error names the file and, when it comes from the file, the line.

use mrsim_scenario::{ScenarioError, parse, parse_with_overrides};
use proptest::prelude::*;

const ORIGIN: &str = "fuzz.toml";

/// A valid scenario using every section.
const RICH: &str = r#"name = "rich"
description = "every section"
length_unit = "m"

[world]
dt = 0.1
substeps = 10
duration = 20.0
mode = "lockstep"
on_deadline_miss = "brake"
seed = 3
arena = { min = [-20, -20], max = [20, 20] }
deadline = 0.5
stall_timeout = 2.0

[defaults]
radius = 0.2
mass = 1.0
damping = 0.1
max_speed = 1.5
max_accel = 3.0
velocity_lag = 0.1
sensing_range = 10.0
field_of_view_deg = 270
goal_tolerance = 0.2
goal_hold_ticks = 2
velocity_source = "differenced"
position_noise = 0.01
params = { gain = 1.0 }

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [10.0, 0.0]
planner = "vdf"
params = { alpha = 5.0, shape = "ellipse", on = true, speeds = [0.1, 0.2] }
path = [[0, 0], [10, 0]]
boundary = 1.0

[[robot]]
name = "r1"
start = [0.0, 3.0]
goal = [10.0, 3.0]

[[obstacle]]
name = "o1"
start = [5.0, -5.0]
radius = 0.5
motion = { model = "waypoints", points = [[5, 5], [6, 6]], speed = 0.5, loop = true }

[[obstacle]]
name = "o2"
start = [-5.0, -5.0]
motion = { model = "random", distribution = "uniform", accel_sigma = 0.3, max_speed = 1.0 }

[[obstacle]]
name = "o3"
start = [-5.0, 5.0]
motion = { model = "intentional", behavior = "pursue", target = "r0", max_speed = 1.0, max_accel = 1.0 }

[[wall]]
segment = [[-15.0, 15.0], [15.0, 15.0]]

[generate]
kind = "circle"
count = 6
radius = 8.0
center = [0.0, -10.0]
planner = "orca"
robot_radius = 0.2
name_prefix = "g"
"#;

#[derive(Debug, Clone)]
enum Mutation {
    /// Replace, insert or delete one character.
    Byte { at: usize, op: u8, ch: char },
    /// Delete `n` lines from line `at`.
    Lines { at: usize, n: usize },
    /// Replace the value of the `at`-th `key = value` line.
    Value { at: usize, value: &'static str },
}

const CHARS: &[char] = &[
    '[', ']', '{', '}', '=', '"', '\'', '.', ',', '-', '+', '0', '1', '9', 'e', ' ', '\n', '#',
    'a', 'n', 'i', 'f', '_', '\\', 'é', '\t',
];
const VALUES: &[&str] = &[
    "-1",
    "0",
    "1",
    "1e300",
    "-1e-300",
    "nan",
    "-inf",
    "inf",
    "1e400",
    "\"x\"",
    "\"\"",
    "true",
    "[]",
    "[1]",
    "[1, 2]",
    "[1, 2, 3]",
    "[[0, 0]]",
    "[[0, 0], [1, 1], [2, 2]]",
    "{}",
    "{ a = 1 }",
    "99999999999999999999",
    "0x10",
    "2024-01-01",
    "\"r1\"",
    "\"o1\"",
    "\"g00\"",
    "\"circle\"",
    "\"random\"",
    "\"crossing\"",
    "\"corridor\"",
    "\"static\"",
    "\"intentional\"",
    "4000",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..3, prop::sample::select(CHARS))
            .prop_map(|(at, op, ch)| Mutation::Byte { at, op, ch }),
        (any::<usize>(), 1usize..4).prop_map(|(at, n)| Mutation::Lines { at, n }),
        (any::<usize>(), prop::sample::select(VALUES))
            .prop_map(|(at, value)| Mutation::Value { at, value }),
    ]
}

fn apply(src: &str, m: &Mutation) -> String {
    match *m {
        Mutation::Byte { at, op, ch } => {
            let mut chars: Vec<char> = src.chars().collect();
            let i = at % (chars.len() + 1);
            match op {
                0 if i < chars.len() => chars[i] = ch,
                1 => chars.insert(i, ch),
                _ if i < chars.len() => {
                    chars.remove(i);
                }
                _ => chars.push(ch),
            }
            chars.into_iter().collect()
        }
        Mutation::Lines { at, n } => {
            let lines: Vec<&str> = src.lines().collect();
            let i = at % lines.len().max(1);
            let mut out: Vec<&str> = lines[..i].to_vec();
            out.extend(lines.iter().skip(i + n));
            out.join("\n")
        }
        Mutation::Value { at, value } => {
            let lines: Vec<&str> = src.lines().collect();
            let kv: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains(" = "))
                .collect();
            if kv.is_empty() {
                return src.to_string();
            }
            let i = kv[at % kv.len()];
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            let key = lines[i].split(" = ").next().unwrap_or_default();
            out[i] = format!("{key} = {value}");
            out.join("\n")
        }
    }
}

fn check_error(e: &ScenarioError) {
    let shown = e.to_string();
    match e {
        ScenarioError::Syntax { line, .. }
        | ScenarioError::Invalid {
            line: Some(line), ..
        } => {
            assert!(shown.starts_with(&format!("{ORIGIN}:{line}")), "{shown}");
        }
        other => panic!("error without a line: {other:?} ({shown})"),
    }
}

#[test]
fn the_rich_scenario_is_valid() {
    let l = parse(RICH, ORIGIN).unwrap();
    assert_eq!(l.scenario.robots.len(), 8);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_scenarios_never_panic_and_errors_name_file_and_line(
        muts in prop::collection::vec(mutation(), 1..4)
    ) {
        let src = muts.iter().fold(RICH.to_string(), |s, m| apply(&s, m));
        match parse(&src, ORIGIN) {
            Ok(l) => {
                for r in &l.scenario.robots {
                    let _ = l.error_at(&format!("robot.{}.planner", r.name), "x");
                    let _ = l.error_at(&format!("robot.{}.params.alpha", r.name), "x");
                }
                let _ = l.error_at("world.dt", "x");
                let _ = l.error_at("", "x");
            }
            Err(e) => check_error(&e),
        }
    }

    #[test]
    fn random_overrides_never_panic_and_errors_name_the_override_or_a_line(
        keys in prop::collection::vec(prop::sample::select(&[
            "planner", "world.dt", "world.arena.min", "world.nope", "defaults.radius",
            "defaults.params.k", "robot.r0.radius", "robot.r1.start", "robot.*.max_speed",
            "robot.g03.goal", "robot.zz.mass", "obstacle.o1.radius", "obstacle.o3.motion.target",
            "wall.0.segment", "generate.count", "generate.kind", "name", "robot.r0.params",
            "robot.*.params.alpha.beta", "x", "robot.*", "",
        ][..]), 1..4),
        values in prop::collection::vec(prop::sample::select(VALUES), 4),
    ) {
        let pairs: Vec<(String, String)> =
            keys.iter().zip(&values).map(|(k, v)| (k.to_string(), v.to_string())).collect();
        match parse_with_overrides(RICH, ORIGIN, &pairs) {
            Ok(l) => {
                for r in &l.scenario.robots {
                    let _ = l.error_at(&format!("robot.{}.max_speed", r.name), "x");
                }
            }
            Err(ScenarioError::Override { key, .. }) => {
                prop_assert!(pairs.iter().any(|(k, _)| k == &key));
            }
            Err(e) => check_error(&e),
        }
    }
}
