//! `mrsim sweep`'s CSV files: sweep.csv (one row per run: the swept
//! values, `mode`, `seed`, the metrics, `run`), summary.csv (per setting:
//! `runs` and each metric's `_mean` and `_ci95`) and allowable.csv (per
//! setting of the other keys: `seeds`, `KEY_allowable_mean`,
//! `KEY_allowable_ci95`). The sweep gives the cells, this module writes
//! them: a cell holding a comma, a quote or a newline is quoted (RFC 4180),
//! an absent number is an empty cell.

use crate::FileError;
use std::path::Path;

/// `s` as a CSV cell.
pub fn cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number's cell: Rust's shortest round-trip form, empty for `None`.
pub fn number(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// The CSV text of `header` and `rows` (cells unquoted; quoted here).
pub fn to_csv(header: &[String], rows: &[Vec<String>]) -> String {
    let mut out = String::new();
    for row in std::iter::once(header).chain(rows.iter().map(Vec::as_slice)) {
        let cells: Vec<String> = row.iter().map(|c| cell(c)).collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// Writes `dir/name` ([`crate::SWEEP_FILE`], [`crate::SUMMARY_FILE`],
/// [`crate::ALLOWABLE_FILE`]) from `header` and `rows`.
pub fn write_table(
    dir: &Path,
    name: &str,
    header: &[String],
    rows: &[Vec<String>],
) -> Result<(), FileError> {
    let path = dir.join(name);
    std::fs::write(&path, to_csv(header, rows)).map_err(|source| FileError::Io { path, source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_with_commas_or_quotes_are_quoted_and_absent_numbers_empty() {
        let header = vec!["robot.r0.max_speed".to_string(), "run".into()];
        let rows = vec![
            vec!["1.5".into(), "a,b".into()],
            vec![number(None), "say \"x\"".into()],
        ];
        assert_eq!(
            to_csv(&header, &rows),
            "robot.r0.max_speed,run\n1.5,\"a,b\"\n,\"say \"\"x\"\"\"\n"
        );
        assert_eq!(number(Some(0.1)), "0.1");
    }
}
