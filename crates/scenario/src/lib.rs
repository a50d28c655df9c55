//! mrsim scenario files: load a TOML scenario (the format docs/scenarios.md documents),
//! apply command-line overrides, resolve defaults and `[generate]`, and
//! check everything, with errors that name the file, the line and the reason.
//!
//! ```
//! let loaded = mrsim_scenario::parse(
//!     "[[robot]]\nname = \"r0\"\nstart = [0, 0]\ngoal = [1, 0]\n",
//!     "inline.toml",
//! )
//! .unwrap();
//! assert_eq!(loaded.scenario.robots[0].planner, "homing");
//! // The launcher finds the planner unknown and points at the robot:
//! let err = loaded.error_at("robot.r0.planner", "unknown planner");
//! assert_eq!(err.line(), Some(1));
//! ```
//!
//! Precedence, lowest first: built-in defaults, `[defaults]`, `[generate]`'s
//! own keys (for generated robots), the robot's own keys, overrides (in the
//! order given). `params` are merged key by key through the same layers.
//!
//! `[output]` says what the world writes of the trajectory
//! ([`OutputConfig`]): `trajectory = "csv" | "parquet" | "none"` (default
//! csv) and `every = K` (record ticks 0, K, 2K, ... and the last; default
//! 1, whole number >= 1).
#![warn(missing_docs)]

mod checks;
pub mod cores;
pub mod crowdnav;
mod error;
mod generate;
pub mod map;
mod overrides;
mod raw;
mod resolve;
pub mod rng;
pub mod schedulability;
pub mod timing;
mod types;

pub use error::ScenarioError;
pub use types::*;

use error::{Fail, Spans};
use overrides::RobotPatch;
use serde::Deserialize;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A loaded scenario, with the text it came from so that later errors (an
/// unknown planner, a bad parameter) can still point at a line.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The resolved, validated scenario.
    pub scenario: Scenario,
    source: String,
    origin: String,
    overrides: Vec<(String, String)>,
    file_robots: usize,
}

/// Reads and loads a scenario file.
pub fn load(path: &Path) -> Result<Loaded, ScenarioError> {
    load_with_overrides(path, &[])
}

/// Reads and loads a scenario file, with overrides (see
/// [`parse_with_overrides`]).
pub fn load_with_overrides(
    path: &Path,
    overrides: &[(String, String)],
) -> Result<Loaded, ScenarioError> {
    let src = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_with_overrides(&src, &path.display().to_string(), overrides)
}

/// Loads a scenario from text; `origin` names it in errors (a path).
pub fn parse(src: &str, origin: &str) -> Result<Loaded, ScenarioError> {
    parse_with_overrides(src, origin, &[])
}

/// Loads a scenario from text with overrides applied to the document before
/// it is resolved. Each override is a dotted KEY and a VALUE as TOML text:
///
/// - `name`, `description`, `length_unit`;
/// - `world.KEY` (e.g. `world.dt`), `defaults.KEY` (e.g.
///   `defaults.field_of_view_deg`, `defaults.params.horizon`),
///   `generate.KEY`;
/// - `robot.NAME.KEY...` (e.g. `robot.r0.params.horizon`; generated robots
///   too, e.g. `robot.g03.max_speed`), `robot.*.KEY...` (every robot,
///   generated ones included);
/// - `planner`: short for `robot.*.planner`;
/// - `obstacle.NAME.KEY...`, `obstacle.*.KEY...`, `wall.INDEX.KEY...`.
///
/// A VALUE that is not TOML but a bare word (`orca`) is taken as a string.
/// Unknown targets, and values the scenario refuses, are
/// [`ScenarioError::Override`] errors naming the override.
pub fn parse_with_overrides(
    src: &str,
    origin: &str,
    overrides: &[(String, String)],
) -> Result<Loaded, ScenarioError> {
    let spans = Spans {
        source: src,
        origin,
        overrides,
    };
    let doc = DeTable::parse(src).map_err(|e| syntax(&e, &spans))?;
    let whole = doc.span();
    let mut table = doc.into_inner();
    let patches = overrides::apply(&mut table, &spans, overrides)?;
    let raw = raw::RawDoc::deserialize(toml::de::Deserializer::from(Spanned::new(whole, table)))
        .map_err(|e| {
            let mut fail = checks::de_fail(e, "");
            if fail
                .span
                .as_ref()
                .is_none_or(|s| spans.override_of(s).is_none())
            {
                fail.what = describe_span(src, fail.span.as_ref());
            }
            if fail.reason.contains("untagged enum ParamValue") {
                fail.reason =
                    "a parameter must be a number, a string, a boolean, a list of numbers \
                           or a list of points [[x, y], ...]"
                        .into();
            }
            if fail.reason.contains("untagged enum RawPriority") {
                fail.reason =
                    "timing.priority must be a whole number 1..99 or \"rate-monotonic\"".into();
            }
            spans.error(fail)
        })?;
    let resolved = resolve::resolve(raw, &patches, &spans).map_err(|f| spans.error(f))?;
    Ok(Loaded {
        scenario: resolved.scenario,
        source: src.to_string(),
        origin: origin.to_string(),
        overrides: overrides.to_vec(),
        file_robots: resolved.file_robots,
    })
}

/// The built-in demo (`scenarios/demo.toml`): 8 robots swapping places
/// across a circle.
pub fn demo() -> Loaded {
    parse(
        include_str!("../../../scenarios/demo.toml"),
        "scenarios/demo.toml",
    )
    .expect("the built-in demo scenario is valid (checked by the tests)")
}

fn syntax(e: &toml::de::Error, spans: &Spans) -> ScenarioError {
    let (line, column) = spans.line_col(e.span().map_or(0, |s| s.start));
    ScenarioError::Syntax {
        origin: spans.origin.to_string(),
        line,
        column,
        message: e.message().trim().to_string(),
    }
}

/// Names the robot, obstacle or table a byte offset falls in, for errors
/// that come from the TOML deserializer (an unknown key, a wrong type): the
/// last table header (or top-level key) that starts at or before it.
fn describe_span(src: &str, span: Option<&Range<usize>>) -> String {
    let (Some(span), Ok(doc)) = (span, DeTable::parse(src)) else {
        return String::new();
    };
    let mut best: Option<(usize, String)> = None;
    let mut consider = |at: usize, label: String| {
        if at <= span.start && best.as_ref().is_none_or(|(b, _)| at >= *b) {
            best = Some((at, label));
        }
    };
    for (key, value) in doc.get_ref() {
        let k = key.get_ref().as_ref();
        match value.get_ref() {
            DeValue::Array(items)
                if matches!(k, "robot" | "obstacle" | "person" | "crowd" | "wall") =>
            {
                for (i, item) in items.iter().enumerate() {
                    let label = match item
                        .get_ref()
                        .get("name")
                        .and_then(|n| n.get_ref().as_str())
                    {
                        Some(n) if k != "wall" && k != "crowd" => format!("{k} `{n}`"),
                        _ => format!("{k} #{}", i + 1),
                    };
                    consider(item.span().start, label);
                }
            }
            DeValue::Table(_) => consider(value.span().start.min(key.span().start), k.to_string()),
            _ => consider(key.span().start, String::new()),
        }
    }
    best.map(|(_, l)| l).unwrap_or_default()
}

impl Loaded {
    /// The file (or name) the scenario came from.
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// The scenario's text.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Is this robot made by `[generate]` (not written in the file)?
    pub fn is_generated(&self, robot: &str) -> bool {
        self.scenario.robots[self.file_robots.min(self.scenario.robots.len())..]
            .iter()
            .any(|r| r.name == robot)
    }

    /// An error about a key of the resolved scenario, pointing at the line it
    /// came from: e.g. `error_at("robot.r1.planner", "unknown planner `x`")`
    /// or `error_at("robot.r1.params.alpha", "...")`.
    ///
    /// A robot key the robot does not set points at `[defaults]` if that
    /// sets it, else at the robot's table. A generated robot points at its
    /// key in `[generate]` (`radius` is `robot_radius` there), else
    /// `[defaults]`, else the `[generate]` table. A value that came from an
    /// override gives [`ScenarioError::Override`] naming it.
    pub fn error_at(&self, key_path: &str, reason: impl Into<String>) -> ScenarioError {
        let spans = Spans {
            source: &self.source,
            origin: &self.origin,
            overrides: &self.overrides,
        };
        let segs: Vec<&str> = key_path.split('.').collect();
        let span = DeTable::parse(&self.source).ok().and_then(|doc| {
            let mut doc = doc.into_inner();
            let patches = overrides::apply(&mut doc, &spans, &self.overrides).ok()?;
            self.locate(&doc, &patches, &segs, &spans)
        });
        let what = match segs.as_slice() {
            [kind @ ("robot" | "obstacle"), name] => format!("{kind} `{name}`"),
            [kind @ ("robot" | "obstacle"), name, rest @ ..] => {
                format!("{kind} `{name}` {}", rest.join("."))
            }
            _ => key_path.to_string(),
        };
        spans.error(Fail::new(span, what, reason))
    }

    fn locate(
        &self,
        doc: &DeTable,
        patches: &[RobotPatch],
        segs: &[&str],
        spans: &Spans,
    ) -> Option<Range<usize>> {
        let defaults = table(doc.get("defaults"));
        match segs {
            ["robot", name, rest @ ..] => {
                if let Some(robot) = named(doc, "robot", name) {
                    let own = table(Some(robot))?;
                    if let Some(s) = [Some(own), defaults]
                        .into_iter()
                        .flatten()
                        .find_map(|t| full(t, rest))
                    {
                        return Some(s);
                    }
                    return Some(deepest(own, rest).unwrap_or(robot.span()));
                }
                if !self.is_generated(name) {
                    return None;
                }
                let generate = doc.get("generate")?;
                let mut patch = DeTable::new();
                for p in patches.iter().filter(|p| p.selects(name)) {
                    let _ = overrides::set_path(
                        &mut patch,
                        &p.rest,
                        p.value.clone(),
                        &spans.sentinel(p.index),
                    );
                }
                let mapped: Vec<&str> = match rest {
                    ["radius"] => vec!["robot_radius"],
                    ["planner" | "params", ..] => rest.to_vec(),
                    _ => vec!["-"],
                };
                let found = full(&patch, rest)
                    .or_else(|| table(Some(generate)).and_then(|g| full(g, &mapped)))
                    .or_else(|| defaults.and_then(|d| full(d, rest)));
                Some(found.unwrap_or(generate.span()))
            }
            ["obstacle", name, rest @ ..] => {
                let o = named(doc, "obstacle", name)?;
                Some(
                    table(Some(o))
                        .and_then(|t| deepest(t, rest))
                        .unwrap_or(o.span()),
                )
            }
            _ => deepest(doc, segs),
        }
    }
}

fn table<'a, 'i>(v: Option<&'a Spanned<DeValue<'i>>>) -> Option<&'a DeTable<'i>> {
    v.and_then(|v| v.get_ref().as_table())
}

/// The element of array `array` whose `name` is `name`.
fn named<'a, 'i>(
    doc: &'a DeTable<'i>,
    array: &str,
    name: &str,
) -> Option<&'a Spanned<DeValue<'i>>> {
    doc.get(array)?
        .get_ref()
        .as_array()?
        .iter()
        .find(|t| t.get_ref().get("name").and_then(|n| n.get_ref().as_str()) == Some(name))
}

/// The span of `keys` in `t` if the whole path is there.
fn full(t: &DeTable, keys: &[&str]) -> Option<Range<usize>> {
    let (first, rest) = keys.split_first()?;
    let mut v = t.get(*first)?;
    for k in rest {
        v = v.get_ref().as_table()?.get(*k)?;
    }
    Some(v.span())
}

/// The span of the deepest key of `keys` found in `t`.
fn deepest(t: &DeTable, keys: &[&str]) -> Option<Range<usize>> {
    let (first, rest) = keys.split_first()?;
    let mut v = t.get(*first)?;
    for k in rest {
        match v.get_ref().as_table().and_then(|t| t.get(*k)) {
            Some(next) => v = next,
            None => break,
        }
    }
    Some(v.span())
}
