//! The trajectory as a Parquet file (`[output] trajectory = "parquet"`):
//! the same columns as `trajectory.csv`, typed.
//!
//! | column | Parquet type | meaning |
//! | --- | --- | --- |
//! | `tick` | INT64, logical UINT_64 | tick number |
//! | `time` | DOUBLE | simulated time, s |
//! | `body` | BYTE_ARRAY, UTF8 (dictionary) | the body's name |
//! | `kind` | BYTE_ARRAY, UTF8 (dictionary) | `robot` or `obstacle` |
//! | `x`, `y` | DOUBLE | position |
//! | `vx`, `vy` | DOUBLE | velocity |
//! | `theta` | DOUBLE | heading, rad (only in a run with a unicycle robot) |
//!
//! Every column is REQUIRED (no nulls); rows come in the CSV's order (tick,
//! then body id). `theta` is written, last, exactly when the CSV has it:
//! when the scenario has a unicycle robot. The CSV rounds the numbers to six decimals, the Parquet
//! file keeps them exact. Row groups hold about [`ROW_GROUP_ROWS`] rows and
//! are Snappy-compressed. The file is readable only once the world has
//! closed it (its footer is written last): a run whose world was killed
//! leaves an unreadable `trajectory.parquet`, where a CSV would keep the
//! ticks up to the last flush.

use crate::parquet_out::{self, Column};
use parquet::data_type::ByteArray;
use parquet::errors::ParquetError;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use std::collections::HashMap;
use std::fs::File;
use std::path::{Path, PathBuf};

/// The columns every trajectory has, in file order (the CSV's header,
/// split).
pub const COLUMNS: [&str; 8] = ["tick", "time", "body", "kind", "x", "y", "vx", "vy"];

/// The optional last column: every body's heading, rad (in runs with a
/// unicycle robot, as in the CSV).
pub const THETA: &str = "theta";

/// Rows a row group holds before the writer starts the next one.
pub const ROW_GROUP_ROWS: usize = 1 << 18;

/// The file's Parquet schema, with the `theta` column or without.
fn schema(theta: bool) -> String {
    format!(
        "message trajectory {{
    REQUIRED INT64 tick (INTEGER(64, false));
    REQUIRED DOUBLE time;
    REQUIRED BYTE_ARRAY body (UTF8);
    REQUIRED BYTE_ARRAY kind (UTF8);
    REQUIRED DOUBLE x;
    REQUIRED DOUBLE y;
    REQUIRED DOUBLE vx;
    REQUIRED DOUBLE vy;{}
}}",
        if theta {
            "\n    REQUIRED DOUBLE theta;"
        } else {
            ""
        }
    )
}

/// Why a Parquet trajectory could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// The file could not be created or opened.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The Parquet library refused to write or read it.
    #[error("{}: {source}", path.display())]
    Parquet {
        /// The file.
        path: PathBuf,
        /// parquet's error.
        source: ParquetError,
    },
    /// The file is Parquet but not a trajectory (columns, types, lengths).
    #[error("{}: {reason}", path.display())]
    Schema {
        /// The file.
        path: PathBuf,
        /// What does not match.
        reason: String,
    },
}

/// A body's `body` and `kind` cells, made once per body so that a row
/// costs no allocation.
#[derive(Debug, Clone)]
pub struct BodyCells {
    name: ByteArray,
    kind: ByteArray,
}

impl BodyCells {
    /// The cells of the body called `name`, of kind `kind` (`robot` or
    /// `obstacle`).
    pub fn new(name: &str, kind: &str) -> Self {
        Self {
            name: ByteArray::from(name),
            kind: ByteArray::from(kind),
        }
    }
}

/// Writes `trajectory.parquet` row by row, a row group at a time.
pub struct ParquetTrajectoryWriter {
    path: PathBuf,
    writer: SerializedFileWriter<File>,
    tick: Vec<i64>,
    time: Vec<f64>,
    body: Vec<ByteArray>,
    kind: Vec<ByteArray>,
    state: [Vec<f64>; 4],
    /// The headings, if the file has a `theta` column.
    theta: Option<Vec<f64>>,
}

impl ParquetTrajectoryWriter {
    /// Creates the file at `path` (replacing one there), with a `theta`
    /// column if `theta`.
    pub fn create(path: &Path, theta: bool) -> Result<Self, TrajectoryError> {
        let file = File::create(path).map_err(|source| TrajectoryError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let writer = parquet_out::writer(file, &schema(theta)).map_err(|source| {
            TrajectoryError::Parquet {
                path: path.to_path_buf(),
                source,
            }
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            tick: Vec::new(),
            time: Vec::new(),
            body: Vec::new(),
            kind: Vec::new(),
            state: Default::default(),
            theta: theta.then(Vec::new),
        })
    }

    /// Adds one row: `state` is `[x, y, vx, vy]`, `theta` the heading (kept
    /// only if the file has that column). A full row group goes to the
    /// file.
    pub fn push(
        &mut self,
        tick: u64,
        time: f64,
        body: &BodyCells,
        state: [f64; 4],
        theta: f64,
    ) -> Result<(), TrajectoryError> {
        self.tick.push(tick as i64);
        self.time.push(time);
        self.body.push(body.name.clone());
        self.kind.push(body.kind.clone());
        for (column, v) in self.state.iter_mut().zip(state) {
            column.push(v);
        }
        if let Some(column) = &mut self.theta {
            column.push(theta);
        }
        if self.tick.len() >= ROW_GROUP_ROWS {
            self.write_group()?;
        }
        Ok(())
    }

    /// Writes the rows held as one row group.
    fn write_group(&mut self) -> Result<(), TrajectoryError> {
        if self.tick.is_empty() {
            return Ok(());
        }
        let [x, y, vx, vy] = &self.state;
        let mut columns = vec![
            Column::Int64(&self.tick),
            Column::Double(&self.time),
            Column::Bytes(&self.body),
            Column::Bytes(&self.kind),
            Column::Double(x),
            Column::Double(y),
            Column::Double(vx),
            Column::Double(vy),
        ];
        if let Some(theta) = &self.theta {
            columns.push(Column::Double(theta));
        }
        parquet_out::write_group(&mut self.writer, &columns).map_err(|source| {
            TrajectoryError::Parquet {
                path: self.path.clone(),
                source,
            }
        })?;
        self.tick.clear();
        self.time.clear();
        self.body.clear();
        self.kind.clear();
        self.state.iter_mut().for_each(Vec::clear);
        if let Some(column) = &mut self.theta {
            column.clear();
        }
        Ok(())
    }

    /// Writes the last row group and the footer.
    pub fn finish(mut self) -> Result<(), TrajectoryError> {
        self.write_group()?;
        let path = self.path.clone();
        self.writer
            .close()
            .map(drop)
            .map_err(|source| TrajectoryError::Parquet { path, source })
    }
}

/// One row of a trajectory read back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryRow<'a> {
    /// Tick number.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
    /// The body's name.
    pub body: &'a str,
    /// `robot` or `obstacle`.
    pub kind: &'a str,
    /// Position x.
    pub x: f64,
    /// Position y.
    pub y: f64,
    /// Velocity x.
    pub vx: f64,
    /// Velocity y.
    pub vy: f64,
    /// Heading, rad, if the file has a `theta` column.
    pub theta: Option<f64>,
}

/// A whole `trajectory.parquet` in memory, by column; the names and kinds
/// are stored once each.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrajectoryTable {
    tick: Vec<u64>,
    time: Vec<f64>,
    body: Vec<u32>,
    kind: Vec<u32>,
    state: [Vec<f64>; 4],
    /// The headings, if the file has a `theta` column.
    theta: Option<Vec<f64>>,
    strings: Vec<String>,
}

impl TrajectoryTable {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.tick.len()
    }

    /// No rows.
    pub fn is_empty(&self) -> bool {
        self.tick.is_empty()
    }

    /// True if the file had a `theta` column (a run with a unicycle).
    pub fn has_theta(&self) -> bool {
        self.theta.is_some()
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> TrajectoryRow<'_> {
        TrajectoryRow {
            tick: self.tick[i],
            time: self.time[i],
            body: &self.strings[self.body[i] as usize],
            kind: &self.strings[self.kind[i] as usize],
            x: self.state[0][i],
            y: self.state[1][i],
            vx: self.state[2][i],
            vy: self.state[3][i],
            theta: self.theta.as_ref().map(|t| t[i]),
        }
    }

    /// Every row, in file order.
    pub fn rows(&self) -> impl Iterator<Item = TrajectoryRow<'_>> {
        (0..self.len()).map(|i| self.row(i))
    }
}

/// Reads a trajectory written by [`ParquetTrajectoryWriter`] (or any
/// Parquet file with its columns and types, in any order; `theta` if there
/// is one).
pub fn read_parquet_trajectory(path: &Path) -> Result<TrajectoryTable, TrajectoryError> {
    let file = File::open(path).map_err(|source| TrajectoryError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let pq = |source| TrajectoryError::Parquet {
        path: path.to_path_buf(),
        source,
    };
    let schema_err = |reason: String| TrajectoryError::Schema {
        path: path.to_path_buf(),
        reason,
    };
    let reader = SerializedFileReader::new(file).map_err(pq)?;
    let meta = reader.metadata();
    let descr = meta.file_metadata().schema_descr();
    let find = |name: &str| (0..descr.num_columns()).find(|&i| descr.column(i).name() == name);
    let mut at = [usize::MAX; 9];
    for (k, name) in COLUMNS.iter().enumerate() {
        at[k] = find(name).ok_or_else(|| schema_err(format!("no column `{name}`")))?;
    }
    let theta_at = find(THETA);
    let columns = COLUMNS.len() + usize::from(theta_at.is_some());
    if let Some(i) = theta_at {
        at[8] = i;
    }
    let mut table = TrajectoryTable {
        theta: theta_at.map(|_| Vec::new()),
        ..Default::default()
    };
    let mut interned: HashMap<Vec<u8>, u32> = HashMap::new();
    for g in 0..meta.num_row_groups() {
        let group = reader.get_row_group(g).map_err(pq)?;
        let rows = group.metadata().num_rows() as usize;
        let wrong = |name: &str| schema_err(format!("column `{name}` has the wrong type"));
        for (k, name) in COLUMNS.iter().chain([&THETA]).take(columns).enumerate() {
            let column = group.get_column_reader(at[k]).map_err(pq)?;
            use parquet::column::reader::ColumnReader as C;
            match (k, column) {
                (0, C::Int64ColumnReader(mut r)) => {
                    let mut v = Vec::with_capacity(rows);
                    r.read_records(rows, None, None, &mut v).map_err(pq)?;
                    table.tick.extend(v.into_iter().map(|t| t as u64));
                }
                (2 | 3, C::ByteArrayColumnReader(mut r)) => {
                    let mut v = Vec::with_capacity(rows);
                    r.read_records(rows, None, None, &mut v).map_err(pq)?;
                    for cell in v {
                        let next = table.strings.len() as u32;
                        let id = *interned.entry(cell.data().to_vec()).or_insert(next);
                        if id == next {
                            let text = cell.as_utf8().map_err(pq)?;
                            table.strings.push(text.to_string());
                        }
                        if k == 2 {
                            &mut table.body
                        } else {
                            &mut table.kind
                        }
                        .push(id);
                    }
                }
                (1 | 4..=8, C::DoubleColumnReader(mut r)) => {
                    let out = match k {
                        1 => &mut table.time,
                        4..=7 => &mut table.state[k - 4],
                        _ => table.theta.get_or_insert_default(),
                    };
                    r.read_records(rows, None, None, out).map_err(pq)?;
                }
                _ => return Err(wrong(name)),
            }
        }
        let n = table.tick.len();
        let lengths = [
            table.time.len(),
            table.body.len(),
            table.kind.len(),
            table.state[0].len(),
            table.state[1].len(),
            table.state[2].len(),
            table.state[3].len(),
            table.theta.as_ref().map_or(n, Vec::len),
        ];
        if lengths.iter().any(|&l| l != n) {
            return Err(schema_err(format!(
                "row group {g}: columns of different lengths (nulls in a REQUIRED column?)"
            )));
        }
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_read_back_as_written_across_row_groups() {
        let dir = std::env::temp_dir().join(format!("mrsim-pq-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.parquet");
        let a = BodyCells::new("r0", "robot");
        let b = BodyCells::new("o1", "obstacle");
        let mut w = ParquetTrajectoryWriter::create(&path, false).expect("create");
        let ticks = ROW_GROUP_ROWS as u64 / 2 + 3;
        for t in 0..ticks {
            let f = t as f64;
            w.push(t, f * 0.1, &a, [f, -f, 0.5, 1e-9 * f], 9.0)
                .expect("row");
            w.push(t, f * 0.1, &b, [1.0 / (f + 1.0), 2.0, -0.0, f64::MAX], 9.0)
                .expect("row");
        }
        w.finish().expect("finish");
        let table = read_parquet_trajectory(&path).expect("read");
        assert_eq!(table.len(), 2 * ticks as usize);
        assert!(!table.has_theta());
        for (i, row) in table.rows().enumerate() {
            let t = i as u64 / 2;
            let f = t as f64;
            let want = if i % 2 == 0 {
                ("r0", "robot", [f, -f, 0.5, 1e-9 * f])
            } else {
                ("o1", "obstacle", [1.0 / (f + 1.0), 2.0, -0.0, f64::MAX])
            };
            assert_eq!((row.tick, row.time), (t, f * 0.1));
            assert_eq!((row.body, row.kind), (want.0, want.1));
            assert_eq!([row.x, row.y, row.vx, row.vy], want.2);
            assert_eq!(row.theta, None);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn headings_read_back_as_written_when_the_file_has_a_theta_column() {
        let dir = std::env::temp_dir().join(format!("mrsim-pq-theta-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.parquet");
        let a = BodyCells::new("u0", "robot");
        let mut w = ParquetTrajectoryWriter::create(&path, true).expect("create");
        let ticks = ROW_GROUP_ROWS as u64 + 5;
        for t in 0..ticks {
            let f = t as f64;
            w.push(t, f, &a, [f, 0.0, 0.0, 0.0], (f * 1e-3).sin())
                .expect("row");
        }
        w.finish().expect("finish");
        let table = read_parquet_trajectory(&path).expect("read");
        assert!(table.has_theta());
        assert_eq!(table.len(), ticks as usize);
        for (t, row) in table.rows().enumerate() {
            assert_eq!(row.theta, Some((t as f64 * 1e-3).sin()), "row {t}");
            assert_eq!(row.x, t as f64);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_that_is_not_parquet_is_an_error_naming_it() {
        let dir = std::env::temp_dir().join(format!("mrsim-pq-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.parquet");
        std::fs::write(&path, b"tick,time\n").expect("write");
        let e = read_parquet_trajectory(&path).expect_err("not parquet");
        assert!(e.to_string().contains("t.parquet"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
