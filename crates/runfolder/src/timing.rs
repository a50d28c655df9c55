//! `timing.csv`: what timing decided for every planner call of a run, one
//! row per command the world heard of, in the order it heard them.
//!
//! Columns: `tick` (the tick of the snapshot the planner read, which the
//! command answers), `robot` (its name), `sent_ns` (when the command was
//! sent, ns after that snapshot was published: whole nanoseconds, so a
//! rerun applies it at exactly the same physics substep) and `status`:
//! `accepted` (in by the deadline, applied), `late` (after it: a miss) or
//! `lost` (lost on its way by the robot's `command_loss`: a miss). A tick
//! of a robot with no row had no answer (a miss, or not a tick of its
//! `period_ticks`). Written by every realtime run and by every lockstep run
//! with a timing model; `mrsim rerun` reads it back.

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// The file's name in the run folder.
pub const TIMING_FILE: &str = "timing.csv";
/// Its header line.
pub const HEADER: &str = "tick,robot,sent_ns,status";

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

/// Writes rows to `dir/timing.csv` as they come.
pub struct TimingWriter {
    path: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
}

impl TimingWriter {
    /// Creates `dir/timing.csv` with its header.
    pub fn create(dir: &Path) -> Result<Self, TimingFileError> {
        let path = dir.join(TIMING_FILE);
        let io = |source| TimingFileError::Io {
            path: path.clone(),
            source,
        };
        let file = std::fs::File::create(&path).map_err(io)?;
        let mut out = std::io::BufWriter::new(file);
        writeln!(out, "{HEADER}").map_err(io)?;
        Ok(Self { path, out })
    }

    /// Appends one row.
    pub fn row(
        &mut self,
        tick: u64,
        robot: &str,
        sent_ns: u64,
        status: Status,
    ) -> Result<(), TimingFileError> {
        writeln!(self.out, "{tick},{robot},{sent_ns},{}", status.as_str()).map_err(|source| {
            TimingFileError::Io {
                path: self.path.clone(),
                source,
            }
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

/// Reads `dir/timing.csv`.
pub fn read_timing(dir: &Path) -> Result<Vec<Row>, TimingFileError> {
    let path = dir.join(TIMING_FILE);
    let file = std::fs::File::open(&path).map_err(|source| TimingFileError::Io {
        path: path.clone(),
        source,
    })?;
    let mut rows = Vec::new();
    for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|source| TimingFileError::Io {
            path: path.clone(),
            source,
        })?;
        let bad = |reason: String| TimingFileError::Malformed {
            path: path.clone(),
            line: i + 1,
            reason,
        };
        if i == 0 {
            if line != HEADER {
                return Err(bad(format!("expected the header `{HEADER}`")));
            }
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let [tick, robot, sent, status] = f.as_slice() else {
            return Err(bad(format!("expected 4 fields, got {}", f.len())));
        };
        let num = |s: &str, what: &str| {
            s.parse::<u64>()
                .map_err(|_| bad(format!("{what} `{s}` is not a whole number")))
        };
        let status = match *status {
            "accepted" => Status::Accepted,
            "late" => Status::Late,
            "lost" => Status::Lost,
            other => {
                return Err(bad(format!(
                    "unknown status `{other}` (accepted, late, lost)"
                )));
            }
        };
        rows.push(Row {
            tick: num(tick, "tick")?,
            robot: robot.to_string(),
            sent_ns: num(sent, "sent_ns")?,
            status,
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_written_are_the_rows_read() {
        let dir = std::env::temp_dir().join(format!("mrsim-timing-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut w = TimingWriter::create(&dir).unwrap();
        w.row(0, "r0", 150_000_000, Status::Late).unwrap();
        w.row(1, "r1", 12, Status::Accepted).unwrap();
        w.row(2, "r0", 0, Status::Lost).unwrap();
        w.finish().unwrap();
        let rows = read_timing(&dir).unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(
            rows[1],
            Row {
                tick: 1,
                robot: "r1".into(),
                sent_ns: 12,
                status: Status::Accepted
            }
        );
        std::fs::write(dir.join(TIMING_FILE), format!("{HEADER}\n1,r0,x,late\n")).unwrap();
        let e = read_timing(&dir).unwrap_err().to_string();
        assert!(
            e.ends_with("timing.csv:2: sent_ns `x` is not a whole number"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
