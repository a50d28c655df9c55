//! The commands' timings, recorded off the tick loop.
//!
//! Every accepted command brings three durations: its round trip
//! (snapshot published -> command received), the agent's wake-up
//! (published -> awake) and the planner's compute time; every planner
//! call of a run that records timing.csv (accepted, late or lost) two more:
//! its response time (published -> command sent) and its CPU. The world keeps a
//! histogram of each per robot and for the whole run. Recorded on the tick
//! loop, that would be six histogram records per robot and tick, each in
//! memory of its own (BENCHMARKS.md, "Realtime over iceoryx2", has the numbers).
//!
//! The loop appends each command's timings to one flat buffer and
//! hands the buffer over in batches (of [`BATCH`] samples, or whatever is
//! pending after [`BATCH_AGE`]) to a thread that owns the histograms and
//! runs at low priority ([`mrsim_sys::sched::background_thread`]). The live
//! view reads each robot's latency median and 99th percentile from a
//! summary that thread refreshes every [`LIVE_PERIOD`]; the run's end
//! takes the histograms back ([`TimingRecorder::finish`]), every sample in
//! them.

use crate::batch::Batcher;
use crate::histogram::{DurationHistogram, RobotTimings};
use crossbeam::channel::{bounded, unbounded};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Samples handed to the thread at once, at most.
pub const BATCH: usize = 4096;

/// Longest a sample waits in the loop before it is handed over.
pub const BATCH_AGE: Duration = Duration::from_millis(100);

/// How often the thread refreshes the live summary (as often as the live
/// statistics are published: [`crate::live::LiveStats::PERIOD`]).
pub const LIVE_PERIOD: Duration = crate::live::LiveStats::PERIOD;

/// One command's timings: round trip, wake-up and compute, ns; or one
/// planner call's response time and CPU ([`Sample::CALL`]).
#[derive(Debug, Clone, Copy)]
struct Sample {
    robot: u32,
    kind: u8,
    ns: [u64; 3],
}

impl Sample {
    /// A command's round trip, wake-up and compute.
    const COMMAND: u8 = 0;
    /// A planner call's response time and CPU (the third unused).
    const CALL: u8 = 1;
}

/// A robot's round trip as the live view shows it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LiveLatency {
    /// Median round trip, µs.
    pub p50_us: f64,
    /// 99th percentile round trip, µs.
    pub p99_us: f64,
    /// Commands recorded.
    pub commands: u64,
}

/// Every histogram of a run's timings.
#[derive(Debug, Clone)]
pub struct Timings {
    /// Robot i's round trip, wake-up and compute histograms.
    pub robots: Vec<RobotTimings>,
    /// Every robot's round trip, wake-up and compute, together (three
    /// significant digits).
    pub all: [DurationHistogram; 3],
}

impl Timings {
    fn new(robots: usize) -> Self {
        Self {
            robots: vec![RobotTimings::default(); robots],
            all: Default::default(),
        }
    }

    fn record(&mut self, batch: &[Sample]) {
        for s in batch {
            let [a, b, c] = s.ns;
            if let Some(r) = self.robots.get_mut(s.robot as usize) {
                match s.kind {
                    Sample::COMMAND => r.record_ns(a, b, c),
                    _ => r.record_call_ns(a, b),
                }
            }
        }
        // One histogram at a time: each stays in cache for the batch.
        for (k, h) in self.all.iter_mut().enumerate() {
            for s in batch.iter().filter(|s| s.kind == Sample::COMMAND) {
                h.record_ns(s.ns[k]);
            }
        }
    }

    fn summarize(&mut self, out: &mut Vec<LiveLatency>) {
        out.clear();
        out.extend(self.robots.iter_mut().map(|r| {
            let (p50_us, p99_us, commands) = r.histograms()[0].p50_p99_us();
            LiveLatency {
                p50_us,
                p99_us,
                commands,
            }
        }));
    }
}

/// The tick loop's handle on the timing thread.
pub struct TimingRecorder {
    batches: Batcher<Vec<Sample>, Vec<Sample>>,
    live: Arc<Mutex<Vec<LiveLatency>>>,
    thread: Option<JoinHandle<Timings>>,
}

impl TimingRecorder {
    /// Starts the thread, with empty histograms for `robots` robots.
    pub fn start(robots: usize) -> std::io::Result<Self> {
        // Room for a few seconds of batches: the loop waits only if the
        // thread falls that far behind.
        let (tx, rx) = bounded::<Vec<Sample>>(256);
        let (back_tx, recycled) = unbounded();
        let live = Arc::new(Mutex::new(vec![LiveLatency::default(); robots]));
        let shared = Arc::clone(&live);
        let thread = std::thread::Builder::new()
            .name("timings".into())
            .spawn(move || {
                mrsim_sys::sched::background_thread();
                let mut t = Timings::new(robots);
                let mut summary = Vec::with_capacity(robots);
                let mut refresh = |t: &mut Timings| {
                    t.summarize(&mut summary);
                    let mut live = shared.lock().unwrap_or_else(PoisonError::into_inner);
                    std::mem::swap(&mut *live, &mut summary);
                };
                let mut refreshed = Instant::now();
                for batch in rx {
                    t.record(&batch);
                    let _ = back_tx.send(batch);
                    if refreshed.elapsed() >= LIVE_PERIOD {
                        refresh(&mut t);
                        refreshed = Instant::now();
                    }
                }
                refresh(&mut t);
                t
            })?;
        Ok(Self {
            batches: Batcher::new(tx, recycled, Vec::with_capacity(BATCH), |b| b),
            live,
            thread: Some(thread),
        })
    }

    /// Records one command of robot `robot`: its round trip, wake-up and
    /// compute time, ns.
    pub fn record(&mut self, robot: usize, latency: u64, wake: u64, compute: u64) {
        let pending = self.batches.pending();
        pending.push(Sample {
            robot: robot as u32,
            kind: Sample::COMMAND,
            ns: [latency, wake, compute],
        });
        if pending.len() >= BATCH {
            self.batches.send();
        }
    }

    /// Records one planner call of robot `robot` (a row of timing.csv):
    /// its response time (snapshot published -> command sent) and the CPU
    /// it took, ns.
    pub fn call(&mut self, robot: usize, response: u64, cpu: u64) {
        let pending = self.batches.pending();
        pending.push(Sample {
            robot: robot as u32,
            kind: Sample::CALL,
            ns: [response, cpu, 0],
        });
        if pending.len() >= BATCH {
            self.batches.send();
        }
    }

    /// Hands the pending samples over if the oldest has waited
    /// [`BATCH_AGE`] (the loop calls it every tick and while it waits).
    pub fn send_if_due(&mut self) {
        self.batches.send_if_older(BATCH_AGE);
    }

    /// Calls `f` with every robot's live round trip, as of the thread's
    /// last refresh (at most [`LIVE_PERIOD`] plus [`BATCH_AGE`] old).
    pub fn live<R>(&self, f: impl FnOnce(&[LiveLatency]) -> R) -> R {
        f(&self.live.lock().unwrap_or_else(PoisonError::into_inner))
    }

    /// Hands over what is pending, waits for the thread to record it, and
    /// returns every histogram; the live summary is then up to date too.
    /// An error only if the thread panicked (a bug): the histograms are
    /// then lost, and the error says so.
    pub fn finish(&mut self) -> std::io::Result<Timings> {
        self.batches.close();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(t)) => Ok(t),
            Some(Err(_)) => Err(std::io::Error::other("the timing thread panicked")),
            None => Err(std::io::Error::other(
                "the timing thread was already finished",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sample_reaches_the_histograms_whatever_the_batches() {
        let robots = 3;
        let mut rec = TimingRecorder::start(robots).expect("thread");
        let mut direct = Timings::new(robots);
        let mut samples = Vec::new();
        for k in 1..=(2 * BATCH as u64 + 17) {
            let robot = (k % robots as u64) as u32;
            let s = Sample {
                robot,
                kind: Sample::COMMAND,
                ns: [k * 1000, 2 * k * 1777, 3 * k * 9000],
            };
            rec.record(robot as usize, s.ns[0], s.ns[1], s.ns[2]);
            samples.push(s);
            if k % 7 == 0 {
                let c = Sample {
                    robot,
                    kind: Sample::CALL,
                    ns: [k * 500, k * 300, 0],
                };
                rec.call(robot as usize, c.ns[0], c.ns[1]);
                samples.push(c);
            }
            if k % 1000 == 0 {
                rec.send_if_due();
            }
        }
        direct.record(&samples);
        let commands = samples.iter().filter(|s| s.kind == Sample::COMMAND).count() as u64;
        let mut got = rec.finish().expect("finished");
        for (g, d) in got.all.iter().zip(&direct.all) {
            assert_eq!(g.percentiles(), d.percentiles());
            assert_eq!(g.percentiles().count, commands);
        }
        let mut calls = 0;
        for (g, d) in got.robots.iter_mut().zip(direct.robots.iter_mut()) {
            for (a, b) in g.histograms().into_iter().zip(d.histograms()) {
                assert_eq!(a.percentiles(), b.percentiles());
            }
            let (a, b) = (g.calls().expect("calls"), d.calls().expect("calls"));
            assert_eq!(a[0].percentiles(), b[0].percentiles());
            assert_eq!(a[1].percentiles(), b[1].percentiles());
            calls += a[0].percentiles().count;
        }
        assert_eq!(calls + commands, samples.len() as u64);
        // The live summary is the final one.
        let live = rec.live(|l| l.to_vec());
        let mut expect = Vec::new();
        direct.summarize(&mut expect);
        assert_eq!(live, expect);
        assert_eq!(live.iter().map(|l| l.commands).sum::<u64>(), commands);
        assert!(rec.finish().is_err(), "finishing twice is an error");
    }
}
