//! The swept keys: the `--set KEY=V1,V2,...` options parsed into axes,
//! their combinations, each combination's folder label and the overrides
//! of one run.

use crate::error::Invalid;

/// Splits `text` at commas outside brackets, braces and quotes.
pub(super) fn split_values(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut quote: Option<char> = None;
    let mut cur = String::new();
    for c in text.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// The varied keys and their values, parsed from the `--set` options.
pub(super) fn parse_axes(set: &[String]) -> Result<Vec<(String, Vec<String>)>, Invalid> {
    let mut axes: Vec<(String, Vec<String>)> = Vec::new();
    for s in set {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| Invalid(format!("--set {s}: expected KEY=V1,V2,...")))?;
        let k = k.trim().to_string();
        if k == "world.seed" {
            return Err(Invalid(format!(
                "--set {s}: the seed is varied by --seeds (runs use seeds 1..=N)"
            )));
        }
        if axes.iter().any(|(a, _)| *a == k) {
            return Err(Invalid(format!("--set {s}: `{k}` is set twice")));
        }
        let values = split_values(v);
        if let Some(i) = values.iter().position(|v| v.is_empty()) {
            return Err(Invalid(format!(
                "--set {s}: value {} of `{k}` is empty",
                i + 1
            )));
        }
        axes.push((k, values));
    }
    Ok(axes)
}

/// Every combination of the axes' values, first axis slowest.
pub(super) fn combinations(axes: &[(String, Vec<String>)]) -> Vec<Vec<String>> {
    let mut out = vec![Vec::new()];
    for (_, values) in axes {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                values.iter().map(move |v| {
                    let mut c = prefix.clone();
                    c.push(v.clone());
                    c
                })
            })
            .collect();
    }
    out
}

/// A folder-name-safe label of a combination: its index (which makes it
/// unique), then `key=value` pairs (last part of each key, values cleaned
/// and cut to 24 characters).
pub(super) fn label(index: usize, axes: &[(String, Vec<String>)], combo: &[String]) -> String {
    let clean = |s: &str| {
        let mut out = String::new();
        for c in s.chars() {
            let c = if c.is_ascii_alphanumeric() || matches!(c, '.' | '-') {
                c
            } else {
                '_'
            };
            if !(c == '_' && (out.is_empty() || out.ends_with('_'))) {
                out.push(c);
            }
        }
        out.truncate(24);
        out.trim_end_matches('_').to_string()
    };
    let mut s = format!("{index:03}");
    for ((k, _), v) in axes.iter().zip(combo) {
        let short = k.rsplit('.').next().unwrap_or(k);
        s.push('-');
        s.push_str(&clean(short));
        s.push('=');
        s.push_str(&clean(v));
    }
    s
}

/// The index of swept key `key`, if its values are all numbers.
pub(super) fn numeric_axis(axes: &[(String, Vec<String>)], key: &str) -> Result<usize, Invalid> {
    match axes.iter().position(|(k, _)| k == key) {
        None => Err(Invalid(format!(
            "--x {key}: not a swept key (give it --set {key}=V1,V2,...)"
        ))),
        Some(i) if axes[i].1.iter().any(|v| v.parse::<f64>().is_err()) => Err(Invalid(format!(
            "--x {key}: its values must be numbers to be an axis"
        ))),
        Some(i) => Ok(i),
    }
}

/// The `--set` overrides of one run: the combination's values and the seed.
pub fn sets(axes: &[(String, Vec<String>)], combo: &[String], seed: u64) -> Vec<String> {
    let mut s: Vec<String> = axes
        .iter()
        .zip(combo)
        .map(|((k, _), v)| format!("{k}={v}"))
        .collect();
    s.push(format!("world.seed={seed}"));
    s
}
