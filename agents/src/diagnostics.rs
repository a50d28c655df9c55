//! Planner diagnostics from the agent to the run folder's `diagnostics.csv`.
//!
//! Each agent writes the named per-tick values its planner reports
//! ([`Planner::diagnostics`](mrsim_planners::Planner::diagnostics)) into its
//! own part file in the run's folder (`out_dir` of the world's setup), so
//! hand-started agents on the same machine do it too and the command message
//! stays fixed-size. The values are handed to a writer thread after the
//! command has been sent, so the control loop never waits on the disk; the
//! thread flushes about once a second. A planner that reports nothing leaves
//! no file.
//!
//! When every agent has ended, [`merge`] joins the part files into
//! `diagnostics.csv` (`tick,time,robot,name,value`), sorted by tick, then by
//! robot in scenario order, each robot's values in the order its planner
//! gave them, and removes the part files. A run in which no planner reported
//! anything has no `diagnostics.csv`.
//!
//! Values are written with Rust's shortest round-trip formatting; a
//! non-finite value (`vdf`'s virtual distance to an obstacle that is no
//! threat is infinite) is written `inf`, `-inf` or `NaN`, which the report
//! reader parses and the plots leave out.

use mrsim_planners::Diagnostic;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

/// The merged file's name in a run folder.
pub const DIAGNOSTICS_FILE: &str = "diagnostics.csv";
/// Its header.
pub const HEADER: &str = "tick,time,robot,name,value";
const PART_PREFIX: &str = "diagnostics-";
const PART_SUFFIX: &str = ".part";

/// Name of the part file of robot `robot_id` written by process `pid` (one
/// per process, so an agent that restarts does not overwrite its
/// predecessor's values).
pub fn part_file_name(robot_id: usize, pid: u32) -> String {
    format!("{PART_PREFIX}{robot_id}-{pid}{PART_SUFFIX}")
}

/// The robot id of a part file's name, or `None` for any other file.
fn part_file_robot(name: &str) -> Option<usize> {
    let rest = name.strip_prefix(PART_PREFIX)?.strip_suffix(PART_SUFFIX)?;
    let (id, pid) = rest.split_once('-')?;
    pid.parse::<u32>().ok()?;
    id.parse().ok()
}

struct Row {
    tick: u64,
    time: f64,
    values: Vec<Diagnostic>,
}

/// One robot's part file, written by the process's one writer thread
/// (started with the first values anywhere in the process): a process
/// driving thousands of robots (a group, the in-process pool) would
/// otherwise start a thread per robot.
pub struct DiagnosticsWriter {
    path: PathBuf,
    robot: std::sync::Arc<str>,
    /// Some values were handed to the writer (the file exists).
    started: bool,
    /// Rows not yet handed over: the thread gets them in batches, so it
    /// wakes about twice a second per robot rather than every tick (with
    /// hundreds of agents a wake-up per agent per tick was a context
    /// switch each).
    batch: Vec<Row>,
    batch_started: Instant,
    /// Why the writer could not take the rows, told at `finish`.
    error: Option<std::io::Error>,
}

/// Rows per batch handed to the writer thread, at most.
const BATCH_ROWS: usize = 64;
/// Age of the oldest queued row after which the batch is handed over.
const BATCH_AGE: Duration = Duration::from_millis(500);
/// Part files the writer keeps open at most (more are closed and opened
/// again to append): far below any limit on open files.
const OPEN_FILES: usize = 256;

/// What the process's writer thread is asked.
enum Job {
    /// Append these rows of `robot` to `path` (created by the first).
    Rows {
        path: PathBuf,
        robot: std::sync::Arc<str>,
        rows: Vec<Row>,
    },
    /// Close `path` and say whether all of it was written.
    Close {
        path: PathBuf,
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
    /// A writer of robot `robot` (id `robot_id`)'s values into its part
    /// file in `dir`. The file is created with the first values.
    pub fn start(dir: &Path, robot_id: usize, robot: &str) -> std::io::Result<Self> {
        Ok(Self {
            path: dir.join(part_file_name(robot_id, std::process::id())),
            robot: robot.into(),
            started: false,
            batch: Vec::new(),
            batch_started: Instant::now(),
            error: None,
        })
    }

    /// Queues one tick's values (nothing is queued when there are none:
    /// a planner that reports nothing costs its agent no call here).
    #[inline]
    pub fn push(&mut self, tick: u64, time: f64, values: Vec<Diagnostic>) {
        if !values.is_empty() {
            self.queue(tick, time, values);
        }
    }

    fn queue(&mut self, tick: u64, time: f64, values: Vec<Diagnostic>) {
        if self.batch.is_empty() {
            self.batch_started = Instant::now();
        }
        self.batch.push(Row { tick, time, values });
        if self.batch.len() >= BATCH_ROWS || self.batch_started.elapsed() >= BATCH_AGE {
            self.hand_over();
        }
    }

    fn hand_over(&mut self) {
        if self.batch.is_empty() || self.error.is_some() {
            return;
        }
        let rows = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH_ROWS));
        let job = Job::Rows {
            path: self.path.clone(),
            robot: self.robot.clone(),
            rows,
        };
        match writer().and_then(|tx| {
            tx.send(job)
                .map_err(|_| std::io::Error::other("the diagnostics writer is gone"))
        }) {
            Ok(()) => self.started = true,
            Err(e) => self.error = Some(e),
        }
    }

    /// Writes what is queued, flushes, and closes the file.
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

/// The writer thread: blocks until a job comes (a robot's batch at most
/// about twice a second, see `BATCH_AGE`) and flushes after each, so it
/// never wakes on a timer: with hundreds of agents, each one's writer
/// waking once a second, all at about the same moment, stole a few
/// milliseconds of both cores at once and made bursts of deadline misses
/// every second.
fn write_jobs(rx: Receiver<Job>) {
    use std::collections::{HashMap, HashSet};
    let mut open: HashMap<PathBuf, BufWriter<File>> = HashMap::new();
    let mut created: HashSet<PathBuf> = HashSet::new();
    let mut failed: HashMap<PathBuf, std::io::Error> = HashMap::new();
    for job in rx {
        match job {
            Job::Rows { path, robot, rows } => {
                if failed.contains_key(&path) {
                    continue;
                }
                if !open.contains_key(&path) && open.len() >= OPEN_FILES {
                    for (p, mut w) in open.drain() {
                        if let Err(e) = w.flush() {
                            failed.insert(p, e);
                        }
                    }
                }
                let w = match open.entry(path.clone()) {
                    std::collections::hash_map::Entry::Occupied(o) => o.into_mut(),
                    std::collections::hash_map::Entry::Vacant(v) => {
                        let file = if created.insert(path.clone()) {
                            File::create(&path)
                        } else {
                            std::fs::OpenOptions::new().append(true).open(&path)
                        };
                        match file {
                            Ok(f) => v.insert(BufWriter::with_capacity(1 << 14, f)),
                            Err(e) => {
                                failed.insert(path, e);
                                continue;
                            }
                        }
                    }
                };
                if let Err(e) = write_rows(w, &robot, &rows) {
                    open.remove(&path);
                    failed.insert(path, e);
                }
            }
            Job::Close { path, done } => {
                let flushed = open.remove(&path).map_or(Ok(()), |mut w| w.flush());
                created.remove(&path);
                let _ = done.send(failed.remove(&path).map_or(flushed, Err));
            }
        }
    }
}

fn write_rows(w: &mut BufWriter<File>, robot: &str, rows: &[Row]) -> std::io::Result<()> {
    for row in rows {
        for d in &row.values {
            writeln!(
                w,
                "{},{:.6},{robot},{},{}",
                row.tick, row.time, d.name, d.value
            )?;
        }
    }
    w.flush()
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

struct Part {
    robot: usize,
    reader: BufReader<File>,
}

impl Part {
    /// The next well-formed row and its tick. A last line without its
    /// newline (the agent was killed mid-write) and a line that is not a
    /// row are counted in `skipped` and left out.
    fn next_row(&mut self, skipped: &mut u64) -> std::io::Result<Option<(u64, String)>> {
        loop {
            let mut line = String::new();
            if self.reader.read_line(&mut line)? == 0 {
                return Ok(None);
            }
            let Some(row) = line.strip_suffix('\n') else {
                *skipped += 1;
                continue;
            };
            let tick = row.split(',').next().and_then(|t| t.parse::<u64>().ok());
            match tick {
                Some(tick) if row.split(',').count() == 5 => {
                    return Ok(Some((tick, row.to_string())));
                }
                _ => *skipped += 1,
            }
        }
    }
}

/// Joins the agents' part files in `dir` into `diagnostics.csv`, sorted by
/// tick, then robot id (scenario order), each agent's rows in their own
/// order, and removes the part files. Call it once every agent of the run
/// has ended. Each part file is already in tick order, so this is a k-way
/// merge that holds one row per file in memory. Without part files nothing
/// is written.
pub fn merge(dir: &Path) -> std::io::Result<MergeSummary> {
    let mut files: Vec<(usize, PathBuf)> = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        if let Some(robot) = entry.file_name().to_str().and_then(part_file_robot) {
            files.push((robot, entry.path()));
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
    let mut parts = Vec::with_capacity(files.len());
    for (robot, path) in &files {
        parts.push(Part {
            robot: *robot,
            reader: BufReader::new(File::open(path)?),
        });
    }

    // Heap of (tick, robot, part, sequence) -> the part's current line.
    let mut heads: Vec<Option<String>> = vec![None; parts.len()];
    let mut heap = BinaryHeap::new();
    let mut seq = 0u64;
    for (k, part) in parts.iter_mut().enumerate() {
        if let Some((tick, line)) = part.next_row(&mut summary.skipped)? {
            heads[k] = Some(line);
            heap.push(Reverse((tick, part.robot, k, seq)));
            seq += 1;
        }
    }
    let out_path = dir.join(DIAGNOSTICS_FILE);
    let tmp_path = dir.join(format!("{DIAGNOSTICS_FILE}.tmp"));
    let mut out = BufWriter::with_capacity(1 << 16, File::create(&tmp_path)?);
    writeln!(out, "{HEADER}")?;
    while let Some(Reverse((_, robot, k, _))) = heap.pop() {
        let part = &mut parts[k];
        let next = part.next_row(&mut summary.skipped)?;
        if let Some(line) = heads[k].take() {
            out.write_all(line.as_bytes())?;
            out.write_all(b"\n")?;
            summary.rows += 1;
        }
        if let Some((tick, line)) = next {
            heads[k] = Some(line);
            heap.push(Reverse((tick, robot, k, seq)));
            seq += 1;
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
            name: name.into(),
            value,
        }
    }

    #[test]
    fn part_file_names_round_trip_and_other_files_are_not_parts() {
        assert_eq!(part_file_robot(&part_file_name(12, 4567)), Some(12));
        assert_eq!(part_file_robot("diagnostics.csv"), None);
        assert_eq!(part_file_robot("diagnostics-x-1.part"), None);
        assert_eq!(part_file_robot("trajectory.csv"), None);
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
        assert_eq!(s.parts, 2);
        let text = std::fs::read_to_string(dir.join(DIAGNOSTICS_FILE)).expect("merged");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], HEADER);
        assert_eq!(lines[1], "0,0.000000,a,speed,0");
        assert_eq!(lines[2], "0,0.000000,a,vd_3,inf");
        assert_eq!(lines[3], "0,0.000000,b,speed,0");
        assert_eq!(lines[5], "1,0.100000,a,speed,1");
        assert_eq!(lines.len(), 13);
        let left: Vec<_> = std::fs::read_dir(&dir)
            .expect("dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(left, vec![DIAGNOSTICS_FILE.to_string()]);
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
            dir.join(part_file_name(0, 1)),
            "0,0.000000,a,speed,0.2\n1,0.100000,a,speed,0.3\n2,0.2000",
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
