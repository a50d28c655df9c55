//! `encounters.csv`: every time two bodies came within `[output]
//! encounter_gap` of each other, one row each, written by the world's
//! recording thread as each encounter ends (those still going on at the
//! end last). Columns: [`ENCOUNTERS_HEADER`]; `min_gap` and `min_ttc` with
//! six decimals, `min_ttc` empty when never finite.

pub use crate::metrics::{ENCOUNTERS_HEADER, Encounter};

use crate::RowsError;
use crate::csv::{Columns, CsvError, numbered_lines};
use crate::stream::{Cut, read_whole_rows};
use std::path::Path;

/// encounters.csv's rows for `encounters`, each ending in a newline.
pub fn rows(encounters: &[Encounter]) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    for e in encounters {
        let ttc = e.min_ttc.map(|t| format!("{t:.6}")).unwrap_or_default();
        // Writing into a String cannot fail.
        let _ = writeln!(
            out,
            "{},{},{},{},{:.6},{},{},{},{}",
            e.a, e.b, e.start_tick, e.end_tick, e.min_gap, ttc, e.kind, e.gave_way, e.b_kind
        );
    }
    out
}

/// Parses encounters.csv's text (whole rows: see [`read_encounters`] for a
/// file that may be cut); the first bad line is the error. A file without
/// the `b_kind` column (written before it) reads with `b_kind` empty.
pub fn parse_encounters(text: &str) -> Result<Vec<Encounter>, CsvError> {
    const COLUMNS: [&str; 9] = [
        "a",
        "b",
        "start_tick",
        "end_tick",
        "min_gap",
        "min_ttc",
        "kind",
        "gave_way",
        "b_kind",
    ];
    let mut lines = numbered_lines(text);
    let header = lines.next().map(|(_, l)| l);
    let with_kind = header.is_some_and(|h| h.split(',').any(|c| c.trim() == "b_kind"));
    let wanted = if with_kind {
        &COLUMNS[..]
    } else {
        &COLUMNS[..8]
    };
    let csv = Columns::new(header, wanted)?;
    lines
        .map(|(n, line)| {
            let f = csv.fields(n, line)?;
            let bad = |reason: String| CsvError { line: n, reason };
            let tick = |cell: &str, what: &str| {
                cell.parse::<u64>()
                    .map_err(|_| bad(format!("column `{what}`: `{cell}` is not a tick number")))
            };
            Ok(Encounter {
                a: f[0].to_string(),
                b: f[1].to_string(),
                start_tick: tick(f[2], "start_tick")?,
                end_tick: tick(f[3], "end_tick")?,
                min_gap: csv.number(n, "min_gap", f[4])?,
                min_ttc: if f[5].is_empty() {
                    None
                } else {
                    Some(csv.number(n, "min_ttc", f[5])?)
                },
                kind: f[6].to_string(),
                gave_way: f[7].to_string(),
                b_kind: f.get(8).map(|k| k.to_string()).unwrap_or_default(),
            })
        })
        .collect()
}

/// Reads `dir/encounters.csv`: its rows (none if the file is absent) and
/// the cut, if its last row is torn.
pub fn read_encounters(dir: &Path) -> Result<(Vec<Encounter>, Option<Cut>), RowsError> {
    let path = dir.join(crate::ENCOUNTERS_FILE);
    let Some((text, cut)) = read_whole_rows(&path).map_err(|source| RowsError::Io {
        path: path.clone(),
        source,
    })?
    else {
        return Ok((Vec::new(), None));
    };
    let rows = parse_encounters(&text).map_err(|e| RowsError::Row {
        path,
        line: e.line,
        reason: e.reason,
    })?;
    Ok((rows, cut))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one() -> Encounter {
        Encounter {
            a: "r0".into(),
            b: "r1".into(),
            start_tick: 3,
            end_tick: 9,
            min_gap: -0.25,
            min_ttc: None,
            kind: "head-on".into(),
            gave_way: "both".into(),
            b_kind: "robot".into(),
        }
    }

    #[test]
    fn rows_written_are_the_rows_read() {
        let mut e = vec![one(), one()];
        e[1].min_ttc = Some(1.5);
        let text = format!("{ENCOUNTERS_HEADER}\n{}", rows(&e));
        assert_eq!(parse_encounters(&text).expect("rows"), e);
    }

    #[test]
    fn a_file_without_the_b_kind_column_reads_with_it_empty() {
        let text = "a,b,start_tick,end_tick,min_gap,min_ttc,kind,gave_way\n\
                    r0,r1,3,9,-0.250000,,head-on,both\n";
        let got = parse_encounters(text).expect("rows");
        assert_eq!(
            got,
            vec![Encounter {
                b_kind: String::new(),
                ..one()
            }]
        );
    }

    #[test]
    fn a_bad_middle_row_is_an_error_at_its_line_and_a_torn_last_row_a_cut() {
        let dir = std::env::temp_dir().join(format!("mrsim-enc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let good = rows(&[one()]);
        let path = dir.join(crate::ENCOUNTERS_FILE);
        std::fs::write(
            &path,
            format!("{ENCOUNTERS_HEADER}\n{good}r0,r1,x,9,0,,head-on,a,robot\n{good}"),
        )
        .expect("write");
        let e = read_encounters(&dir).expect_err("bad row").to_string();
        assert!(
            e.ends_with("encounters.csv:3: column `start_tick`: `x` is not a tick number"),
            "{e}"
        );
        std::fs::write(
            &path,
            format!("{ENCOUNTERS_HEADER}\n{good}{good}r0,r1,3,9,0.1"),
        )
        .expect("write");
        let (got, cut) = read_encounters(&dir).expect("read");
        assert_eq!(got.len(), 2);
        assert_eq!(cut.expect("cut").line, 4);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
