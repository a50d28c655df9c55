//! Planner diagnostics from the agent to the run folder's `diagnostics.csv`.
//!
//! Each agent hands the named per-tick values its planner reports
//! ([`Planner::diagnostics`](mrsim_planners::Planner::diagnostics)) to its
//! process's one writer thread, which appends them to the process's part
//! file in the run's folder (`out_dir` of the world's setup), so
//! hand-started agents on the same machine do it too and the command message
//! stays fixed-size. A process drives one robot (an agent process) or many
//! (a group, the in-process pool): one part file per process, not per
//! robot, so 100,000 robots in one process create one file and keep one
//! open, not 100,000. The values are handed over after the command has been
//! sent, so the control loop never waits on the disk, in batches per robot
//! (at most [`BATCH_ROWS`] rows, about half a second old, or at the first
//! tick of a new simulated second); the thread writes whatever has come, in
//! whole lines ([`RowFile`]), and then flushes, so a killed agent loses at
//! most its last half second or simulated second, whichever is shorter. A
//! planner that reports nothing leaves no file.
//!
//! When every agent has ended, [`merge`] joins the part files into
//! `diagnostics.csv` (`tick,time,robot,name,value`), sorted by tick, then by
//! robot in scenario order, each robot's values in the order its planner
//! gave them, and removes the part files. A part file holds the rows of its
//! robots as they were handed over, so the merge sorts: in memory up to
//! [`RUN_ROWS`] rows, beyond that in sorted runs on disk merged at the end
//! (memory bounded whatever the run's length). A run in which no planner
//! reported anything has no `diagnostics.csv`.
//!
//! Values are written with Rust's shortest round-trip formatting; a
//! non-finite value (`vdf`'s virtual distance to an obstacle that is no
//! threat is infinite) is written `inf`, `-inf` or `NaN`, which the report
//! reader parses and the plots leave out.

use mrsim_planners::{Diagnostic, Planner};
use mrsim_runfolder::stream::{FlushClock, RowFile};
pub use mrsim_runfolder::{DIAGNOSTICS_FILE, DIAGNOSTICS_HEADER as HEADER};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

pub use mrsim_runfolder::diagnostics_part_file as part_file_name;
use mrsim_runfolder::diagnostics_part_pid as part_file_pid;

/// One tick's values of a robot: those of its batch's flat list of values
/// after the previous row's, up to `end`.
struct Row {
    tick: u64,
    time: f64,
    end: usize,
}

/// One robot's values, handed in batches to the process's one writer
/// thread (started with the first values anywhere in the process): a
/// process driving thousands of robots (a group, the in-process pool)
/// would otherwise start a thread per robot.
pub struct DiagnosticsWriter {
    /// The process's part file in the run's folder.
    path: Arc<Path>,
    robot_id: usize,
    robot: Arc<str>,
    /// Some values were handed to the writer (the robot counts among the
    /// file's writers until it closes).
    started: bool,
    /// Rows not yet handed over: the thread gets them in batches, so it
    /// wakes about twice a second per robot rather than every tick (with
    /// hundreds of agents a wake-up per agent per tick was a context
    /// switch each). Empty, it holds no memory: a batch handed over leaves
    /// none behind (100,000 robots each keeping room for 64 rows held
    /// 250 MB).
    batch: Vec<Row>,
    /// The values of the rows of `batch`, in order (one list, not one per
    /// row: a row costs no allocation of its own).
    values: Vec<Diagnostic>,
    batch_started: Instant,
    /// Why the writer could not take the rows, told at `finish`.
    error: Option<std::io::Error>,
}

/// Rows per batch handed to the writer thread, at most.
pub const BATCH_ROWS: usize = 64;
/// Age of the oldest queued row after which the batch is handed over.
const BATCH_AGE: Duration = Duration::from_millis(500);

/// What the process's writer thread is asked.
enum Job {
    /// Append these rows of robot `robot_id` (named `robot`) to `path`;
    /// `first`: its first rows (it now writes to `path` until it closes).
    Rows {
        path: Arc<Path>,
        robot_id: usize,
        robot: Arc<str>,
        first: bool,
        rows: Vec<Row>,
        values: Vec<Diagnostic>,
    },
    /// A robot writing to `path` is done: flush it (close it when it was
    /// the last) and say whether all of it was written.
    Close {
        path: Arc<Path>,
        done: Sender<std::io::Result<()>>,
    },
}

/// The process's writer thread, started on first use.
fn writer() -> std::io::Result<Sender<Job>> {
    static WRITER: std::sync::Mutex<Option<Sender<Job>>> = std::sync::Mutex::new(None);
    let mut w = WRITER
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(tx) = w.as_ref() {
        return Ok(tx.clone());
    }
    let (tx, rx) = channel::<Job>();
    std::thread::Builder::new()
        .name("diagnostics".into())
        .spawn(move || {
            mrsim_sys::sched::background_thread();
            write_jobs(rx)
        })?;
    *w = Some(tx.clone());
    Ok(tx)
}

impl DiagnosticsWriter {
    /// A writer of robot `robot` (id `robot_id`)'s values into the
    /// process's part file in `dir`. The file is created with the first
    /// values.
    pub fn start(dir: &Path, robot_id: usize, robot: &str) -> std::io::Result<Self> {
        Ok(Self {
            path: dir.join(part_file_name(std::process::id())).into(),
            robot_id,
            robot: robot.into(),
            started: false,
            batch: Vec::new(),
            values: Vec::new(),
            batch_started: Instant::now(),
            error: None,
        })
    }

    /// Queues one tick's values, gathered already (the tests' way in; an
    /// agent calls [`DiagnosticsWriter::record`]). Nothing is queued when
    /// there are none.
    #[cfg(test)]
    fn push(&mut self, tick: u64, time: f64, values: Vec<Diagnostic>) {
        if !values.is_empty() {
            self.values.extend(values);
            self.queue(tick, time);
        }
    }

    /// Queues the values `planner` reports for its last plan, at `tick`
    /// and `time` ([`Planner::diagnostics_into`]: a planner that reports
    /// without allocating costs no allocation here either, but when a
    /// batch starts).
    #[inline]
    pub fn record(&mut self, tick: u64, time: f64, planner: &dyn Planner) {
        let before = self.values.len();
        planner.diagnostics_into(&mut self.values);
        if self.values.len() > before {
            self.queue(tick, time);
        }
    }

    /// Queues a row of the values appended to `self.values` since the last
    /// row.
    fn queue(&mut self, tick: u64, time: f64) {
        if self.batch.is_empty() {
            self.batch_started = Instant::now();
        }
        self.batch.push(Row {
            tick,
            time,
            end: self.values.len(),
        });
        let new_second = self
            .batch
            .first()
            .is_some_and(|first| FlushClock::second_of(time) > FlushClock::second_of(first.time));
        if self.batch.len() >= BATCH_ROWS || new_second || self.batch_started.elapsed() >= BATCH_AGE
        {
            self.hand_over();
        }
    }

    fn hand_over(&mut self) {
        if self.batch.is_empty() || self.error.is_some() {
            return;
        }
        let job = Job::Rows {
            path: self.path.clone(),
            robot_id: self.robot_id,
            robot: self.robot.clone(),
            first: !self.started,
            rows: std::mem::take(&mut self.batch),
            values: std::mem::take(&mut self.values),
        };
        match writer().and_then(|tx| {
            tx.send(job)
                .map_err(|_| std::io::Error::other("the diagnostics writer is gone"))
        }) {
            Ok(()) => self.started = true,
            Err(e) => self.error = Some(e),
        }
    }

    /// Writes what is queued, flushes, and closes the file (when this
    /// robot was the last of the process writing to it).
    pub fn finish(mut self) -> std::io::Result<()> {
        self.stop()
    }

    fn stop(&mut self) -> std::io::Result<()> {
        self.hand_over();
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        if !std::mem::take(&mut self.started) {
            return Ok(());
        }
        let (done, answer) = channel();
        writer()?
            .send(Job::Close {
                path: self.path.clone(),
                done,
            })
            .map_err(|_| std::io::Error::other("the diagnostics writer is gone"))?;
        answer
            .recv()
            .unwrap_or_else(|_| Err(std::io::Error::other("the diagnostics writer is gone")))
    }
}

impl Drop for DiagnosticsWriter {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}

/// A part file the writer thread has open, and the robots writing to it.
struct Open {
    file: RowFile,
    robots: usize,
}

/// The writer thread: blocks until a job comes (a robot's batch at most
/// about twice a second, see `BATCH_AGE`), does it and every job already
/// queued, then flushes, so it never wakes on a timer: with hundreds of
/// agents, each one's writer waking once a second, all at about the same
/// moment, stole a few milliseconds of both cores at once and made bursts
/// of deadline misses every second. A write error of a part file is told
/// to every robot of it that closes afterwards.
fn write_jobs(rx: Receiver<Job>) {
    use std::collections::{HashMap, HashSet};
    let mut open: HashMap<Arc<Path>, Open> = HashMap::new();
    let mut created: HashSet<Arc<Path>> = HashSet::new();
    let mut failed: HashMap<Arc<Path>, (std::io::ErrorKind, String)> = HashMap::new();
    let mut line = Vec::new();
    let mut times = Times::default();
    let fail = |failed: &mut HashMap<Arc<Path>, _>, path: &Arc<Path>, e: std::io::Error| {
        failed.insert(path.clone(), (e.kind(), e.to_string()));
    };
    while let Ok(first) = rx.recv() {
        for job in std::iter::once(first).chain(std::iter::from_fn(|| rx.try_recv().ok())) {
            match job {
                Job::Rows {
                    path,
                    robot_id,
                    robot,
                    first,
                    rows,
                    values,
                } => {
                    if failed.contains_key(&path) {
                        continue;
                    }
                    let w = match open.entry(path.clone()) {
                        std::collections::hash_map::Entry::Occupied(o) => o.into_mut(),
                        std::collections::hash_map::Entry::Vacant(v) => {
                            let file = if created.insert(path.clone()) {
                                RowFile::create(&path, "")
                            } else {
                                RowFile::append(&path)
                            };
                            match file {
                                Ok(file) => v.insert(Open { file, robots: 0 }),
                                Err(e) => {
                                    fail(&mut failed, &path, e);
                                    continue;
                                }
                            }
                        }
                    };
                    w.robots += usize::from(first);
                    let batch = Batch {
                        robot_id,
                        robot: &robot,
                        rows: &rows,
                        values: &values,
                    };
                    if let Err(e) = batch.write(&mut w.file, &mut line, &mut times) {
                        open.remove(&path);
                        fail(&mut failed, &path, e);
                    }
                }
                Job::Close { path, done } => {
                    let mut flushed = Ok(());
                    if let Some(w) = open.get_mut(&path) {
                        flushed = w.file.flush();
                        w.robots = w.robots.saturating_sub(1);
                        if w.robots == 0 || flushed.is_err() {
                            open.remove(&path);
                        }
                    }
                    if let Err(e) = flushed {
                        fail(&mut failed, &path, e);
                    }
                    let told = failed.get(&path).map_or(Ok(()), |(kind, what)| {
                        Err(std::io::Error::new(*kind, what.clone()))
                    });
                    let _ = done.send(told);
                }
            }
        }
        let mut broken = Vec::new();
        for (path, w) in &mut open {
            if let Err(e) = w.file.flush() {
                broken.push((path.clone(), e));
            }
        }
        for (path, e) in broken {
            open.remove(&path);
            fail(&mut failed, &path, e);
        }
    }
}

/// One robot's batch of rows as the writer thread gets it.
struct Batch<'a> {
    robot_id: usize,
    robot: &'a str,
    rows: &'a [Row],
    values: &'a [Diagnostic],
}

impl Batch<'_> {
    /// Appends the batch's lines (`id,tick,time,robot,name,value`) to `w`,
    /// `line` being room for one line. The numbers are written without
    /// `format!` where that is exact: the integers, and a value that is a
    /// whole number (most are counts); the time with six decimals is
    /// formatted once per tick (`times`).
    fn write(&self, w: &mut RowFile, line: &mut Vec<u8>, times: &mut Times) -> std::io::Result<()> {
        let mut first = 0;
        for row in self.rows {
            // The row's start (`id,tick,time,robot,`) is written once for
            // all its values.
            line.clear();
            push_u64(line, self.robot_id as u64);
            line.push(b',');
            push_u64(line, row.tick);
            line.push(b',');
            line.extend_from_slice(times.fixed6(row.tick, row.time));
            line.push(b',');
            line.extend_from_slice(self.robot.as_bytes());
            line.push(b',');
            let start = line.len();
            let values = self.values.get(first..row.end).unwrap_or_default();
            first = row.end;
            for d in values {
                line.truncate(start);
                line.extend_from_slice(d.name.as_bytes());
                line.push(b',');
                push_value(line, d.value);
                line.push(b'\n');
                w.write_all(line)?;
            }
        }
        Ok(())
    }
}

/// The times of recent ticks formatted with six decimals (`{:.6}`), by
/// tick: every robot's row of a tick has the same time.
#[derive(Default)]
struct Times {
    /// Slot `tick % TIME_SLOTS`: the time's bits and its text.
    slots: Vec<Option<(u64, Vec<u8>)>>,
}

/// Ticks whose times [`Times`] keeps (a batch spans at most
/// [`BATCH_ROWS`] ticks).
const TIME_SLOTS: usize = 2 * BATCH_ROWS;

impl Times {
    /// `time` formatted as `{:.6}` formats it.
    fn fixed6(&mut self, tick: u64, time: f64) -> &[u8] {
        use std::io::Write as _;
        if self.slots.is_empty() {
            self.slots.resize(TIME_SLOTS, None);
        }
        let slot = &mut self.slots[(tick % TIME_SLOTS as u64) as usize];
        let bits = time.to_bits();
        if slot.as_ref().is_none_or(|(b, _)| *b != bits) {
            let mut text = slot.take().map(|(_, t)| t).unwrap_or_default();
            text.clear();
            // Writing into a Vec cannot fail.
            let _ = write!(text, "{time:.6}");
            *slot = Some((bits, text));
        }
        slot.as_ref().map_or(&[], |(_, t)| t.as_slice())
    }
}

/// Appends `n` in decimal.
fn push_u64(out: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[i..]);
}

/// Appends `v` as Rust's `{}` writes it (the shortest text that reads back
/// as `v`): a whole number below 2^53 in magnitude is its integer's digits
/// (`4.0` is `4`, as `{}` writes it), anything else goes through `{}`.
fn push_value(out: &mut Vec<u8>, v: f64) {
    use std::io::Write as _;
    const EXACT: f64 = (1u64 << 53) as f64;
    if v.fract() == 0.0 && v.abs() < EXACT && !(v == 0.0 && v.is_sign_negative()) {
        if v < 0.0 {
            out.push(b'-');
        }
        push_u64(out, v.abs() as u64);
    } else {
        // Writing into a Vec cannot fail.
        let _ = write!(out, "{v}");
    }
}

/// What [`merge`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MergeSummary {
    /// The merged file, `None` when no agent wrote any value.
    pub file: Option<PathBuf>,
    /// Rows written.
    pub rows: u64,
    /// Part files merged (and removed).
    pub parts: usize,
    /// Lines left out: an unfinished last line of an agent that was killed
    /// mid-write, or a line that is not a row.
    pub skipped: u64,
}

/// Rows the merge sorts in memory at once; more are sorted in runs of
/// this many, written to temporary files and merged (about 20 MB).
pub const RUN_ROWS: usize = 1 << 18;

/// A row's place in the merged file: by tick, then robot id, then where it
/// was written (part file, line), which keeps each robot's rows in the
/// order its planner gave them.
type Key = (u64, u64, u64, u64);

/// The key of a part file's line (`id,tick,time,robot,name,value`, without
/// its newline) and where the row (all but `id,`) starts, or `None` if it
/// is not a row.
fn part_key(part: u64, seq: u64, row: &str) -> Option<(Key, usize)> {
    let (robot, line) = row.split_once(',')?;
    let robot = robot.parse().ok()?;
    let tick = line.split(',').next()?.parse().ok()?;
    (line.bytes().filter(|&b| b == b',').count() == 4)
        .then_some(((tick, robot, part, seq), row.len() - line.len()))
}

/// Rows sorted in memory: their keys and where their text is in `text`.
#[derive(Default)]
struct Run {
    keys: Vec<(Key, usize, usize)>,
    text: String,
}

impl Run {
    fn push(&mut self, key: Key, row: &str) {
        let start = self.text.len();
        self.text.push_str(row);
        self.keys.push((key, start, row.len()));
    }

    fn len(&self) -> usize {
        self.keys.len()
    }

    fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    fn sort(&mut self) {
        // Keys are unique (part and line), so the order is total.
        self.keys.sort_unstable_by_key(|k| k.0);
    }

    fn row(&self, i: usize) -> (Key, &str) {
        let (key, start, len) = self.keys[i];
        (key, self.text.get(start..start + len).unwrap_or_default())
    }

    /// Writes the sorted rows as a run on disk: each its key's four
    /// numbers and its text's length (little-endian), then the text.
    fn write_to(&self, path: &Path) -> std::io::Result<()> {
        let mut w = BufWriter::with_capacity(1 << 16, File::create(path)?);
        for i in 0..self.len() {
            let ((tick, robot, part, seq), row) = self.row(i);
            for n in [tick, robot, part, seq] {
                w.write_all(&n.to_le_bytes())?;
            }
            w.write_all(&(row.len() as u64).to_le_bytes())?;
            w.write_all(row.as_bytes())?;
        }
        w.flush()
    }

    fn clear(&mut self) {
        self.keys.clear();
        self.text.clear();
    }
}

/// The next row of a run on disk ([`Run::write_to`]) into `row`, with its
/// key; `None` at its end.
fn next_run_row(r: &mut impl BufRead, row: &mut Vec<u8>) -> std::io::Result<Option<Key>> {
    if r.fill_buf()?.is_empty() {
        return Ok(None);
    }
    let mut head = [0u8; 40];
    r.read_exact(&mut head)?;
    let n = |k: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&head[8 * k..8 * k + 8]);
        u64::from_le_bytes(b)
    };
    let len = usize::try_from(n(4))
        .map_err(|_| std::io::Error::other("a sorted run of diagnostics is malformed"))?;
    row.resize(len, 0);
    r.read_exact(row)?;
    Ok(Some((n(0), n(1), n(2), n(3))))
}

/// Reads the next line of `r` without its newline into `line`; `false` at
/// the end. A last line without its newline (an agent killed mid-write)
/// is counted in `skipped` and left out.
fn next_line(r: &mut impl BufRead, line: &mut String, skipped: &mut u64) -> std::io::Result<bool> {
    loop {
        line.clear();
        if r.read_line(line)? == 0 {
            return Ok(false);
        }
        if line.ends_with('\n') {
            line.pop();
            return Ok(true);
        }
        *skipped += 1;
    }
}

/// Joins the agents' part files in `dir` into `diagnostics.csv`, sorted by
/// tick, then robot id (scenario order), each robot's rows in their own
/// order, and removes the part files. Call it once every agent of the run
/// has ended. Without part files nothing is written.
pub fn merge(dir: &Path) -> std::io::Result<MergeSummary> {
    merge_in_runs(dir, RUN_ROWS)
}

/// [`merge`], sorting at most `run_rows` rows in memory at once.
fn merge_in_runs(dir: &Path, run_rows: usize) -> std::io::Result<MergeSummary> {
    // By process id: an agent's earlier process first, as a rule.
    let mut files: Vec<(u32, PathBuf)> = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        if let Some(pid) = entry.file_name().to_str().and_then(part_file_pid) {
            files.push((pid, entry.path()));
        }
    }
    let mut summary = MergeSummary {
        parts: files.len(),
        ..Default::default()
    };
    if files.is_empty() {
        return Ok(summary);
    }
    files.sort();
    let run_rows = run_rows.max(1);
    let out_path = dir.join(DIAGNOSTICS_FILE);
    let tmp_path = dir.join(format!("{DIAGNOSTICS_FILE}.tmp"));
    let run_path = |k: usize| dir.join(format!("{DIAGNOSTICS_FILE}.run{k}"));

    // Sorted runs of at most `run_rows` rows; the last stays in memory.
    let mut runs = 0;
    let mut memory = Run::default();
    let mut line = String::new();
    for (part, (_, path)) in files.iter().enumerate() {
        let mut r = BufReader::with_capacity(1 << 16, File::open(path)?);
        let mut seq = 0;
        while next_line(&mut r, &mut line, &mut summary.skipped)? {
            match part_key(part as u64, seq, &line) {
                Some((key, start)) => memory.push(key, &line[start..]),
                None => summary.skipped += 1,
            }
            seq += 1;
            if memory.len() >= run_rows {
                memory.sort();
                memory.write_to(&run_path(runs))?;
                runs += 1;
                memory.clear();
            }
        }
    }
    memory.sort();

    let mut out = BufWriter::with_capacity(1 << 16, File::create(&tmp_path)?);
    writeln!(out, "{HEADER}")?;
    let mut emit = |row: &[u8], out: &mut BufWriter<File>| -> std::io::Result<()> {
        out.write_all(row)?;
        out.write_all(b"\n")?;
        summary.rows += 1;
        Ok(())
    };
    if runs == 0 {
        for i in 0..memory.len() {
            emit(memory.row(i).1.as_bytes(), &mut out)?;
        }
    } else {
        // A k-way merge of the runs on disk (each with its current row)
        // and the one in memory (its next row's index).
        let mut readers = Vec::with_capacity(runs);
        let mut current = vec![Vec::new(); runs];
        let mut heap = BinaryHeap::new();
        for (k, row) in current.iter_mut().enumerate() {
            let mut r = BufReader::with_capacity(1 << 16, File::open(run_path(k))?);
            if let Some(key) = next_run_row(&mut r, row)? {
                heap.push(Reverse((key, k)));
            }
            readers.push(r);
        }
        let mut next_memory = 0;
        if !memory.is_empty() {
            heap.push(Reverse((memory.row(0).0, runs)));
        }
        while let Some(Reverse((_, k))) = heap.pop() {
            if k == runs {
                emit(memory.row(next_memory).1.as_bytes(), &mut out)?;
                next_memory += 1;
                if next_memory < memory.len() {
                    heap.push(Reverse((memory.row(next_memory).0, runs)));
                }
            } else {
                emit(&current[k], &mut out)?;
                if let Some(key) = next_run_row(&mut readers[k], &mut current[k])? {
                    heap.push(Reverse((key, k)));
                }
            }
        }
        drop(readers);
        for k in 0..runs {
            std::fs::remove_file(run_path(k))?;
        }
    }
    out.flush()?;
    drop(out);
    if summary.rows == 0 {
        std::fs::remove_file(&tmp_path)?;
    } else {
        std::fs::rename(&tmp_path, &out_path)?;
        summary.file = Some(out_path);
    }
    for (_, path) in &files {
        std::fs::remove_file(path)?;
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of the files left in `dir`.
    fn files_in(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .expect("dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect()
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "mrsim-diag-{tag}-{}-{:?}",
            std::process::id(),
            std::thread::current().id()
        ));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    fn d(name: &str, value: f64) -> Diagnostic {
        Diagnostic {
            name: name.to_string().into(),
            value,
        }
    }

    #[test]
    fn values_and_times_are_written_as_rusts_own_formatting_writes_them() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            4.0,
            10.0,
            12345.0,
            -987654321.0,
            9007199254740991.0,
            9007199254740992.0,
            -9007199254740992.0,
            1e300,
            0.5,
            -0.25,
            0.1,
            1.0 / 3.0,
            2.5e-8,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for v in values {
            let mut out = Vec::new();
            push_value(&mut out, v);
            assert_eq!(String::from_utf8(out).expect("ascii"), format!("{v}"));
        }
        for n in [0u64, 7, 10, 99, 100, 123456789, u64::MAX] {
            let mut out = Vec::new();
            push_u64(&mut out, n);
            assert_eq!(String::from_utf8(out).expect("ascii"), n.to_string());
        }
        let mut times = Times::default();
        // Ticks that share a slot, a tick seen again with another time,
        // and times that round at the sixth decimal.
        for (tick, time) in [
            (0, 0.0),
            (1, 0.1),
            (1 + TIME_SLOTS as u64, 12.8000005),
            (1, 0.1),
            (2, 0.2),
            (2, 0.0000015),
            (3, 1e20),
        ] {
            assert_eq!(
                String::from_utf8(times.fixed6(tick, time).to_vec()).expect("ascii"),
                format!("{time:.6}")
            );
        }
    }

    #[test]
    fn a_planners_values_are_recorded_as_it_reports_them() {
        struct Two;
        impl Planner for Two {
            fn plan(&mut self, _: &mrsim_planners::Observation) -> mrsim_planners::Command {
                mrsim_planners::Command::Velocity(mrsim_planners::Vec2::zeros())
            }
            fn diagnostics(&self) -> Vec<Diagnostic> {
                vec![d("lines", 3.0), d("ratio", 0.1)]
            }
        }
        struct Silent;
        impl Planner for Silent {
            fn plan(&mut self, _: &mrsim_planners::Observation) -> mrsim_planners::Command {
                mrsim_planners::Command::Velocity(mrsim_planners::Vec2::zeros())
            }
        }
        let dir = temp_dir("record");
        let mut w = DiagnosticsWriter::start(&dir, 2, "b").expect("writer");
        for t in 0..3 {
            w.record(t, t as f64 * 0.1, &Two);
            w.record(t, t as f64 * 0.1, &Silent);
        }
        w.finish().expect("flushed");
        let s = merge(&dir).expect("merge");
        assert_eq!((s.rows, s.skipped), (6, 0));
        let text = std::fs::read_to_string(dir.join(DIAGNOSTICS_FILE)).expect("merged");
        assert_eq!(
            text,
            format!(
                "{HEADER}\n0,0.000000,b,lines,3\n0,0.000000,b,ratio,0.1\n\
                 1,0.100000,b,lines,3\n1,0.100000,b,ratio,0.1\n\
                 2,0.200000,b,lines,3\n2,0.200000,b,ratio,0.1\n"
            )
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn part_file_names_give_their_process_and_other_files_none() {
        assert_eq!(part_file_pid(&part_file_name(4567)), Some(4567));
        assert_eq!(part_file_pid("diagnostics.csv"), None);
        assert_eq!(part_file_pid("diagnostics-x.part"), None);
        assert_eq!(part_file_pid("diagnostics.csv.run0"), None);
        assert_eq!(part_file_pid("trajectory.csv"), None);
    }

    /// Robots `0..n` of one process, each writing `ticks` ticks of two
    /// values, in an order that is not the merged file's.
    fn write_robots(dir: &Path, n: usize, ticks: u64) {
        let mut writers: Vec<_> = (0..n)
            .rev()
            .map(|id| {
                let w = DiagnosticsWriter::start(dir, id, &format!("r{id}")).expect("writer");
                (id, w)
            })
            .collect();
        for t in 0..ticks {
            for (id, w) in &mut writers {
                w.push(
                    t,
                    t as f64 * 0.1,
                    vec![
                        d("speed", (t * 100 + *id as u64) as f64),
                        d("lines", *id as f64),
                    ],
                );
            }
        }
        for (_, w) in writers {
            w.finish().expect("flushed");
        }
    }

    #[test]
    fn many_robots_of_one_process_write_one_part_file() {
        let dir = temp_dir("one-part");
        write_robots(&dir, 50, 3);
        let names: Vec<String> = std::fs::read_dir(&dir)
            .expect("dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec![part_file_name(std::process::id())]);
        let s = merge(&dir).expect("merge");
        assert_eq!((s.rows, s.parts, s.skipped), (300, 1, 0));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn merging_in_sorted_runs_on_disk_gives_the_file_sorting_in_memory_gives() {
        let (small, large) = (temp_dir("runs-small"), temp_dir("runs-large"));
        for dir in [&small, &large] {
            write_robots(dir, 7, 5);
        }
        // An earlier process's part (an agent that restarted), written by
        // hand: its rows come before the later process's at a tick.
        for dir in [&small, &large] {
            std::fs::write(
                dir.join(part_file_name(0)),
                "3,2,0.200000,r3,extra,1\n0,4,0.400000,r0,extra,2\n",
            )
            .expect("write part");
        }
        let a = merge_in_runs(&small, 3).expect("merge in runs");
        let b = merge_in_runs(&large, 1 << 20).expect("merge in memory");
        assert_eq!(a.rows, 7 * 5 * 2 + 2);
        assert_eq!(a.rows, b.rows);
        let text = std::fs::read_to_string(small.join(DIAGNOSTICS_FILE)).expect("merged");
        assert_eq!(
            text,
            std::fs::read_to_string(large.join(DIAGNOSTICS_FILE)).expect("merged")
        );
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[1], "0,0.000000,r0,speed,0");
        assert_eq!(lines[2], "0,0.000000,r0,lines,0");
        assert_eq!(lines[3], "0,0.000000,r1,speed,1");
        // Tick 2: robot 3's values of the earlier process, then its own.
        let at = lines
            .iter()
            .position(|l| *l == "2,0.200000,r3,extra,1")
            .expect("robot 3 at tick 2");
        assert_eq!(lines[at - 1], "2,0.200000,r2,lines,2");
        assert_eq!(lines[at + 1], "2,0.200000,r3,speed,203");
        assert_eq!(lines[at + 2], "2,0.200000,r3,lines,3");
        assert_eq!(lines[at + 3], "2,0.200000,r4,speed,204");
        // Only the merged file is left: no part, no run.
        assert_eq!(files_in(&small), vec![DIAGNOSTICS_FILE.to_string()]);
        for dir in [small, large] {
            let _ = std::fs::remove_dir_all(&dir);
        }
    }

    #[test]
    fn agents_rows_merge_sorted_by_tick_then_robot_and_the_parts_are_removed() {
        let dir = temp_dir("merge");
        // Robot 1 writes first, robot 0 second; ticks interleave.
        for (id, name, ticks) in [(1usize, "b", [0u64, 1, 2]), (0, "a", [0, 1, 2])] {
            let mut w = DiagnosticsWriter::start(&dir, id, name).expect("writer");
            for t in ticks {
                w.push(
                    t,
                    t as f64 * 0.1,
                    vec![d("speed", t as f64), d("vd_3", f64::INFINITY)],
                );
            }
            w.finish().expect("flushed");
        }
        let s = merge(&dir).expect("merge");
        assert_eq!(s.rows, 12);
        assert_eq!(s.parts, 1);
        let text = std::fs::read_to_string(dir.join(DIAGNOSTICS_FILE)).expect("merged");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], HEADER);
        assert_eq!(lines[1], "0,0.000000,a,speed,0");
        assert_eq!(lines[2], "0,0.000000,a,vd_3,inf");
        assert_eq!(lines[3], "0,0.000000,b,speed,0");
        assert_eq!(lines[5], "1,0.100000,a,speed,1");
        assert_eq!(lines.len(), 13);
        assert_eq!(files_in(&dir), vec![DIAGNOSTICS_FILE.to_string()]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_planner_that_reports_nothing_leaves_no_file_and_no_merged_file() {
        let dir = temp_dir("empty");
        let mut w = DiagnosticsWriter::start(&dir, 0, "a").expect("writer");
        w.push(0, 0.0, Vec::new());
        w.finish().expect("flushed");
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 0);
        let s = merge(&dir).expect("merge");
        assert_eq!(s.file, None);
        assert!(!dir.join(DIAGNOSTICS_FILE).exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_cut_last_line_of_a_killed_agent_is_left_out() {
        let dir = temp_dir("cut");
        std::fs::write(
            dir.join(part_file_name(1)),
            "0,0,0.000000,a,speed,0.2\n0,1,0.100000,a,speed,0.3\n0,2,0.2000",
        )
        .expect("write part");
        let s = merge(&dir).expect("merge");
        assert_eq!((s.rows, s.skipped), (2, 1));
        let text = std::fs::read_to_string(dir.join(DIAGNOSTICS_FILE)).expect("merged");
        assert_eq!(
            text,
            format!("{HEADER}\n0,0.000000,a,speed,0.2\n1,0.100000,a,speed,0.3\n")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
