//! Duration histograms: the commands' timings and the tick loop's own
//! costs, recorded in ns and reported as [`Percentiles`] in µs.

use hdrhistogram::Histogram;
pub use mrsim_runfolder::metrics::Percentiles;

/// A histogram of durations recorded in ns, reported in µs.
///
/// It starts small and grows to the largest duration recorded (up to
/// 60 s), so memory follows what was measured rather than the range: a
/// world keeps three per robot.
#[derive(Debug, Clone)]
pub struct DurationHistogram(Histogram<u32>);

/// Longest duration a [`DurationHistogram`] holds, ns; longer ones count as it.
const MAX_NS: u64 = 60_000_000_000;

impl Default for DurationHistogram {
    /// Three significant digits (run-wide figures such as the all-in time).
    fn default() -> Self {
        Self::with_precision(1, 3)
    }
}

impl DurationHistogram {
    /// Two significant digits from 100 ns (a robot's own latency, wake-up
    /// and compute times, of which a world keeps three per robot).
    pub fn per_robot() -> Self {
        Self::with_precision(100, 2)
    }

    fn with_precision(lowest_ns: u64, digits: u8) -> Self {
        // Valid constants: construction cannot fail; an auto-resizing
        // histogram of default bounds is the fallback all the same.
        let mut h = Histogram::new_with_bounds(lowest_ns, lowest_ns * 2, digits)
            .or_else(|_| Histogram::new(digits))
            .unwrap_or_else(|_| unreachable!("1..5 significant digits are valid"));
        h.auto(true);
        Self(h)
    }

    /// Records one duration, ns (clamped into 1 ns .. 60 s).
    pub fn record_ns(&mut self, ns: u64) {
        let ns = ns.clamp(1, MAX_NS);
        // Grows to hold `ns`; should growing ever fail, count it as the
        // largest value held rather than lose it.
        if self.0.record(ns).is_err() {
            self.0.saturating_record(ns);
        }
    }

    /// p50/p99/p99.9/max in µs (zeros when empty).
    pub fn percentiles(&self) -> Percentiles {
        if self.0.is_empty() {
            return Percentiles::default();
        }
        let us = |ns: u64| ns as f64 / 1000.0;
        Percentiles {
            p50: us(self.0.value_at_quantile(0.5)),
            p99: us(self.0.value_at_quantile(0.99)),
            p999: us(self.0.value_at_quantile(0.999)),
            max: us(self.0.max()),
            count: self.0.len(),
        }
    }

    /// Median and 99th percentile in µs, and the sample count (zeros when
    /// empty): the live view's numbers, cheaper than [`Self::percentiles`].
    pub fn p50_p99_us(&self) -> (f64, f64, u64) {
        if self.0.is_empty() {
            return (0.0, 0.0, 0);
        }
        let us = |ns: u64| ns as f64 / 1000.0;
        (
            us(self.0.value_at_quantile(0.5)),
            us(self.0.value_at_quantile(0.99)),
            self.0.len(),
        )
    }
}

/// Samples a robot's timings wait for before they go into its histograms.
const TIMING_BATCH: usize = 32;

/// One robot's three timing histograms: snapshot published -> command
/// received (latency), published -> agent awake (wake), and the planner's
/// compute time.
///
/// Samples are kept in a small buffer and go into the histograms
/// [`TIMING_BATCH`] at a time, so that a tick does not touch 3 x robots
/// histograms far apart in memory, one cache miss each.
#[derive(Debug, Clone)]
pub struct RobotTimings {
    latency: DurationHistogram,
    wake: DurationHistogram,
    compute: DurationHistogram,
    pending: Vec<[u64; 3]>,
}

impl Default for RobotTimings {
    fn default() -> Self {
        Self {
            latency: DurationHistogram::per_robot(),
            wake: DurationHistogram::per_robot(),
            compute: DurationHistogram::per_robot(),
            pending: Vec::with_capacity(TIMING_BATCH),
        }
    }
}

impl RobotTimings {
    /// Records one command's latency, wake-up and compute time, ns.
    pub fn record_ns(&mut self, latency: u64, wake: u64, compute: u64) {
        self.pending.push([latency, wake, compute]);
        if self.pending.len() >= TIMING_BATCH {
            self.flush();
        }
    }

    fn flush(&mut self) {
        for [l, w, c] in self.pending.drain(..) {
            self.latency.record_ns(l);
            self.wake.record_ns(w);
            self.compute.record_ns(c);
        }
    }

    /// Latency, wake-up and compute histograms, with every sample recorded.
    pub fn histograms(&mut self) -> [&DurationHistogram; 3] {
        self.flush();
        [&self.latency, &self.wake, &self.compute]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histograms_grow_to_hold_durations_far_beyond_their_first_range() {
        for mut h in [DurationHistogram::default(), DurationHistogram::per_robot()] {
            for us in [3, 150, 2_500, 40_000] {
                h.record_ns(us * 1000);
            }
            h.record_ns(90_000_000_000); // beyond 60 s: counted as 60 s
            let p = h.percentiles();
            assert_eq!(p.count, 5);
            // Two significant digits at least.
            assert!((p.p50 - 2_500.0).abs() / 2_500.0 < 0.01, "{p:?}");
            assert!((p.max - 60e6).abs() / 60e6 < 0.01, "{p:?}");
        }
    }

    #[test]
    fn robot_timings_hold_every_sample_whatever_the_batch() {
        // The same as recording each sample straight into its histogram.
        let mut t = RobotTimings::default();
        let mut direct: [DurationHistogram; 3] =
            std::array::from_fn(|_| DurationHistogram::per_robot());
        for k in 1..=(3 * TIMING_BATCH as u64 + 5) {
            let sample = [k * 1000, 2 * k * 1777, 3 * k * 9000];
            t.record_ns(sample[0], sample[1], sample[2]);
            for (h, v) in direct.iter_mut().zip(sample) {
                h.record_ns(v);
            }
            if k % 7 == 0 || k == TIMING_BATCH as u64 {
                for (h, d) in t.histograms().into_iter().zip(&direct) {
                    assert_eq!(h.percentiles(), d.percentiles(), "after {k} samples");
                    assert_eq!(h.percentiles().count, k);
                }
            }
        }
    }
}
