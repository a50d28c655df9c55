//! Duration histograms: the commands' timings and the tick loop's own
//! costs, recorded in ns and reported as [`Percentiles`] in µs.

use hdrhistogram::Histogram;
pub use mrsim_runfolder::metrics::Percentiles;

/// A histogram of durations recorded in ns, reported in µs.
///
/// Run-wide histograms are HdrHistogram's, which start small and grow to
/// the largest duration recorded (up to 60 s). A robot's own
/// ([`Self::per_robot`]; a world keeps three per robot) hold only the
/// buckets that were hit, in bucket order ([`Sparse`]): the same buckets
/// and the same percentiles as the dense histogram of the same precision,
/// in the memory of the few dozen buckets a robot's timings fall in rather
/// than of every bucket up to its largest duration (about 6 KB each at
/// milliseconds: 18 KB a robot, 1.8 GB for 100,000 robots).
#[derive(Debug, Clone)]
pub struct DurationHistogram(Repr);

#[derive(Debug, Clone)]
enum Repr {
    Dense(Histogram<u32>),
    Sparse(Sparse),
}

/// The per-robot histograms' bucket layout: two significant digits from
/// 100 ns to [`MAX_NS`]. It only names buckets (their lowest and highest
/// values); counts live in each [`Sparse`].
fn per_robot_layout() -> &'static Histogram<u32> {
    static LAYOUT: std::sync::OnceLock<Histogram<u32>> = std::sync::OnceLock::new();
    LAYOUT.get_or_init(|| {
        Histogram::new_with_bounds(PER_ROBOT_LOWEST_NS, MAX_NS, PER_ROBOT_DIGITS)
            .or_else(|_| Histogram::new(PER_ROBOT_DIGITS))
            .unwrap_or_else(|_| unreachable!("1..5 significant digits are valid"))
    })
}

/// Lowest duration a robot's histograms tell apart, ns.
const PER_ROBOT_LOWEST_NS: u64 = 100;
/// Significant digits of a robot's histograms.
const PER_ROBOT_DIGITS: u8 = 2;

/// The buckets that were hit, ascending: each bucket's lowest value (in
/// units of the layout's smallest bucket width, which every bucket's lowest
/// value is a multiple of) and its count.
#[derive(Debug, Clone, Default)]
struct Sparse {
    buckets: Vec<(u32, u32)>,
    total: u64,
    /// Largest duration recorded, ns.
    max: u64,
}

impl Sparse {
    /// The layout's smallest bucket width, as a shift.
    fn unit_shift() -> u32 {
        per_robot_layout().equivalent_range(0).trailing_zeros()
    }

    fn record(&mut self, ns: u64) {
        let layout = per_robot_layout();
        let key = (layout.lowest_equivalent(ns) >> Self::unit_shift()) as u32;
        match self.buckets.binary_search_by_key(&key, |b| b.0) {
            Ok(k) => self.buckets[k].1 = self.buckets[k].1.saturating_add(1),
            Err(k) => self.buckets.insert(k, (key, 1)),
        }
        self.total += 1;
        self.max = self.max.max(ns);
    }

    /// HdrHistogram's `value_at_quantile` over the buckets hit (0 < q <= 1).
    fn value_at_quantile(&self, q: f64) -> u64 {
        let target = ((q.min(1.0) * self.total as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        let shift = Self::unit_shift();
        let layout = per_robot_layout();
        for &(key, count) in &self.buckets {
            seen += u64::from(count);
            if seen >= target {
                return layout.highest_equivalent(u64::from(key) << shift);
            }
        }
        self.buckets.last().map_or(0, |&(key, _)| {
            layout.highest_equivalent(u64::from(key) << shift)
        })
    }

    fn max(&self) -> u64 {
        per_robot_layout().highest_equivalent(self.max)
    }
}

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
        Self(Repr::Sparse(Sparse::default()))
    }

    fn with_precision(lowest_ns: u64, digits: u8) -> Self {
        // Valid constants: construction cannot fail; an auto-resizing
        // histogram of default bounds is the fallback all the same.
        let mut h = Histogram::new_with_bounds(lowest_ns, lowest_ns * 2, digits)
            .or_else(|_| Histogram::new(digits))
            .unwrap_or_else(|_| unreachable!("1..5 significant digits are valid"));
        h.auto(true);
        Self(Repr::Dense(h))
    }

    /// Records one duration, ns (clamped into 1 ns .. 60 s).
    pub fn record_ns(&mut self, ns: u64) {
        let ns = ns.clamp(1, MAX_NS);
        match &mut self.0 {
            Repr::Dense(h) => {
                // Grows to hold `ns`; should growing ever fail, count it as
                // the largest value held rather than lose it.
                if h.record(ns).is_err() {
                    h.saturating_record(ns);
                }
            }
            Repr::Sparse(h) => h.record(ns),
        }
    }

    fn len(&self) -> u64 {
        match &self.0 {
            Repr::Dense(h) => h.len(),
            Repr::Sparse(h) => h.total,
        }
    }

    fn value_at_quantile(&self, q: f64) -> u64 {
        match &self.0 {
            Repr::Dense(h) => h.value_at_quantile(q),
            Repr::Sparse(h) => h.value_at_quantile(q),
        }
    }

    fn max(&self) -> u64 {
        match &self.0 {
            Repr::Dense(h) => h.max(),
            Repr::Sparse(h) => h.max(),
        }
    }

    /// p50/p99/p99.9/max in µs (zeros when empty).
    pub fn percentiles(&self) -> Percentiles {
        if self.len() == 0 {
            return Percentiles::default();
        }
        let us = |ns: u64| ns as f64 / 1000.0;
        Percentiles {
            p50: us(self.value_at_quantile(0.5)),
            p99: us(self.value_at_quantile(0.99)),
            p999: us(self.value_at_quantile(0.999)),
            max: us(self.max()),
            count: self.len(),
        }
    }

    /// Median and 99th percentile in µs, and the sample count (zeros when
    /// empty): the live view's numbers, cheaper than [`Self::percentiles`].
    pub fn p50_p99_us(&self) -> (f64, f64, u64) {
        if self.len() == 0 {
            return (0.0, 0.0, 0);
        }
        let us = |ns: u64| ns as f64 / 1000.0;
        (
            us(self.value_at_quantile(0.5)),
            us(self.value_at_quantile(0.99)),
            self.len(),
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
/// `TIMING_BATCH` at a time, so that a tick does not touch 3 x robots
/// histograms far apart in memory, one cache miss each.
#[derive(Debug, Clone)]
pub struct RobotTimings {
    latency: DurationHistogram,
    wake: DurationHistogram,
    compute: DurationHistogram,
    pending: Vec<[u64; 3]>,
    /// The planner calls' response time and CPU (timing.csv's rows), if
    /// the run records them.
    calls: Option<Box<[DurationHistogram; 2]>>,
}

impl Default for RobotTimings {
    fn default() -> Self {
        Self {
            latency: DurationHistogram::per_robot(),
            wake: DurationHistogram::per_robot(),
            compute: DurationHistogram::per_robot(),
            pending: Vec::with_capacity(TIMING_BATCH),
            calls: None,
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

    /// Records one planner call's response time and CPU, ns.
    pub fn record_call_ns(&mut self, response: u64, cpu: u64) {
        let h = self.calls.get_or_insert_with(|| {
            Box::new([
                DurationHistogram::per_robot(),
                DurationHistogram::per_robot(),
            ])
        });
        h[0].record_ns(response);
        h[1].record_ns(cpu);
    }

    /// The planner calls' response time and CPU histograms, if any call
    /// was recorded.
    pub fn calls(&self) -> Option<&[DurationHistogram; 2]> {
        self.calls.as_deref()
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
    fn a_robots_histogram_gives_the_dense_histograms_percentiles() {
        // The dense histogram of the same layout, fed the same durations
        // (spread over six decades, many in shared buckets).
        let mut dense = DurationHistogram::with_precision(PER_ROBOT_LOWEST_NS, PER_ROBOT_DIGITS);
        let mut sparse = DurationHistogram::per_robot();
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        for k in 0..5_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let ns = match k % 4 {
                0 => 1 + x % 200,
                1 => 10_000 + x % 5_000,
                2 => 1_000_000 + x % 3_000_000,
                _ => x % 70_000_000_000,
            };
            dense.record_ns(ns);
            sparse.record_ns(ns);
            if k % 97 == 0 {
                assert_eq!(sparse.percentiles(), dense.percentiles(), "after {k}");
                assert_eq!(sparse.p50_p99_us(), dense.p50_p99_us(), "after {k}");
            }
        }
        assert_eq!(sparse.percentiles(), dense.percentiles());
        assert_eq!(sparse.percentiles().count, 5_000);
        let Repr::Sparse(s) = &sparse.0 else {
            panic!("a robot's histogram is sparse")
        };
        // Far fewer buckets than the dense one counts.
        let Repr::Dense(d) = &dense.0 else {
            panic!("with_precision is dense")
        };
        assert!(s.buckets.len() < d.distinct_values(), "{}", s.buckets.len());
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
