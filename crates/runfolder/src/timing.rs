//! `timing.csv`: what timing decided for every planner call of a run, one
//! row per command the world heard of, in the order it heard them.
//!
//! Columns: `tick` (the tick of the snapshot the planner read, which the
//! command answers), `robot` (its name), `sent_ns` (when the command was
//! sent, ns after that snapshot was published: whole nanoseconds, so a
//! rerun applies it at exactly the same physics substep) and `status`:
//! `accepted` (in by the deadline, applied), `late` (after it: a miss) or
//! `lost` (lost on its way by the robot's `command_loss`: a miss), and
//! `cpu_ns`: the CPU the call took. In realtime that is the agent's thread
//! CPU clock over the call (planner and any `cpu = true` work); in lockstep
//! it is the model's: the drawn compute time of a `cpu = true` robot, 0 for
//! a wait (`cpu = false`); a rerun writes what it replays. `sent_ns` is the
//! call's response time. Files of older runs, without the column, read with
//! `cpu_ns` 0. A tick
//! of a robot with no row had no answer (a miss, or not a tick of its
//! `period_ticks`). Written by every realtime run and by every lockstep run
//! with a timing model; `mrsim rerun` reads it back.
//!
//! A run whose `[output] trajectory = "parquet"` writes the same rows as
//! `timing.parquet` instead (columns `tick` INT64, `robot` UTF8 string,
//! `sent_ns` INT64, `status` UTF8 string): [`TimingSink`] writes either,
//! [`read_timing`] reads whichever the folder holds. While such a run
//! lives its rows also go to `timing.journal.csv` (timing.csv's format),
//! removed once the Parquet file's footer is written: a cut run's
//! `timing.parquet` has no footer, and [`read_timing`] reads the journal.
//!
//! Rows are written whole ([`RowFile`]) and reach the disk when the
//! recording thread flushes ([`TimingSink::flush`]); a torn last row (a
//! cut run) is left out and reported ([`Timing::cut`]).

use crate::parquet_out::{self, Column};
use crate::stream::{Cut, RowFile, read_whole_rows};
use parquet::data_type::ByteArray;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The file's name in the run folder.
pub const TIMING_FILE: &str = "timing.csv";
/// The file's name when the run writes Parquet.
pub const TIMING_PARQUET_FILE: &str = "timing.parquet";
/// timing.parquet's rows as CSV while the run lives (removed at its end).
pub const TIMING_JOURNAL_FILE: &str = "timing.journal.csv";
/// Rows per Parquet row group.
const ROW_GROUP_ROWS: usize = 1 << 16;
/// Its header line.
pub const HEADER: &str = "tick,robot,sent_ns,status,cpu_ns";
/// The header of files written before the `cpu_ns` column.
const HEADER_WITHOUT_CPU: &str = "tick,robot,sent_ns,status";

/// What became of a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// In by its tick's deadline, applied.
    Accepted,
    /// After its tick's deadline: a miss, not applied.
    Late,
    /// Lost on its way: a miss.
    Lost,
}

impl Status {
    /// The status a word of the file names, if any.
    pub fn parse(word: &str) -> Option<Self> {
        match word {
            "accepted" => Some(Status::Accepted),
            "late" => Some(Status::Late),
            "lost" => Some(Status::Lost),
            _ => None,
        }
    }

    /// The word written in the file.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Accepted => "accepted",
            Status::Late => "late",
            Status::Lost => "lost",
        }
    }
}

/// One row.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    /// The tick of the snapshot the planner read.
    pub tick: u64,
    /// The robot's name.
    pub robot: String,
    /// When its command was sent, ns after that snapshot's publication.
    pub sent_ns: u64,
    /// What became of it.
    pub status: Status,
    /// The CPU the call took, ns (0 in files without the column).
    pub cpu_ns: u64,
}

/// Why timing.csv could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum TimingFileError {
    /// The file could not be created, written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The Parquet file could not be written or decoded.
    #[error("{}: {source}", path.display())]
    Parquet {
        /// The file.
        path: PathBuf,
        /// The Parquet error.
        source: parquet::errors::ParquetError,
    },
    /// A line is not a row of this schema.
    #[error("{}:{line}: {reason}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong with it.
        reason: String,
    },
}

/// Writes rows to `dir/timing.csv` as they come, whole: they reach the
/// file at [`TimingWriter::flush`].
pub struct TimingWriter {
    path: PathBuf,
    out: RowFile,
}

impl TimingWriter {
    /// Creates `dir/timing.csv` with its header.
    pub fn create(dir: &Path) -> Result<Self, TimingFileError> {
        Self::create_at(&dir.join(TIMING_FILE))
    }

    /// Creates the CSV file at `path` with its header.
    fn create_at(path: &Path) -> Result<Self, TimingFileError> {
        let out = RowFile::create(path, HEADER).map_err(|source| TimingFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            out,
        })
    }

    /// Puts the rows held on the disk.
    pub fn flush(&mut self) -> Result<(), TimingFileError> {
        self.out.write_out().map_err(|source| TimingFileError::Io {
            path: self.path.clone(),
            source,
        })
    }

    /// Holds enough to be written out.
    pub fn is_full(&self) -> bool {
        self.out.is_full()
    }

    /// Appends one row.
    pub fn row(
        &mut self,
        tick: u64,
        robot: &str,
        sent_ns: u64,
        status: Status,
        cpu_ns: u64,
    ) -> Result<(), TimingFileError> {
        writeln!(
            self.out,
            "{tick},{robot},{sent_ns},{},{cpu_ns}",
            status.as_str()
        )
        .map_err(|source| TimingFileError::Io {
            path: self.path.clone(),
            source,
        })
    }

    /// Flushes and closes the file.
    pub fn finish(mut self) -> Result<(), TimingFileError> {
        self.out.flush().map_err(|source| TimingFileError::Io {
            path: self.path.clone(),
            source,
        })
    }
}

/// Writes `timing.parquet` a row group at a time, and every row to its
/// journal as it comes.
pub struct ParquetTimingWriter {
    path: PathBuf,
    writer: SerializedFileWriter<std::fs::File>,
    journal: TimingWriter,
    tick: Vec<i64>,
    robot: Vec<ByteArray>,
    sent_ns: Vec<i64>,
    status: Vec<ByteArray>,
    cpu_ns: Vec<i64>,
}

/// The Parquet file's schema.
const PARQUET_SCHEMA: &str = "message timing {
    REQUIRED INT64 tick;
    REQUIRED BYTE_ARRAY robot (UTF8);
    REQUIRED INT64 sent_ns;
    REQUIRED BYTE_ARRAY status (UTF8);
    REQUIRED INT64 cpu_ns;
}";

impl ParquetTimingWriter {
    /// Creates `dir/timing.parquet`.
    pub fn create(dir: &Path) -> Result<Self, TimingFileError> {
        let path = dir.join(TIMING_PARQUET_FILE);
        let file = std::fs::File::create(&path).map_err(|source| TimingFileError::Io {
            path: path.clone(),
            source,
        })?;
        let writer = parquet_out::writer(file, PARQUET_SCHEMA).map_err(|source| {
            TimingFileError::Parquet {
                path: path.clone(),
                source,
            }
        })?;
        let journal = TimingWriter::create_at(&dir.join(TIMING_JOURNAL_FILE))?;
        Ok(Self {
            path,
            writer,
            journal,
            tick: Vec::new(),
            robot: Vec::new(),
            sent_ns: Vec::new(),
            status: Vec::new(),
            cpu_ns: Vec::new(),
        })
    }

    /// Appends one row; a full row group goes to the file.
    pub fn row(
        &mut self,
        tick: u64,
        robot: &str,
        sent_ns: u64,
        status: Status,
        cpu_ns: u64,
    ) -> Result<(), TimingFileError> {
        self.journal.row(tick, robot, sent_ns, status, cpu_ns)?;
        self.tick.push(tick as i64);
        self.robot.push(ByteArray::from(robot));
        self.sent_ns.push(sent_ns as i64);
        self.status.push(ByteArray::from(status.as_str()));
        self.cpu_ns.push(cpu_ns as i64);
        if self.tick.len() >= ROW_GROUP_ROWS {
            self.write_group()?;
        }
        Ok(())
    }

    fn write_group(&mut self) -> Result<(), TimingFileError> {
        if self.tick.is_empty() {
            return Ok(());
        }
        parquet_out::write_group(
            &mut self.writer,
            &[
                Column::Int64(&self.tick),
                Column::Bytes(&self.robot),
                Column::Int64(&self.sent_ns),
                Column::Bytes(&self.status),
                Column::Int64(&self.cpu_ns),
            ],
        )
        .map_err(|source| TimingFileError::Parquet {
            path: self.path.clone(),
            source,
        })?;
        self.tick.clear();
        self.robot.clear();
        self.sent_ns.clear();
        self.status.clear();
        self.cpu_ns.clear();
        Ok(())
    }

    /// Writes the last row group and the footer, and removes the journal.
    pub fn finish(mut self) -> Result<(), TimingFileError> {
        self.write_group()?;
        let path = self.path.clone();
        self.writer
            .close()
            .map(drop)
            .map_err(|source| TimingFileError::Parquet { path, source })?;
        let journal = self.journal.path;
        std::fs::remove_file(&journal).map_err(|source| TimingFileError::Io {
            path: journal,
            source,
        })
    }
}

/// Where a run's timing rows go: timing.csv or timing.parquet.
pub enum TimingSink {
    /// `timing.csv`.
    Csv(TimingWriter),
    /// `timing.parquet`.
    Parquet(Box<ParquetTimingWriter>),
}

impl TimingSink {
    /// Creates the file in `dir`, Parquet if `parquet`, and removes one of
    /// the other format a previous run left there.
    pub fn create(dir: &Path, parquet: bool) -> Result<Self, TimingFileError> {
        let other = dir.join(if parquet {
            TIMING_FILE
        } else {
            TIMING_PARQUET_FILE
        });
        if other.exists() {
            std::fs::remove_file(&other).map_err(|source| TimingFileError::Io {
                path: other.clone(),
                source,
            })?;
        }
        Ok(if parquet {
            TimingSink::Parquet(Box::new(ParquetTimingWriter::create(dir)?))
        } else {
            TimingSink::Csv(TimingWriter::create(dir)?)
        })
    }

    /// The file's name in the run folder.
    pub fn file_name(&self) -> &'static str {
        match self {
            TimingSink::Csv(_) => TIMING_FILE,
            TimingSink::Parquet(_) => TIMING_PARQUET_FILE,
        }
    }

    /// Appends one row.
    pub fn row(
        &mut self,
        tick: u64,
        robot: &str,
        sent_ns: u64,
        status: Status,
        cpu_ns: u64,
    ) -> Result<(), TimingFileError> {
        match self {
            TimingSink::Csv(w) => w.row(tick, robot, sent_ns, status, cpu_ns),
            TimingSink::Parquet(w) => w.row(tick, robot, sent_ns, status, cpu_ns),
        }
    }

    /// Puts the rows held on the disk (timing.csv, or timing.parquet's
    /// journal).
    pub fn flush(&mut self) -> Result<(), TimingFileError> {
        match self {
            TimingSink::Csv(w) => w.flush(),
            TimingSink::Parquet(w) => w.journal.flush(),
        }
    }

    /// Holds enough rows to be written out.
    pub fn is_full(&self) -> bool {
        match self {
            TimingSink::Csv(w) => w.is_full(),
            TimingSink::Parquet(w) => w.journal.is_full(),
        }
    }

    /// Writes what is held and closes the file.
    pub fn finish(self) -> Result<(), TimingFileError> {
        match self {
            TimingSink::Csv(w) => w.finish(),
            TimingSink::Parquet(w) => w.finish(),
        }
    }
}

/// A run folder's timing rows, and where the file was cut if it was.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// The rows, in file order.
    pub rows: Vec<Row>,
    /// The run was cut: timing.csv's torn last row (left out), or a
    /// timing.parquet without its footer (its journal read instead).
    pub cut: Option<Cut>,
}

/// Reads the run folder `dir`'s timing rows: `timing.parquet` if it has
/// one (its journal, `timing.journal.csv`, if the run was cut before the
/// footer was written), else `timing.csv`. A torn last row is left out
/// and reported; any other bad line is an error naming it.
pub fn read_timing(dir: &Path) -> Result<Timing, TimingFileError> {
    let parquet = dir.join(TIMING_PARQUET_FILE);
    let journal = dir.join(TIMING_JOURNAL_FILE);
    if parquet.exists() {
        return match read_parquet_timing(&parquet) {
            Ok(rows) => Ok(Timing { rows, cut: None }),
            Err(TimingFileError::Parquet { .. }) if journal.exists() => {
                let mut t = read_csv_timing(&journal)?;
                t.cut = Some(Cut {
                    path: parquet,
                    line: 0,
                    detail: format!(
                        "no Parquet footer; read its journal {TIMING_JOURNAL_FILE}{}",
                        t.cut.map_or(String::new(), |c| format!(" ({c})"))
                    ),
                });
                Ok(t)
            }
            Err(e) => Err(e),
        };
    }
    read_csv_timing(&dir.join(TIMING_FILE))
}

/// Reads a `timing.parquet` at `path`.
fn read_parquet_timing(path: &Path) -> Result<Vec<Row>, TimingFileError> {
    use parquet::column::reader::ColumnReader as C;
    let file = std::fs::File::open(path).map_err(|source| TimingFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let pq = |source| TimingFileError::Parquet {
        path: path.to_path_buf(),
        source,
    };
    let bad = |line: usize, reason: String| TimingFileError::Malformed {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let reader = SerializedFileReader::new(file).map_err(pq)?;
    let meta = reader.metadata();
    let descr = meta.file_metadata().schema_descr();
    let find = |name: &str| {
        (0..descr.num_columns())
            .find(|&i| descr.column(i).name() == name)
            .ok_or_else(|| bad(0, format!("no column `{name}`")))
    };
    let at = [
        find("tick")?,
        find("robot")?,
        find("sent_ns")?,
        find("status")?,
    ];
    // Absent in files written before the column.
    let cpu_at = find("cpu_ns").ok();
    let mut rows = Vec::new();
    for g in 0..meta.num_row_groups() {
        let group = reader.get_row_group(g).map_err(pq)?;
        let n = group.metadata().num_rows() as usize;
        let (mut ints, mut texts): ([Vec<i64>; 2], [Vec<ByteArray>; 2]) = Default::default();
        for (k, &i) in at.iter().enumerate() {
            match (k, group.get_column_reader(i).map_err(pq)?) {
                (0 | 2, C::Int64ColumnReader(mut r)) => {
                    r.read_records(n, None, None, &mut ints[k / 2])
                        .map_err(pq)?;
                }
                (1 | 3, C::ByteArrayColumnReader(mut r)) => {
                    r.read_records(n, None, None, &mut texts[k / 2])
                        .map_err(pq)?;
                }
                _ => return Err(bad(0, format!("column {k} has the wrong type"))),
            }
        }
        let mut cpu = Vec::new();
        match cpu_at
            .map(|i| group.get_column_reader(i))
            .transpose()
            .map_err(pq)?
        {
            Some(C::Int64ColumnReader(mut r)) => {
                r.read_records(n, None, None, &mut cpu).map_err(pq)?;
            }
            Some(_) => return Err(bad(0, "column cpu_ns has the wrong type".into())),
            None => cpu = vec![0; n],
        }
        if ints.iter().any(|c| c.len() != n) || texts.iter().any(|c| c.len() != n) || cpu.len() != n
        {
            return Err(bad(
                0,
                format!("row group {g}: columns of different lengths"),
            ));
        }
        for j in 0..n {
            let line = rows.len() + 1;
            let text = |c: &ByteArray| {
                c.as_utf8()
                    .map(str::to_string)
                    .map_err(|_| bad(line, "a cell is not UTF-8".into()))
            };
            let status = text(&texts[1][j])?;
            let whole = |v: i64, what: &str| {
                u64::try_from(v).map_err(|_| bad(line, format!("{what} {v} is negative")))
            };
            rows.push(Row {
                tick: whole(ints[0][j], "tick")?,
                robot: text(&texts[0][j])?,
                sent_ns: whole(ints[1][j], "sent_ns")?,
                status: Status::parse(&status).ok_or_else(|| {
                    bad(
                        line,
                        format!("unknown status `{status}` (accepted, late, lost)"),
                    )
                })?,
                cpu_ns: whole(cpu[j], "cpu_ns")?,
            });
        }
    }
    Ok(rows)
}

/// Reads the timing CSV at `path` (timing.csv or the journal).
fn read_csv_timing(path: &Path) -> Result<Timing, TimingFileError> {
    let io = |source| TimingFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (text, cut) = read_whole_rows(path).map_err(io)?.ok_or_else(|| {
        io(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no such file",
        ))
    })?;
    let path = path.to_path_buf();
    let mut rows = Vec::new();
    let mut fields = 5;
    for (i, line) in text.lines().enumerate() {
        let bad = |reason: String| TimingFileError::Malformed {
            path: path.clone(),
            line: i + 1,
            reason,
        };
        if i == 0 {
            fields = match line {
                HEADER => 5,
                HEADER_WITHOUT_CPU => 4,
                _ => return Err(bad(format!("expected the header `{HEADER}`"))),
            };
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let (tick, robot, sent, status, cpu) = match (fields, f.as_slice()) {
            (5, [tick, robot, sent, status, cpu]) => (tick, robot, sent, status, Some(cpu)),
            (4, [tick, robot, sent, status]) => (tick, robot, sent, status, None),
            _ => return Err(bad(format!("expected {fields} fields, got {}", f.len()))),
        };
        let num = |s: &str, what: &str| {
            s.parse::<u64>()
                .map_err(|_| bad(format!("{what} `{s}` is not a whole number")))
        };
        let status = Status::parse(status)
            .ok_or_else(|| bad(format!("unknown status `{status}` (accepted, late, lost)")))?;
        rows.push(Row {
            tick: num(tick, "tick")?,
            robot: robot.to_string(),
            sent_ns: num(sent, "sent_ns")?,
            status,
            cpu_ns: cpu.map_or(Ok(0), |c| num(c, "cpu_ns"))?,
        });
    }
    Ok(Timing { rows, cut })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_written_are_the_rows_read() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut w = TimingWriter::create(&dir).unwrap();
        w.row(0, "r0", 150_000_000, Status::Late, 20_000_000)
            .unwrap();
        w.row(1, "r1", 12, Status::Accepted, 7).unwrap();
        w.row(2, "r0", 0, Status::Lost, 0).unwrap();
        w.finish().unwrap();
        let rows = read_timing(&dir).unwrap().rows;
        assert_eq!(rows.len(), 3);
        assert_eq!(
            rows[1],
            Row {
                tick: 1,
                robot: "r1".into(),
                sent_ns: 12,
                status: Status::Accepted,
                cpu_ns: 7,
            }
        );
        std::fs::write(dir.join(TIMING_FILE), format!("{HEADER}\n1,r0,x,late,0\n")).unwrap();
        let e = read_timing(&dir).unwrap_err().to_string();
        assert!(
            e.ends_with("timing.csv:2: sent_ns `x` is not a whole number"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn parquet_rows_written_are_the_rows_read_and_replace_the_csv() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-pq-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = TimingSink::create(&dir, false).unwrap();
        csv.row(7, "old", 1, Status::Accepted, 0).unwrap();
        csv.finish().unwrap();
        let mut w = TimingSink::create(&dir, true).unwrap();
        assert_eq!(w.file_name(), TIMING_PARQUET_FILE);
        let written: Vec<Row> = (0..(ROW_GROUP_ROWS as u64 + 5))
            .map(|t| Row {
                tick: t / 3,
                robot: format!("r{}", t % 3),
                sent_ns: t * 1_000_003,
                status: [Status::Accepted, Status::Late, Status::Lost][(t % 3) as usize],
                cpu_ns: t * 17,
            })
            .collect();
        for r in &written {
            w.row(r.tick, &r.robot, r.sent_ns, r.status, r.cpu_ns)
                .unwrap();
        }
        w.finish().unwrap();
        assert!(
            !dir.join(TIMING_FILE).exists(),
            "the csv of a previous run stays"
        );
        assert_eq!(read_timing(&dir).unwrap().rows, written);
        assert!(
            !dir.join(TIMING_JOURNAL_FILE).exists(),
            "the journal stays after the footer"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_torn_last_row_is_left_out_and_reported_and_a_bad_middle_row_is_an_error() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-cut-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(TIMING_FILE);
        std::fs::write(&path, format!("{HEADER}\n0,r0,5,accepted,0\n1,r0,6,acc")).unwrap();
        let t = read_timing(&dir).unwrap();
        assert_eq!(t.rows.len(), 1);
        let cut = t.cut.expect("reported as cut");
        assert_eq!((cut.path.as_path(), cut.line), (path.as_path(), 3));
        std::fs::write(
            &path,
            format!("{HEADER}\n0,r0,5,accepted\n1,r0,6,accepted,0\n"),
        )
        .unwrap();
        let e = read_timing(&dir).unwrap_err().to_string();
        assert!(e.ends_with("timing.csv:2: expected 5 fields, got 4"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_parquet_file_cut_before_its_footer_is_read_from_its_journal() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-journal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut w = TimingSink::create(&dir, true).unwrap();
        w.row(0, "r0", 10, Status::Accepted, 0).unwrap();
        w.row(0, "r1", 20, Status::Late, 0).unwrap();
        w.flush().unwrap();
        // The run is killed here: no footer, the journal on the disk.
        std::mem::forget(w);
        let t = read_timing(&dir).unwrap();
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[1].status, Status::Late);
        let cut = t.cut.expect("reported as cut");
        assert!(cut.to_string().contains("no Parquet footer"), "{cut}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_file_written_before_the_cpu_column_reads_with_no_cpu() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-old-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join(TIMING_FILE),
            format!("{HEADER_WITHOUT_CPU}\n0,r0,5,accepted\n"),
        )
        .unwrap();
        let t = read_timing(&dir).unwrap();
        assert_eq!((t.rows[0].sent_ns, t.rows[0].cpu_ns), (5, 0));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
