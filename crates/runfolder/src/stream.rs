//! How the run folder's streaming files are written and read back after a
//! cut: whole rows, flushed on a clock, and a torn last row told apart from
//! a bad one.
//!
//! **Writing.** trajectory.csv, timing.csv, events.jsonl, scan.csv,
//! encounters.csv and the diagnostics part files are [`RowFile`]s: rows are
//! gathered in memory and go to the file only when the writer says so, at
//! a row boundary (never at a buffer boundary, which is how a buffered
//! writer tore `timing.csv` mid-line at exactly 8,192 bytes). The world's
//! recording thread puts all of its files on the disk together, in a fixed
//! order, whenever a [`FlushClock`] says so: once per simulated second or
//! per [`FLUSH_WALL`] of wall time, whichever comes first, and whenever a
//! buffer holds [`ROW_FILE_BUFFER`] bytes. Only `write(2)` is called (no
//! `fsync`): what the kernel has survives the process being killed, not
//! the machine losing power.
//!
//! **Reading.** Every writer ends a row with a newline, so a file whose
//! last line has none was cut while that line was written (the process was
//! killed inside a `write`): [`whole_rows`] splits the text there, and the
//! reader accepts the rows before it and reports the cut ([`Cut`]). Any
//! other malformed line is an error naming the file and the line.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The longest wall time between two flushes of the world's files.
pub const FLUSH_WALL: Duration = Duration::from_secs(1);

/// The most simulated time between two flushes of the world's files, s.
pub const FLUSH_SIM_S: f64 = 1.0;

/// Bytes a [`RowFile`] holds before its writer puts everything on the disk.
pub const ROW_FILE_BUFFER: usize = 1 << 20;

/// A file written in whole rows: [`Write`] appends to memory only, and
/// [`Write::flush`] (or [`RowFile::write_out`]) puts what is held on the
/// disk in one `write_all`. A writer that calls them between rows never
/// leaves a partial row in the file, whatever the rows' sizes.
#[derive(Debug)]
pub struct RowFile {
    path: PathBuf,
    file: File,
    buf: Vec<u8>,
}

impl RowFile {
    /// Creates (or truncates) the file at `path`, with `header` (a line,
    /// without its newline; nothing if empty) written at once.
    pub fn create(path: &Path, header: &str) -> std::io::Result<Self> {
        let mut out = Self {
            path: path.to_path_buf(),
            file: File::create(path)?,
            buf: Vec::with_capacity(1 << 12),
        };
        if !header.is_empty() {
            out.buf.extend_from_slice(header.as_bytes());
            out.buf.push(b'\n');
            out.write_out()?;
        }
        Ok(out)
    }

    /// Opens `path` to append to it (created if absent).
    pub fn append(path: &Path) -> std::io::Result<Self> {
        let file = std::fs::OpenOptions::new()
            .append(true)
            .create(true)
            .open(path)?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            buf: Vec::with_capacity(1 << 12),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The rows held, to append to directly (each ended by a newline).
    pub fn rows_mut(&mut self) -> &mut Vec<u8> {
        &mut self.buf
    }

    /// Bytes held.
    pub fn held(&self) -> usize {
        self.buf.len()
    }

    /// Holds [`ROW_FILE_BUFFER`] bytes or more: time to write out.
    pub fn is_full(&self) -> bool {
        self.buf.len() >= ROW_FILE_BUFFER
    }

    /// Writes what is held to the file (nothing if nothing is).
    pub fn write_out(&mut self) -> std::io::Result<()> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let r = self.file.write_all(&self.buf);
        self.buf.clear();
        // Room for one big tick (100,000 robots: 6 MB) is kept; more, left
        // by a burst, is given back.
        if self.buf.capacity() > 64 * ROW_FILE_BUFFER {
            self.buf.shrink_to(ROW_FILE_BUFFER);
        }
        r
    }
}

impl Write for RowFile {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.buf.extend_from_slice(bytes);
        Ok(bytes.len())
    }

    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.buf.extend_from_slice(bytes);
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.write_out()
    }
}

/// When the world's files are due on the disk: [`FLUSH_WALL`] after the
/// last flush, or at the first row of each new simulated second (time
/// [`FLUSH_SIM_S`] x k).
#[derive(Debug, Clone)]
pub struct FlushClock {
    wall: Duration,
    last: Instant,
    second: i64,
}

impl FlushClock {
    /// A clock whose wall period is `wall` (the world takes [`FLUSH_WALL`]
    /// less what its tick loop may hold rows before handing them over).
    pub fn new(wall: Duration) -> Self {
        Self {
            wall,
            last: Instant::now(),
            second: i64::MIN,
        }
    }

    /// The simulated second `time` lies in.
    pub fn second_of(time: f64) -> i64 {
        (time / FLUSH_SIM_S).floor() as i64
    }

    /// The files are due, rows up to simulated time `time` (if any came)
    /// being held.
    pub fn due(&self, time: Option<f64>) -> bool {
        self.last.elapsed() >= self.wall || time.is_some_and(|t| Self::second_of(t) > self.second)
    }

    /// The wall time left until the files are due by the wall clock.
    pub fn left(&self) -> Duration {
        self.wall.saturating_sub(self.last.elapsed())
    }

    /// Everything up to simulated time `time` (if known) went to the disk now.
    pub fn flushed(&mut self, time: Option<f64>) {
        self.last = Instant::now();
        if let Some(t) = time {
            self.second = self.second.max(Self::second_of(t));
        }
    }
}

/// A file that ends in a torn row: the run was cut (its writer killed)
/// while writing it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cut {
    /// The file.
    pub path: PathBuf,
    /// Its torn last line (1-based), or 0 when what was cut is not a line
    /// (a Parquet file without its footer, read from its journal).
    pub line: usize,
    /// What was read instead.
    pub detail: String,
}

impl std::fmt::Display for Cut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: ", self.path.display(), self.line)?;
        } else {
            write!(f, "{}: ", self.path.display())?;
        }
        write!(f, "the run was cut: {}", self.detail)
    }
}

/// The run was cut at `line` of `path` (a torn last row): read up to it.
pub fn torn_at(path: &Path, line: usize) -> Cut {
    Cut {
        path: path.to_path_buf(),
        line,
        detail: format!(
            "its last line is torn (the writer was killed while writing it); read up to line {}",
            line - 1
        ),
    }
}

/// `text` up to and including its last newline, and the 1-based number of
/// the torn line after it, if there is one (text after the last newline:
/// every writer ends each row with one, so that line was cut).
pub fn whole_rows(text: &str) -> (&str, Option<usize>) {
    if text.is_empty() || text.ends_with('\n') {
        return (text, None);
    }
    let whole = text.rfind('\n').map_or("", |i| &text[..=i]);
    let line = whole.bytes().filter(|&b| b == b'\n').count() + 1;
    (whole, Some(line))
}

/// Reads `path` as text and splits off a torn last row: the whole rows and
/// the [`Cut`], if any. `None` if the file does not exist.
pub fn read_whole_rows(path: &Path) -> std::io::Result<Option<(String, Option<Cut>)>> {
    let mut text = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    };
    // A torn row may end inside a multi-byte character: only the bytes up
    // to the last newline must be text.
    let cut = match text.iter().rposition(|&b| b == b'\n') {
        _ if text.is_empty() || text.ends_with(b"\n") => None,
        end => {
            let keep = end.map_or(0, |i| i + 1);
            let line = text[..keep].iter().filter(|&&b| b == b'\n').count() + 1;
            text.truncate(keep);
            Some(torn_at(path, line))
        }
    };
    let text = String::from_utf8(text).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text: {e}"),
        )
    })?;
    Ok(Some((text, cut)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("mrsim-stream-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        dir
    }

    #[test]
    fn a_row_file_writes_nothing_until_told_and_then_whole_rows() {
        let dir = temp_dir("rows");
        let path = dir.join("t.csv");
        let mut f = RowFile::create(&path, "a,b").expect("create");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "a,b\n");
        // Far more than a buffered writer's 8 KiB, in pieces that are not
        // rows: nothing reaches the file until the writer says so.
        for i in 0..10_000 {
            write!(f, "{i},").expect("write");
            writeln!(f, "{}", i * 2).expect("write");
        }
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "a,b\n");
        f.write_out().expect("out");
        let text = std::fs::read_to_string(&path).expect("read");
        assert_eq!(text.lines().count(), 10_001);
        assert!(text.ends_with("9999,19998\n"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_torn_last_line_is_split_off_and_numbered() {
        assert_eq!(whole_rows(""), ("", None));
        assert_eq!(whole_rows("h\n1\n"), ("h\n1\n", None));
        assert_eq!(whole_rows("h\n1\n2,"), ("h\n1\n", Some(3)));
        assert_eq!(whole_rows("h"), ("", Some(1)));
    }

    #[test]
    fn a_file_cut_inside_a_character_reads_up_to_its_last_whole_line() {
        let dir = temp_dir("utf8");
        let path = dir.join("e.jsonl");
        let mut bytes = "{\"a\":1}\n{\"b\":\"é".as_bytes().to_vec();
        bytes.pop();
        std::fs::write(&path, &bytes).expect("write");
        let (text, cut) = read_whole_rows(&path).expect("read").expect("exists");
        assert_eq!(text, "{\"a\":1}\n");
        let cut = cut.expect("cut");
        assert_eq!(cut.line, 2);
        assert!(
            cut.to_string().contains("e.jsonl:2: the run was cut"),
            "{cut}"
        );
        assert!(read_whole_rows(&dir.join("none")).expect("read").is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_clock_is_due_at_each_new_simulated_second() {
        let mut c = FlushClock::new(Duration::from_secs(3600));
        assert!(c.due(Some(0.0)));
        c.flushed(Some(0.0));
        assert!(!c.due(Some(0.9)));
        assert!(!c.due(None));
        assert!(c.due(Some(1.0)));
        c.flushed(Some(1.05));
        assert!(!c.due(Some(1.95)));
        assert!(c.due(Some(2.0)));
        let c = FlushClock::new(Duration::ZERO);
        assert!(c.due(None));
    }
}
