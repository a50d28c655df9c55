//! Recording off the tick loop: trajectory.csv and events.jsonl are written
//! by their own thread, fed through a crossbeam channel, flushed about once
//! a second (also when no tick comes), so a crash loses at most the last
//! second and the tick loop never waits on the disk. A tick's rows and an
//! event's line are written in one piece, so what reaches the disk ends
//! with a whole tick and a whole line (no torn rows after a crash). Row buffers are returned to the loop for reuse.

use crossbeam::channel::{Receiver, RecvTimeoutError, Sender, bounded, unbounded};
use mrsim_proto::{BodyState, body_kind};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

enum Msg {
    Tick {
        tick: u64,
        time: f64,
        bodies: Vec<BodyState>,
    },
    Event(String),
}

/// The recording thread's handle.
pub struct Recorder {
    tx: Option<Sender<Msg>>,
    recycled: Receiver<Vec<BodyState>>,
    thread: Option<JoinHandle<std::io::Result<()>>>,
}

impl Recorder {
    /// Creates trajectory.csv and events.jsonl in `dir` and starts the
    /// thread. `names[i]` is body i's name.
    pub fn start(dir: &Path, names: Vec<String>) -> std::io::Result<Self> {
        let mut traj = BufWriter::with_capacity(1 << 16, File::create(dir.join("trajectory.csv"))?);
        let mut events = BufWriter::new(File::create(dir.join("events.jsonl"))?);
        writeln!(traj, "tick,time,body,kind,x,y,vx,vy")?;
        traj.flush()?;
        let (tx, rx) = bounded::<Msg>(256);
        let (back_tx, recycled) = unbounded();
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                let period = Duration::from_secs(1);
                let mut last_flush = Instant::now();
                let mut block = Vec::with_capacity(1 << 12);
                loop {
                    // Wake at least once a period, so rows reach the disk
                    // even while the tick loop waits (a lockstep stall).
                    let left = period.saturating_sub(last_flush.elapsed());
                    match rx.recv_timeout(left) {
                        Ok(Msg::Tick { tick, time, bodies }) => {
                            // A tick's rows go to the buffer in one piece, so
                            // the file only ever ends after a whole tick.
                            block.clear();
                            for b in &bodies {
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
                            let _ = back_tx.send(bodies);
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
                Ok(())
            })?;
        Ok(Self {
            tx: Some(tx),
            recycled,
            thread: Some(thread),
        })
    }

    /// Queues one tick's bodies.
    pub fn tick(&self, tick: u64, time: f64, bodies: &[BodyState]) {
        let mut buf = self.recycled.try_recv().unwrap_or_default();
        buf.clear();
        buf.extend_from_slice(bodies);
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::Tick {
                tick,
                time,
                bodies: buf,
            });
        }
    }

    /// Queues one event (a JSON object).
    pub fn event(&self, value: serde_json::Value) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(Msg::Event(value.to_string()));
        }
    }

    /// Flushes and stops the thread.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.tx.take();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r,
            Some(Err(_)) => Err(std::io::Error::other("recorder thread panicked")),
            None => Ok(()),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.tx.take();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
