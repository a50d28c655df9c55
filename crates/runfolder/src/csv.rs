//! Reading the folder's CSV files: `trajectory.csv` (its rows, as
//! [`TrajectoryRow`]s like the Parquet file's) and the reader beneath it,
//! which finds the columns by the header's names and says which line is
//! wrong and why (also for `diagnostics.csv`).
//!
//! Lines are numbered from 1, the header being line 1; blank lines are
//! skipped but counted, and a trailing `\r` is dropped.

use crate::trajectory::{COLUMNS, THETA, TrajectoryRow};

/// A malformed line of a CSV file: the file's reader adds the path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct CsvError {
    /// 1-based line number (the header is line 1).
    pub line: usize,
    /// What is wrong with it.
    pub reason: String,
}

/// A CSV file's header: where the wanted columns are and how many cells a
/// row must have.
#[derive(Debug, Clone)]
pub struct Columns {
    columns: Vec<usize>,
    width: usize,
}

impl Columns {
    /// Reads the header (line 1; `None` for an empty file) and finds
    /// `wanted` in it.
    pub fn new(header: Option<&str>, wanted: &[&str]) -> Result<Self, CsvError> {
        let header = header.ok_or_else(|| error(1, "empty file: no header".into()))?;
        let names = header_names(header);
        let mut columns = Vec::with_capacity(wanted.len());
        for w in wanted {
            let i = names.iter().position(|n| n == w).ok_or_else(|| {
                error(
                    1,
                    format!("header has no `{w}` column (expected {})", wanted.join(",")),
                )
            })?;
            columns.push(i);
        }
        Ok(Columns {
            columns,
            width: names.len(),
        })
    }

    /// Splits a data row into the wanted fields, in `wanted` order.
    pub fn fields<'l>(&self, line_no: usize, line: &'l str) -> Result<Vec<&'l str>, CsvError> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != self.width {
            return Err(error(
                line_no,
                format!("{} fields, the header has {}", cells.len(), self.width),
            ));
        }
        Ok(self.columns.iter().map(|&i| cells[i]).collect())
    }

    /// The number in `cell` of column `column`.
    pub fn number(&self, line_no: usize, column: &str, cell: &str) -> Result<f64, CsvError> {
        cell.parse::<f64>().map_err(|_| {
            error(
                line_no,
                format!("column `{column}`: `{cell}` is not a number"),
            )
        })
    }

    /// The tick number in `cell` (column `tick`).
    pub fn tick(&self, line_no: usize, cell: &str) -> Result<u64, CsvError> {
        cell.parse::<u64>().map_err(|_| {
            error(
                line_no,
                format!("column `tick`: `{cell}` is not a tick number"),
            )
        })
    }
}

/// The header's column names, trimmed.
fn header_names(header: &str) -> Vec<&str> {
    header
        .trim_end_matches('\r')
        .split(',')
        .map(str::trim)
        .collect()
}

fn error(line: usize, reason: String) -> CsvError {
    CsvError { line, reason }
}

/// Non-blank lines with their 1-based line numbers, `\r` removed.
pub fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty())
}

/// The rows of `trajectory.csv`'s text, each with its line number, in file
/// order; `theta` is read when the header has that column. The header's
/// error comes first; each row's in the iteration, so that a reader can
/// stop at the first bad line. Whether `kind` is `robot` or `obstacle` is
/// left to the reader, as for the Parquet file.
pub fn trajectory_rows(
    text: &str,
) -> Result<impl Iterator<Item = Result<(usize, TrajectoryRow<'_>), CsvError>>, CsvError> {
    let mut lines = numbered_lines(text);
    let header = lines.next().map(|(_, l)| l);
    let mut csv = Columns::new(header, &COLUMNS)?;
    let theta = header.is_some_and(|h| header_names(h).contains(&THETA));
    if theta {
        let mut wanted = COLUMNS.to_vec();
        wanted.push(THETA);
        csv = Columns::new(header, &wanted)?;
    }
    Ok(lines.map(move |(line_no, line)| {
        let f = csv.fields(line_no, line)?;
        let tick = csv.tick(line_no, f[0])?;
        let time = csv.number(line_no, "time", f[1])?;
        let mut v = [0.0; 4];
        for (k, col) in ["x", "y", "vx", "vy"].iter().enumerate() {
            v[k] = csv.number(line_no, col, f[4 + k])?;
        }
        let theta = match f.get(8) {
            Some(cell) => Some(csv.number(line_no, THETA, cell)?),
            None => None,
        };
        Ok((
            line_no,
            TrajectoryRow {
                tick,
                time,
                body: f[2],
                kind: f[3],
                x: v[0],
                y: v[1],
                vx: v[2],
                vy: v[3],
                theta,
            },
        ))
    }))
}

/// The last tick of `trajectory.csv`'s text whose rows are all there (as
/// many as the first tick's: a run cut while writing a tick leaves that
/// tick short), `None` without one; a bad line is the error.
pub fn last_whole_tick(text: &str) -> Result<Option<u64>, CsvError> {
    let mut first_count = None;
    let (mut tick, mut count) = (None, 0usize);
    let mut whole = None;
    for row in trajectory_rows(text)? {
        let (_, row) = row?;
        if tick != Some(row.tick) {
            if let Some(t) = tick {
                let full = *first_count.get_or_insert(count);
                if count >= full {
                    whole = Some(t);
                }
            }
            tick = Some(row.tick);
            count = 0;
        }
        count += 1;
    }
    if let Some(t) = tick
        && count >= first_count.unwrap_or(count)
    {
        whole = Some(t);
    }
    Ok(whole)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(text: &str) -> Result<Vec<(usize, TrajectoryRow<'_>)>, CsvError> {
        trajectory_rows(text)?.collect()
    }

    #[test]
    fn rows_come_with_their_line_numbers_and_blank_lines_count() {
        let text = "tick,time,body,kind,x,y,vx,vy\r\n0,0,r0,robot,1,2,3,4\r\n\n1,0.1,o1,obstacle,-1,0,0,0.5\n";
        let got = rows(text).expect("rows");
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].0, 2);
        assert_eq!(
            (got[0].1.body, got[0].1.kind, got[0].1.x, got[0].1.vy),
            ("r0", "robot", 1.0, 4.0)
        );
        assert_eq!(got[1].0, 4);
        assert_eq!((got[1].1.tick, got[1].1.time), (1, 0.1));
        assert_eq!(got[1].1.theta, None);
    }

    #[test]
    fn columns_are_found_by_name_and_theta_is_read_when_there() {
        let text = "x,y,tick,theta,time,body,kind,vx,vy\n1,2,7,0.5,0.7,u0,robot,0,0\n";
        let got = rows(text).expect("rows");
        assert_eq!(got[0].1.tick, 7);
        assert_eq!((got[0].1.x, got[0].1.y), (1.0, 2.0));
        assert_eq!(got[0].1.theta, Some(0.5));
    }

    #[test]
    fn a_header_without_a_column_is_an_error_at_line_one_naming_it() {
        let Err(e) = trajectory_rows("tick,time,body,kind,x,y,vx\n") else {
            panic!("accepted a header without vy");
        };
        assert_eq!(e.line, 1);
        assert!(e.reason.contains("`vy`"), "{e}");
        let Err(e) = trajectory_rows("") else {
            panic!("accepted an empty file");
        };
        assert_eq!((e.line, e.reason.as_str()), (1, "empty file: no header"));
    }

    #[test]
    fn a_bad_cell_or_a_short_row_is_an_error_at_its_line() {
        let text =
            "tick,time,body,kind,x,y,vx,vy\n0,0,r0,robot,1,2,3,4\n1,0.1,r0,robot,abc,2,3,4\n";
        let e = rows(text).expect_err("bad x");
        assert_eq!(e.line, 3);
        assert!(
            e.reason.contains("`x`") && e.reason.contains("`abc`"),
            "{e}"
        );
        let e = rows("tick,time,body,kind,x,y,vx,vy\n0,0,r0,robot,1,2\n").expect_err("short");
        assert_eq!(
            (e.line, e.reason.as_str()),
            (2, "6 fields, the header has 8")
        );
        let e = rows("tick,time,body,kind,x,y,vx,vy\n-1,0,r0,robot,1,2,3,4\n").expect_err("tick");
        assert!(e.reason.contains("tick number"), "{e}");
    }

    #[test]
    fn the_last_whole_tick_is_the_last_with_every_body() {
        let h = "tick,time,body,kind,x,y,vx,vy\n";
        let row = |t: u64, b: &str| format!("{t},0,{b},robot,0,0,0,0\n");
        let two = |t| row(t, "a") + &row(t, "b");
        assert_eq!(last_whole_tick(h), Ok(None));
        let text = format!("{h}{}{}", two(0), two(5));
        assert_eq!(last_whole_tick(&text), Ok(Some(5)));
        let text = format!("{h}{}{}{}", two(0), two(5), row(10, "a"));
        assert_eq!(last_whole_tick(&text), Ok(Some(5)));
        assert_eq!(last_whole_tick(&format!("{h}{}", row(0, "a"))), Ok(Some(0)));
    }
}
