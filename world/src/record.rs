//! Recording off the tick loop: the trajectory, events.jsonl, timing.csv,
//! scan.csv and encounters.csv are written by their own thread, fed
//! through a crossbeam channel, so the tick loop never waits on the disk.
//! Every file is a [`RowFile`]: rows gather in memory, whole, and the
//! thread puts all the files on the disk together (timing, events,
//! encounters, scans, then the trajectory) at the first tick of every
//! simulated second, after [`FLUSH_WALL`] less [`BATCH_AGE`] of wall time
//! (also when no tick comes), and when a buffer is full; so a process
//! killed loses at most the rows of the last simulated second or wall
//! second, whichever is shorter, and never leaves a partial row but one
//! cut inside the kernel's `write` (which the readers leave out).
//!
//! Ticks go to the thread in batches of up to [`BATCH_TICKS`] (or whatever
//! is pending after [`BATCH_AGE`], or at once at the first tick of a
//! simulated second), so the loop does not pay a futex wake of the thread
//! each tick. Batch buffers are returned to the loop for reuse.
//!
//! The trajectory is trajectory.csv, trajectory.parquet or nothing, of
//! every tick or every K-th (`[output]`); encounters.csv gets each
//! encounter once it has ended (and those still going on at the end); the
//! same thread
//! computes the robots' motion metrics from every tick's states whatever
//! it writes ([`crate::tracking`]) and hands them back at the end.

use crate::batch::{Batch, Batcher};
use crate::tracking::Tracker;
use crossbeam::channel::{RecvTimeoutError, bounded, unbounded};
use mrsim_proto::{BodyState, body_kind};
use mrsim_runfolder::encounters::{ENCOUNTERS_HEADER, rows as encounter_rows};
use mrsim_runfolder::stream::{FLUSH_WALL, FlushClock, RowFile};
use mrsim_runfolder::timing::{Status, TimingSink};
use mrsim_runfolder::trajectory::{BodyCells, ParquetTrajectoryWriter};
use mrsim_runfolder::{TRAJECTORY_FILE, TRAJECTORY_JOURNAL_FILE, TRAJECTORY_PARQUET_FILE};
use mrsim_scenario::{OutputConfig, TrajectoryFormat};
use std::io::Write;
use std::path::Path;
use std::thread::JoinHandle;
use std::time::Duration;

/// Ticks sent to the thread at once, at most.
pub const BATCH_TICKS: usize = 16;

/// Longest a recorded tick waits in the loop before it is sent.
pub const BATCH_AGE: Duration = Duration::from_millis(100);

/// Consecutive ticks' bodies, concatenated, with the events and planner
/// calls recorded meanwhile.
#[derive(Default)]
struct Ticks {
    /// (tick, time, bodies in it), in order.
    ticks: Vec<(u64, f64, usize)>,
    bodies: Vec<BodyState>,
    /// events.jsonl's lines, each ended by a newline.
    events: Vec<u8>,
    /// timing.csv's rows.
    calls: Vec<Call>,
}

impl Batch for Ticks {
    fn is_empty(&self) -> bool {
        self.ticks.is_empty() && self.events.is_empty() && self.calls.is_empty()
    }
    fn clear(&mut self) {
        self.ticks.clear();
        self.bodies.clear();
        self.events.clear();
        self.calls.clear();
    }
}

/// One planner call's row of the timing file ([`mrsim_runfolder::timing`]).
#[derive(Debug, Clone, Copy)]
pub struct Call {
    /// The tick of the snapshot the planner read.
    pub tick: u64,
    /// The robot (its index).
    pub robot: u32,
    /// When its command was sent, ns after that snapshot's publication.
    pub sent_ns: u64,
    /// What became of it.
    pub status: Status,
    /// The CPU the call took, ns.
    pub cpu_ns: u64,
}

enum Msg {
    Ticks(Ticks),
}

/// What trajectory.csv holds besides its usual columns, and scan.csv.
#[derive(Default)]
pub struct Extras {
    /// Append a `theta` column (every body's heading): only when the
    /// bodies' headings matter (`Scenario::has_headings`: a unicycle or a
    /// car, or a body that is not a disc), so other runs' files stay the
    /// same.
    pub theta: bool,
    /// The scans to record, if any robot asks.
    pub scans: Option<crate::scan::ScanWriter>,
    /// Where the planner calls go (timing.csv or timing.parquet), if the
    /// run records them.
    pub calls: Option<TimingSink>,
}

impl Extras {
    /// What `scenario` asks for, scan.csv created in `dir` if needed.
    pub fn of(dir: &Path, scenario: &mrsim_scenario::Scenario) -> std::io::Result<Self> {
        Ok(Self {
            theta: scenario.has_headings(),
            scans: crate::scan::ScanWriter::create(dir, scenario)?,
            calls: None,
        })
    }
}

/// The recording thread's handle.
pub struct Recorder {
    batches: Batcher<Ticks, Msg>,
    thread: Option<JoinHandle<std::io::Result<Tracker>>>,
    /// The simulated second of the last tick queued.
    second: i64,
}

/// Where the trajectory's rows go (`[output] trajectory`).
enum Sink {
    /// trajectory.csv; `true`: with a `theta` column.
    Csv(RowFile, bool),
    /// trajectory.parquet, and its journal (trajectory.csv's rows while
    /// the run lives, removed once the footer is written).
    Parquet(Box<ParquetTrajectoryWriter>, RowFile, bool),
    None,
}

impl Sink {
    /// Creates the trajectory file `output` asks for in `dir` (and removes
    /// one of another format a previous run left there, so that the folder
    /// holds only this run's).
    fn create(dir: &Path, output: OutputConfig, theta: bool) -> std::io::Result<Self> {
        let csv = dir.join(TRAJECTORY_FILE);
        let parquet = dir.join(TRAJECTORY_PARQUET_FILE);
        let journal = dir.join(TRAJECTORY_JOURNAL_FILE);
        for (path, keep) in [
            (&csv, output.trajectory == TrajectoryFormat::Csv),
            (&parquet, output.trajectory == TrajectoryFormat::Parquet),
            (&journal, false),
        ] {
            if !keep && path.exists() {
                std::fs::remove_file(path)?;
            }
        }
        let header = format!("{CSV_HEADER}{}", if theta { ",theta" } else { "" });
        Ok(match output.trajectory {
            TrajectoryFormat::Csv => Sink::Csv(RowFile::create(&csv, &header)?, theta),
            TrajectoryFormat::Parquet => Sink::Parquet(
                Box::new(
                    ParquetTrajectoryWriter::create(&parquet, theta)
                        .map_err(std::io::Error::other)?,
                ),
                RowFile::create(&journal, &header)?,
                theta,
            ),
            TrajectoryFormat::None => Sink::None,
        })
    }

    /// Writes one tick's rows.
    fn write_tick(
        &mut self,
        labels: &mut Labels,
        names: &[String],
        tick: (u64, f64),
        bodies: &[BodyState],
    ) -> std::io::Result<()> {
        match self {
            Sink::Csv(traj, theta) => {
                csv_rows(traj.rows_mut(), labels, names, tick, bodies, *theta);
                Ok(())
            }
            Sink::Parquet(w, journal, theta) => {
                csv_rows(journal.rows_mut(), labels, names, tick, bodies, *theta);
                parquet_rows(w, labels, names, tick, bodies)
            }
            Sink::None => Ok(()),
        }
    }

    /// Holds enough rows to be written out.
    fn is_full(&self) -> bool {
        match self {
            Sink::Csv(f, _) | Sink::Parquet(_, f, _) => f.is_full(),
            Sink::None => false,
        }
    }

    /// Puts the rows held on the disk (the CSV, or the Parquet file's
    /// journal: its row groups go when full, its footer at
    /// [`Sink::finish`]).
    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::Csv(f, _) | Sink::Parquet(_, f, _) => f.write_out(),
            Sink::None => Ok(()),
        }
    }

    /// Writes what is left and closes the file (the Parquet file's footer,
    /// then its journal removed).
    fn finish(self) -> std::io::Result<()> {
        match self {
            Sink::Csv(mut traj, _) => traj.write_out(),
            Sink::Parquet(w, mut journal, _) => {
                journal.write_out()?;
                w.finish().map_err(std::io::Error::other)?;
                std::fs::remove_file(journal.path())
            }
            Sink::None => Ok(()),
        }
    }
}

/// trajectory.csv's header.
const CSV_HEADER: &str = "tick,time,body,kind,x,y,vx,vy";

/// Appends one tick's CSV rows to `block`, each ended by its newline.
/// `tick,time,` is the same on every row; `theta` appends each body's
/// heading.
fn csv_rows(
    block: &mut Vec<u8>,
    labels: &mut Labels,
    names: &[String],
    (tick, time): (u64, f64),
    bodies: &[BodyState],
    theta: bool,
) {
    if bodies.is_empty() {
        return;
    }
    let start = block.len();
    push_u64(block, tick);
    block.push(b',');
    push_fixed6(block, time);
    block.push(b',');
    let prefix = start..block.len();
    for (k, b) in bodies.iter().enumerate() {
        if k > 0 {
            block.extend_from_within(prefix.clone());
        }
        // tick,time,body,kind,x,y,vx,vy
        block.extend_from_slice(&labels.of(b, names).csv);
        for v in [b.position, b.velocity].into_iter().flatten() {
            block.push(b',');
            push_fixed6(block, v);
        }
        if theta {
            block.push(b',');
            push_fixed6(block, b.heading);
        }
        block.push(b'\n');
    }
}

/// Adds one tick's rows to the Parquet file (the CSV's columns, typed;
/// the heading goes to the `theta` column if the file has one).
fn parquet_rows(
    w: &mut ParquetTrajectoryWriter,
    labels: &mut Labels,
    names: &[String],
    (tick, time): (u64, f64),
    bodies: &[BodyState],
) -> std::io::Result<()> {
    for b in bodies {
        let state = [b.position[0], b.position[1], b.velocity[0], b.velocity[1]];
        w.push(tick, time, &labels.of(b, names).cells, state, b.heading)
            .map_err(std::io::Error::other)?;
    }
    Ok(())
}

impl Recorder {
    /// [`Recorder::start_with`] the default output (trajectory.csv, every
    /// tick) and no extras.
    pub fn start(dir: &Path, names: Vec<String>, tracker: Tracker) -> std::io::Result<Self> {
        Self::start_with(
            dir,
            names,
            tracker,
            OutputConfig::default(),
            Extras::default(),
        )
    }

    /// Creates the trajectory file `output` asks for (with the `extras` the
    /// scenario asks for) and events.jsonl in `dir` and starts the thread.
    /// `names[i]` is body i's name; `tracker` takes in every tick's states,
    /// in order, whatever `output` records.
    pub fn start_with(
        dir: &Path,
        names: Vec<String>,
        mut tracker: Tracker,
        output: OutputConfig,
        extras: Extras,
    ) -> std::io::Result<Self> {
        let Extras {
            theta,
            mut scans,
            mut calls,
        } = extras;
        let mut sink = Sink::create(dir, output, theta)?;
        let mut events = RowFile::create(&dir.join(mrsim_runfolder::EVENTS_FILE), "")?;
        let mut encounters = RowFile::create(
            &dir.join(mrsim_runfolder::ENCOUNTERS_FILE),
            ENCOUNTERS_HEADER,
        )?;
        let (tx, rx) = bounded::<Msg>(256);
        let (back_tx, recycled) = unbounded();
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                mrsim_sys::sched::background_thread();
                // A row waits at most BATCH_AGE in the loop, so the files
                // go out this much later than it, and a row reaches the
                // disk within FLUSH_WALL of its tick.
                let mut clock = FlushClock::new(FLUSH_WALL.saturating_sub(BATCH_AGE));
                // The latest simulated time taken in.
                let mut latest: Option<f64> = None;
                let mut labels = Labels::default();
                // The last tick taken in if `every` skipped it: written at
                // the end, so the trajectory ends where the run did.
                let mut skipped: Option<(u64, f64)> = None;
                let mut skipped_bodies = Vec::new();
                // Every file to the disk, the trajectory last: a tick seen
                // in it means the other files hold everything before it.
                macro_rules! flush_all {
                    () => {
                        flush_calls(&mut calls);
                        events.write_out()?;
                        encounters.write_out()?;
                        if let Some(s) = &mut scans {
                            s.flush()?;
                        }
                        sink.flush()?;
                        clock.flushed(latest);
                    };
                }
                loop {
                    // Wake at least once a period, so rows reach the disk
                    // even while the tick loop waits (a lockstep stall).
                    match rx.recv_timeout(clock.left()) {
                        Ok(Msg::Ticks(batch)) => {
                            // The batch's calls and events first: they are
                            // of its ticks (or earlier), so a flush within
                            // the batch has them on the disk before the
                            // trajectory's rows.
                            events.write_all(&batch.events)?;
                            write_calls(&mut calls, &names, &batch.calls);
                            let mut from = 0;
                            for &(tick, time, count) in &batch.ticks {
                                let bodies = &batch.bodies[from..from + count];
                                from += count;
                                latest = Some(time);
                                tracker.track(tick, time, bodies);
                                if output.records(tick) {
                                    skipped = None;
                                    sink.write_tick(&mut labels, &names, (tick, time), bodies)?;
                                    if let Some(s) = &mut scans {
                                        s.write(tick, bodies)?;
                                    }
                                    // A big tick (100,000 robots) goes out
                                    // at once rather than a batch of them
                                    // held.
                                    if sink.is_full() || scans.as_ref().is_some_and(|s| s.is_full())
                                    {
                                        flush_all!();
                                    }
                                } else {
                                    skipped = Some((tick, time));
                                    skipped_bodies.clear();
                                    skipped_bodies.extend_from_slice(bodies);
                                }
                            }
                            let _ = back_tx.send(batch);
                            let ended = tracker.interaction_mut().take_closed(&names);
                            encounters.write_all(encounter_rows(&ended).as_bytes())?;
                        }
                        Err(RecvTimeoutError::Timeout) => {}
                        Err(RecvTimeoutError::Disconnected) => break,
                    }
                    let full = sink.is_full()
                        || events.is_full()
                        || encounters.is_full()
                        || scans.as_ref().is_some_and(|s| s.is_full())
                        || calls.as_ref().is_some_and(TimingSink::is_full);
                    if full || clock.due(latest) {
                        flush_all!();
                    }
                }
                if let Some(tick) = skipped {
                    sink.write_tick(&mut labels, &names, tick, &skipped_bodies)?;
                }
                events.write_out()?;
                if let Some(w) = calls.take()
                    && let Err(e) = w.finish()
                {
                    eprintln!("world: {e}");
                }
                tracker.interaction_mut().close_all();
                let ended = tracker.interaction_mut().take_closed(&names);
                encounters.write_all(encounter_rows(&ended).as_bytes())?;
                encounters.write_out()?;
                if let Some(s) = &mut scans {
                    s.flush()?;
                }
                sink.finish()?;
                Ok(tracker)
            })?;
        Ok(Self {
            batches: Batcher::new(tx, recycled, Ticks::default(), Msg::Ticks),
            thread: Some(thread),
            second: i64::MIN,
        })
    }
    /// Queues one tick's bodies; they go to the thread with the batch (at
    /// once if it is the first tick of a simulated second, when the thread
    /// flushes the files).
    pub fn tick(&mut self, tick: u64, time: f64, bodies: &[BodyState]) {
        let pending = self.batches.pending();
        pending.ticks.push((tick, time, bodies.len()));
        pending.bodies.extend_from_slice(bodies);
        let second = FlushClock::second_of(time);
        if pending.ticks.len() >= BATCH_TICKS || second > self.second {
            self.second = self.second.max(second);
            self.batches.send();
        } else {
            self.batches.send_if_older(BATCH_AGE);
        }
    }

    /// Sends the queued ticks if the oldest has waited [`BATCH_AGE`]: the
    /// loop calls it while it waits for commands, so a stalled run's last
    /// ticks still reach the disk within about a second.
    pub fn send_if_due(&mut self) {
        self.batches.send_if_older(BATCH_AGE);
    }

    /// Queues one event: `value` as one line of events.jsonl (a JSON
    /// object). It goes to the thread with the ticks' batch, so the loop
    /// pays no wake-up of the thread per event.
    pub fn event<T: serde::Serialize>(&mut self, value: &T) {
        let events = &mut self.batches.pending().events;
        let before = events.len();
        if serde_json::to_writer(&mut *events, value).is_ok() {
            events.push(b'\n');
        } else {
            events.truncate(before);
        }
    }

    /// Queues one planner call's row of the timing file.
    pub fn call(&mut self, call: Call) {
        self.batches.pending().calls.push(call);
    }

    /// Flushes and stops the thread; the tracker has taken in every tick
    /// recorded.
    pub fn finish(&mut self) -> std::io::Result<Tracker> {
        self.stop()?
            .ok_or_else(|| std::io::Error::other("recorder thread already stopped"))
    }

    fn stop(&mut self) -> std::io::Result<Option<Tracker>> {
        self.batches.close();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r.map(Some),
            Some(Err(_)) => Err(std::io::Error::other("recorder thread panicked")),
            None => Ok(None),
        }
    }
}

/// Writes planner calls to the timing file; a failure to write ends the
/// file (said once), never the run.
fn write_calls(sink: &mut Option<TimingSink>, names: &[String], calls: &[Call]) {
    let Some(w) = sink else { return };
    for c in calls {
        let name = names.get(c.robot as usize).map_or("", String::as_str);
        if let Err(e) = w.row(c.tick, name, c.sent_ns, c.status, c.cpu_ns) {
            eprintln!("world: {e}; {} stops here", w.file_name());
            *sink = None;
            return;
        }
    }
}

/// Puts the timing file's rows held on the disk; a failure ends the file
/// (said once), never the run.
fn flush_calls(sink: &mut Option<TimingSink>) {
    if let Some(w) = sink
        && let Err(e) = w.flush()
    {
        eprintln!("world: {e}; {} stops here", w.file_name());
        *sink = None;
    }
}

/// A body's cells as the trajectory writes them, made once per body.
struct Label {
    /// The kind it was made for.
    kind: u32,
    /// `name,kind` as a CSV row spells it.
    csv: Vec<u8>,
    /// The Parquet file's `body` and `kind` cells.
    cells: BodyCells,
}

/// Each body's [`Label`].
#[derive(Default)]
struct Labels {
    /// By body id; an id not seen yet has kind [`Labels::UNSET`].
    by_id: Vec<Label>,
}

impl Labels {
    /// The kind of a label not made yet (no body has it).
    const UNSET: u32 = u32::MAX;

    /// The label of `b` (name `?` for an id without a name).
    fn of(&mut self, b: &BodyState, names: &[String]) -> &Label {
        let id = b.id as usize;
        if self.by_id.len() <= id {
            self.by_id.resize_with(id + 1, || Label {
                kind: Self::UNSET,
                csv: Vec::new(),
                cells: BodyCells::new("", ""),
            });
        }
        let label = &mut self.by_id[id];
        if label.kind != b.kind {
            let name = names.get(id).map_or("?", String::as_str);
            let kind = body_kind::name(b.kind);
            *label = Label {
                kind: b.kind,
                csv: format!("{name},{kind}").into_bytes(),
                cells: BodyCells::new(name, kind),
            };
        }
        label
    }
}

/// The two-digit decimal strings "00" to "99", concatenated.
const DIGIT_PAIRS: &[u8; 200] = b"\
0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Writes the last two decimal digits of `n` (below 100) at `out[0..2]`.
fn two_digits(out: &mut [u8], n: u64) {
    let i = 2 * n as usize;
    out[..2].copy_from_slice(&DIGIT_PAIRS[i..i + 2]);
}

/// Appends `n` in decimal.
fn push_u64(out: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    while n >= 100 {
        i -= 2;
        two_digits(&mut digits[i..], n % 100);
        n /= 100;
    }
    if n >= 10 {
        i -= 2;
        two_digits(&mut digits[i..], n);
    } else {
        i -= 1;
        digits[i] = b'0' + n as u8;
    }
    out.extend_from_slice(&digits[i..]);
}

/// Appends `x` exactly as `format!("{x:.6}")` writes it, without the
/// formatting machinery: Rust's exact float formatting of the trajectory's
/// five numbers a row was over half of the recording thread's time.
///
/// `x * 1e6` is within `|x * 1e6| * 2^-53` of the true product, so rounding
/// it gives the true product's rounding unless the fraction is that near
/// one half. Those (ties, which Rust rounds to even, and near-ties), large
/// magnitudes and non-finite values take `format!`'s own path.
fn push_fixed6(out: &mut Vec<u8>, x: f64) {
    let s = (x * 1e6).abs();
    // Below 1e15 (< 2^50) the cast is the floor of `s`, and `s - floor` is
    // exact: no call into libm for `floor` and `round`.
    let whole = s as u64;
    let frac = s - whole as f64;
    if s.is_nan() || s >= 1e15 || (frac - 0.5).abs() <= s * 4e-16 {
        // Not a number, too large (or infinite), or too near a half to
        // round here.
        let _ = write!(out, "{x:.6}");
        return;
    }
    let n = whole + u64::from(frac > 0.5);
    if x.is_sign_negative() {
        // As Rust does: a negative value that rounds to zero keeps its sign.
        out.push(b'-');
    }
    push_u64(out, n / 1_000_000);
    let f = n % 1_000_000;
    let mut digits = [b'.'; 7];
    two_digits(&mut digits[1..], f / 10_000);
    two_digits(&mut digits[3..], f / 100 % 100);
    two_digits(&mut digits[5..], f % 100);
    out.extend_from_slice(&digits);
}

impl Drop for Recorder {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fast(x: f64) -> String {
        let mut v = Vec::new();
        push_fixed6(&mut v, x);
        String::from_utf8(v).expect("ascii")
    }

    #[test]
    fn fixed_six_decimals_match_rusts_own_formatting() {
        let mut cases = vec![
            0.0,
            -0.0,
            -1e-9,
            1e-9,
            0.0078125,  // an exact tie: Rust rounds it to even
            -0.0234375, // another, negative
            0.5e-6,
            1.5e-6,
            2.5e-6,
            1.0000005,
            123456.0000005,
            -29.0,
            1e9,
            -1e9 - 0.4999995,
            4e9 + 0.1,
            1e15,
            -1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        // Many values at every scale a trajectory has, and their halves.
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let unit = (x >> 11) as f64 / (1u64 << 53) as f64;
            let scale = 10f64.powi((x % 14) as i32 - 7);
            let v = (unit - 0.5) * scale;
            cases.push(v);
            cases.push((v * 1e6).round() / 1e6 + 0.5e-6);
            cases.push(f32::from_bits(x as u32) as f64);
        }
        for v in cases {
            assert_eq!(fast(v), format!("{v:.6}"), "{v:e}");
        }
    }

    #[test]
    fn integers_are_written_in_decimal() {
        for n in [0u64, 7, 10, 999, 1_000_000, u64::MAX] {
            let mut v = Vec::new();
            push_u64(&mut v, n);
            assert_eq!(String::from_utf8(v).expect("ascii"), n.to_string());
        }
    }
}
