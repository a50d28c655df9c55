//! Recording off the tick loop: trajectory.csv and events.jsonl are written
//! by their own thread, fed through a crossbeam channel, flushed about once
//! a second (also when no tick comes), so a crash loses at most the last
//! second and the tick loop never waits on the disk. A tick's rows and an
//! event's line are written in one piece, so what reaches the disk ends
//! with a whole tick and a whole line (no torn rows after a crash).
//!
//! Ticks go to the thread in batches of up to [`BATCH_TICKS`] (or whatever
//! is pending after [`BATCH_AGE`]): one wake-up of the thread per tick cost
//! the loop a futex wake, about 7 % of the world's tick at 64 robots.
//! Batch buffers are returned to the loop for reuse.
//!
//! The same thread computes the robots' motion metrics from the states it
//! writes ([`crate::tracking`]) and hands them back at the end.

use crate::tracking::Tracker;
use crossbeam::channel::{Receiver, RecvTimeoutError, Sender, bounded, unbounded};
use mrsim_proto::{BodyState, body_kind};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Ticks sent to the thread at once, at most.
pub const BATCH_TICKS: usize = 16;

/// Longest a recorded tick waits in the loop before it is sent.
pub const BATCH_AGE: Duration = Duration::from_millis(100);

/// Consecutive ticks' bodies, concatenated.
#[derive(Default)]
struct Batch {
    /// (tick, time, bodies in it), in order.
    ticks: Vec<(u64, f64, usize)>,
    bodies: Vec<BodyState>,
}

enum Msg {
    Ticks(Batch),
    Event(String),
}

/// The recording thread's handle.
pub struct Recorder {
    tx: Option<Sender<Msg>>,
    recycled: Receiver<Batch>,
    thread: Option<JoinHandle<std::io::Result<Tracker>>>,
    pending: Batch,
    oldest: Option<Instant>,
}

impl Recorder {
    /// Creates trajectory.csv and events.jsonl in `dir` and starts the
    /// thread. `names[i]` is body i's name; `tracker` takes in every tick's
    /// states, in order.
    pub fn start(dir: &Path, names: Vec<String>, mut tracker: Tracker) -> std::io::Result<Self> {
        let mut traj = BufWriter::with_capacity(1 << 16, File::create(dir.join("trajectory.csv"))?);
        let mut events = BufWriter::new(File::create(dir.join("events.jsonl"))?);
        writeln!(traj, "tick,time,body,kind,x,y,vx,vy")?;
        traj.flush()?;
        let (tx, rx) = bounded::<Msg>(256);
        let (back_tx, recycled) = unbounded();
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                mrsim_transport::background_thread();
                let period = Duration::from_secs(1);
                let mut last_flush = Instant::now();
                let mut block = Vec::with_capacity(1 << 12);
                loop {
                    // Wake at least once a period, so rows reach the disk
                    // even while the tick loop waits (a lockstep stall).
                    let left = period.saturating_sub(last_flush.elapsed());
                    match rx.recv_timeout(left) {
                        Ok(Msg::Ticks(batch)) => {
                            let mut from = 0;
                            for &(tick, time, count) in &batch.ticks {
                                let bodies = &batch.bodies[from..from + count];
                                from += count;
                                tracker.track(bodies);
                                // A tick's rows go to the buffer in one piece, so
                                // the file only ever ends after a whole tick.
                                block.clear();
                                for b in bodies {
                                    let name =
                                        names.get(b.id as usize).map(String::as_str).unwrap_or("?");
                                    let kind = if b.kind == body_kind::ROBOT {
                                        "robot"
                                    } else {
                                        "obstacle"
                                    };
                                    writeln!(
                                        block,
                                        "{tick},{time:.6},{name},{kind},{:.6},{:.6},{:.6},{:.6}",
                                        b.position[0], b.position[1], b.velocity[0], b.velocity[1]
                                    )?;
                                }
                                traj.write_all(&block)?;
                            }
                            let _ = back_tx.send(batch);
                        }
                        Ok(Msg::Event(mut line)) => {
                            line.push('\n');
                            events.write_all(line.as_bytes())?;
                        }
                        Err(RecvTimeoutError::Timeout) => {}
                        Err(RecvTimeoutError::Disconnected) => break,
                    }
                    if last_flush.elapsed() >= period {
                        traj.flush()?;
                        events.flush()?;
                        last_flush = Instant::now();
                    }
                }
                traj.flush()?;
                events.flush()?;
                Ok(tracker)
            })?;
        Ok(Self {
            tx: Some(tx),
            recycled,
            thread: Some(thread),
            pending: Batch::default(),
            oldest: None,
        })
    }

    /// Queues one tick's bodies; they go to the thread with the batch.
    pub fn tick(&mut self, tick: u64, time: f64, bodies: &[BodyState]) {
        self.pending.ticks.push((tick, time, bodies.len()));
        self.pending.bodies.extend_from_slice(bodies);
        let oldest = *self.oldest.get_or_insert_with(Instant::now);
        if self.pending.ticks.len() >= BATCH_TICKS || oldest.elapsed() >= BATCH_AGE {
            self.send_pending();
        }
    }

    /// Sends the queued ticks if the oldest has waited [`BATCH_AGE`]: the
    /// loop calls it while it waits for commands, so a stalled run's last
    /// ticks still reach the disk within about a second.
    pub fn send_if_due(&mut self) {
        if self.oldest.is_some_and(|t| t.elapsed() >= BATCH_AGE) {
            self.send_pending();
        }
    }

    /// Sends the ticks queued so far to the thread.
    fn send_pending(&mut self) {
        self.oldest = None;
        if self.pending.ticks.is_empty() {
            return;
        }
        let mut next = self.recycled.try_recv().unwrap_or_default();
        next.ticks.clear();
        next.bodies.clear();
        let batch = std::mem::replace(&mut self.pending, next);
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::Ticks(batch));
        }
    }

    /// Queues one event (a JSON object).
    pub fn event(&self, value: serde_json::Value) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::Event(value.to_string()));
        }
    }

    /// Flushes and stops the thread; the tracker has taken in every tick
    /// recorded.
    pub fn finish(&mut self) -> std::io::Result<Tracker> {
        self.stop()?
            .ok_or_else(|| std::io::Error::other("recorder thread already stopped"))
    }

    fn stop(&mut self) -> std::io::Result<Option<Tracker>> {
        self.send_pending();
        self.tx.take();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r.map(Some),
            Some(Err(_)) => Err(std::io::Error::other("recorder thread panicked")),
            None => Ok(None),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}
