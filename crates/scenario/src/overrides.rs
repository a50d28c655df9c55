//! Command-line overrides `KEY=VALUE`, applied to the parsed document before
//! it is resolved.
//!
//! Key forms: `name`, `description`, `length_unit`, `planner` (every robot's
//! planner, generated ones included), `world.KEY`, `defaults.KEY...`,
//! `generate.KEY...`, `robot.NAME.KEY...` (a robot by name, generated ones
//! included), `robot.*.KEY...` (every robot), `obstacle.NAME.KEY...`,
//! `obstacle.*.KEY...`, `person.NAME.KEY...`, `person.*.KEY...` (the
//! `[[person]]` tables; a crowd's people are set through their crowd),
//! `wall.INDEX.KEY...` and `crowd.INDEX.KEY...` (0-based, file order),
//! `map.KEY`, `output.KEY`.
//!
//! The VALUE is TOML text (`0.2`, `"orca"`, `[1, 2]`, `{ a = 1 }`); a bare
//! word that is not TOML (`orca`) is taken as a string, so `planner=orca`
//! works from a shell. Every value an override puts in the document carries
//! a sentinel span (see `error::Spans`), so an error about it names the
//! override rather than a line of the file.

use crate::error::{ScenarioError, Spans};
use std::borrow::Cow;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeArray, DeTable, DeValue};

/// Which robots a robot override selects.
#[derive(Debug, Clone)]
pub(crate) enum Selector {
    /// `robot.*`, or `planner`.
    All,
    /// `robot.NAME`.
    Name(String),
}

/// A robot override kept for the generated robots (which are not in the
/// document): applied, in command-line order, to each one it selects.
#[derive(Debug, Clone)]
pub(crate) struct RobotPatch<'i> {
    /// Index of the override.
    pub index: usize,
    /// Which robots.
    pub selector: Selector,
    /// The key inside the robot, e.g. `["params", "horizon"]`.
    pub rest: Vec<&'i str>,
    /// The value, spans already set to the sentinel.
    pub value: Spanned<DeValue<'i>>,
}

impl RobotPatch<'_> {
    /// Does this patch apply to a robot named `name`?
    pub(crate) fn selects(&self, name: &str) -> bool {
        match &self.selector {
            Selector::All => true,
            Selector::Name(n) => n == name,
        }
    }
}

const TARGETS: &str = "name, description, length_unit, planner, world.KEY, defaults.KEY, \
     robot.NAME.KEY, robot.*.KEY, obstacle.NAME.KEY, obstacle.*.KEY, person.NAME.KEY, person.*.KEY, wall.INDEX.KEY, \
     crowd.INDEX.KEY, generate.KEY, map.KEY, output.KEY";

/// Applies every override to `doc`; returns those that (also) select robots,
/// for the generated robots.
pub(crate) fn apply<'i>(
    doc: &mut DeTable<'i>,
    spans: &Spans<'_>,
    overrides: &'i [(String, String)],
) -> Result<Vec<RobotPatch<'i>>, ScenarioError> {
    let mut patches = Vec::new();
    for (index, (key, text)) in overrides.iter().enumerate() {
        let fail = |reason: String| ScenarioError::Override {
            key: key.clone(),
            reason,
        };
        let span = spans.sentinel(index);
        let segs: Vec<&'i str> = key.split('.').map(str::trim).collect();
        if segs.iter().any(|s| s.is_empty()) {
            return Err(fail("empty part in the key".into()));
        }
        let value = restamp(parse_value(text).map_err(&fail)?, &span);
        match (segs[0], segs.len()) {
            ("planner", 1) => {
                robots(doc, Selector::All, &["planner"], &value, &span).map_err(&fail)?;
                patches.push(RobotPatch {
                    index,
                    selector: Selector::All,
                    rest: vec!["planner"],
                    value,
                });
            }
            ("name" | "description" | "length_unit", 1)
            | ("world" | "defaults" | "generate" | "map" | "output", 2..) => {
                set_path(doc, &segs, value, &span).map_err(&fail)?;
            }
            ("robot", 3..) => {
                let selector = match segs[1] {
                    "*" => Selector::All,
                    n => Selector::Name(n.to_string()),
                };
                let hits =
                    robots(doc, selector.clone(), &segs[2..], &value, &span).map_err(&fail)?;
                // A robot not in the file may be a generated one: kept, and
                // refused later if no generated robot has that name.
                if hits == 0 || matches!(selector, Selector::All) {
                    patches.push(RobotPatch {
                        index,
                        selector,
                        rest: segs[2..].to_vec(),
                        value,
                    });
                }
            }
            ("obstacle", 3..) => {
                let hits = named_elements(doc, "obstacle", segs[1], &segs[2..], &value, &span)
                    .map_err(&fail)?;
                if hits == 0 {
                    return Err(fail(format!("no obstacle named `{}`", segs[1])));
                }
            }
            ("person", 3..) => {
                let hits = named_elements(doc, "person", segs[1], &segs[2..], &value, &span)
                    .map_err(&fail)?;
                if hits == 0 {
                    return Err(fail(format!("no person named `{}`", segs[1])));
                }
            }
            (array @ ("wall" | "crowd"), 3..) => {
                let i: usize = segs[1].parse().map_err(|_| {
                    fail(format!("`{}` is not a {array} index (0, 1, ...)", segs[1]))
                })?;
                let item = array_mut(doc, array)
                    .and_then(|a| a.get_mut(i))
                    .ok_or_else(|| {
                        fail(format!("there is no {array} {i} ({array}s count from 0)"))
                    })?;
                match item.get_mut() {
                    DeValue::Table(t) => set_path(t, &segs[2..], value, &span).map_err(&fail)?,
                    _ => return Err(fail(format!("`{array}` is not an array of tables"))),
                }
            }
            _ => {
                return Err(fail(format!(
                    "unknown override target; expected one of {TARGETS}"
                )));
            }
        }
    }
    Ok(patches)
}

/// Sets `rest` in every robot the selector picks in the document; returns
/// how many it picked.
fn robots<'i>(
    doc: &mut DeTable<'i>,
    selector: Selector,
    rest: &[&'i str],
    value: &Spanned<DeValue<'i>>,
    span: &Range<usize>,
) -> Result<usize, String> {
    let name = match &selector {
        Selector::All => "*",
        Selector::Name(n) => n.as_str(),
    };
    named_elements(doc, "robot", name, rest, value, span)
}

/// Sets `rest` in every table of the array `array` whose `name` is `name`
/// (`*`: all of them).
fn named_elements<'i>(
    doc: &mut DeTable<'i>,
    array: &str,
    name: &str,
    rest: &[&'i str],
    value: &Spanned<DeValue<'i>>,
    span: &Range<usize>,
) -> Result<usize, String> {
    let Some(items) = array_mut(doc, array) else {
        return Ok(0);
    };
    let mut hits = 0;
    for item in items.iter_mut() {
        if let DeValue::Table(t) = item.get_mut() {
            let picked =
                name == "*" || t.get("name").and_then(|n| n.get_ref().as_str()) == Some(name);
            if picked {
                set_path(t, rest, value.clone(), span)?;
                hits += 1;
            }
        }
    }
    Ok(hits)
}

fn array_mut<'a, 'i>(doc: &'a mut DeTable<'i>, key: &str) -> Option<&'a mut DeArray<'i>> {
    match doc.get_mut(key)?.get_mut() {
        DeValue::Array(a) => Some(a),
        _ => None,
    }
}

/// Sets `keys` (a dotted path) in `table` to `value`, making the tables on
/// the way if they are missing.
pub(crate) fn set_path<'i>(
    table: &mut DeTable<'i>,
    keys: &[&'i str],
    value: Spanned<DeValue<'i>>,
    span: &Range<usize>,
) -> Result<(), String> {
    let Some((last, init)) = keys.split_last() else {
        return Err("the key names no field".into());
    };
    let mut t = table;
    for k in init {
        if !t.contains_key(*k) {
            t.insert(
                Spanned::new(span.clone(), Cow::Borrowed(*k)),
                Spanned::new(span.clone(), DeValue::Table(DeTable::new())),
            );
        }
        match t.get_mut(*k).map(|v| v.get_mut()) {
            Some(DeValue::Table(inner)) => t = inner,
            Some(other) => {
                return Err(format!(
                    "`{k}` is {} in the file, not a table",
                    other.type_str()
                ));
            }
            None => return Err(format!("cannot set `{k}`")),
        }
    }
    // Replace the key too, so that an error about it names the override.
    t.remove(*last);
    t.insert(Spanned::new(span.clone(), Cow::Borrowed(*last)), value);
    Ok(())
}

/// Parses an override's VALUE as TOML; a bare word is a string.
fn parse_value(text: &str) -> Result<Spanned<DeValue<'_>>, String> {
    match DeValue::parse(text.trim()) {
        Ok(v) => Ok(v),
        Err(e) => {
            let t = text.trim();
            let bare = !t.is_empty()
                && t.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if bare {
                Ok(Spanned::new(0..0, DeValue::String(Cow::Borrowed(t))))
            } else {
                Err(format!("`{t}` is not a TOML value: {}", e.message()))
            }
        }
    }
}

/// Gives a value and everything inside it the span `span`.
pub(crate) fn restamp<'i>(v: Spanned<DeValue<'i>>, span: &Range<usize>) -> Spanned<DeValue<'i>> {
    let inner = match v.into_inner() {
        DeValue::Array(a) => {
            let mut out = DeArray::new();
            for item in a {
                out.push(restamp(item, span));
            }
            DeValue::Array(out)
        }
        DeValue::Table(t) => {
            let mut out = DeTable::new();
            for (k, item) in t {
                out.insert(
                    Spanned::new(span.clone(), k.into_inner()),
                    restamp(item, span),
                );
            }
            DeValue::Table(out)
        }
        other => other,
    };
    Spanned::new(span.clone(), inner)
}
