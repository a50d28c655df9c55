//! `bench.json`: `mrsim bench`'s rows, `{"rows": [...]}`, one row per
//! agent count and transport.
//!
//! The fields are declared in alphabetical order: that is the order the
//! bench writes them in (and `bench.csv`'s column order follows it).
//! Percentiles of a histogram without samples are null.

use serde::{Deserialize, Serialize};

/// `bench.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BenchDoc {
    /// One per run.
    pub rows: Vec<BenchRow>,
    /// `--baseline`: mrsim's all-in median over the bare fan-out's, per
    /// agent count, transport and load, over the `--repeat` interleaved
    /// pairs.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub overhead: Vec<Overhead>,
}

/// mrsim's overhead over the bare iceoryx2 fan-out: the ratio of the
/// all-in medians (mrsim's run over the baseline run right after it), over
/// several interleaved pairs, so that one command gives a figure that holds
/// from run to run although each side alone moves.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Overhead {
    /// Robots (one agent each).
    pub agents: usize,
    /// Largest ratio.
    pub max: f64,
    /// Median ratio.
    pub median: f64,
    /// Smallest ratio.
    pub min: f64,
    /// Pairs with both medians.
    pub pairs: usize,
    /// First quartile of the ratios.
    pub q1: f64,
    /// Third quartile of the ratios.
    pub q3: f64,
    /// Every pair's ratio, in the order measured.
    pub ratios: Vec<f64>,
    /// CPU-bound processes run beside it (`--stress`).
    pub stress: usize,
    /// `shm`, `inproc` or `zenoh`.
    pub transport: String,
}

/// Median, 99th, 99.9th percentile and largest sample, µs (null: no sample).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Quantiles {
    /// Largest sample.
    pub max: Option<f64>,
    /// Median.
    pub p50: Option<f64>,
    /// 99th percentile.
    pub p99: Option<f64>,
    /// 99.9th percentile.
    pub p999: Option<f64>,
}

/// Median and 99th percentile, µs (null: no sample).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MedianP99 {
    /// Median.
    pub p50: Option<f64>,
    /// 99th percentile.
    pub p99: Option<f64>,
}

/// One row of `bench.json`: one realtime run of the bench's crossing scene.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BenchRow {
    /// Largest peak RSS of one agent process, MiB (null in-process).
    pub agent_rss_mb: Option<f64>,
    /// Robots (one agent each).
    pub agents: usize,
    /// CPU of the agents over the tick loop's wall time, %.
    pub agents_cpu_pct: f64,
    /// Snapshot published -> last command in, µs.
    pub allin_us: MedianP99,
    /// `--baseline`: bare iceoryx2's all-in time for this agent count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_allin_us: Option<MedianP99>,
    /// `--baseline`: bare iceoryx2's round trip for this agent count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_roundtrip_us: Option<MedianP99>,
    /// Planner compute time, µs.
    pub compute_us: Quantiles,
    /// CPUs the bench pinned everything to.
    pub cpus: Vec<usize>,
    /// Deadline misses, all robots.
    pub deadline_misses: u64,
    /// Tick jitter's 99th percentile, µs (null: no sample).
    pub jitter_us_p99: Option<f64>,
    /// Deadline misses over (ticks x agents).
    pub miss_rate: f64,
    /// Physics step within the world's tick, µs.
    pub physics_us: Quantiles,
    /// Planner of every robot.
    pub planner: String,
    /// Tick rate, Hz.
    pub rate_hz: f64,
    /// Simulated over wall time of the tick loop.
    pub realtime_factor: f64,
    /// Which of the `--repeat` measurements it is (1-based).
    pub repeat: usize,
    /// Snapshot published -> command received by the world, µs.
    pub roundtrip_us: Quantiles,
    /// Under SCHED_FIFO (`--rt`).
    pub rt: bool,
    /// The run's folder.
    pub run_dir: String,
    /// Time the hypervisor stole from the run's CPUs, % of wall (null where
    /// /proc/stat is unreadable).
    pub steal_pct: Option<f64>,
    /// CPU-bound processes run beside it on its CPUs (`--stress`).
    pub stress: usize,
    /// Ticks run.
    pub ticks: u64,
    /// `shm` or `inproc`.
    pub transport: String,
    /// Snapshot published -> agent awake, µs.
    pub wake_us: Quantiles,
    /// Wall-clock duration of the tick loop, s.
    pub wall_s: f64,
    /// CPU of the world (without in-process agents) over wall time, %.
    pub world_cpu_pct: f64,
    /// Peak RSS of the world's process, MiB.
    pub world_rss_mb: Option<f64>,
    /// The world's own work per tick, µs.
    pub world_tick_us: Quantiles,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_writes_its_keys_in_the_sorted_order_the_bench_writes() {
        let mut row = BenchRow {
            baseline_allin_us: Some(MedianP99::default()),
            baseline_roundtrip_us: Some(MedianP99::default()),
            ..Default::default()
        };
        for _ in 0..2 {
            let text = serde_json::to_string(&row).expect("a row serializes");
            let keys = top_level_keys(&text);
            let mut sorted = keys.clone();
            sorted.sort();
            assert!(keys.len() > 20, "{keys:?}");
            assert_eq!(keys, sorted);
            row.baseline_allin_us = None;
            row.baseline_roundtrip_us = None;
        }
    }

    /// The keys of a compact JSON object, in the order written (no strings
    /// with brackets inside: the default row has empty strings).
    fn top_level_keys(text: &str) -> Vec<String> {
        let (mut depth, mut keys, mut chars) = (0, Vec::new(), text.chars().peekable());
        let mut expect_key = false;
        while let Some(c) = chars.next() {
            match c {
                '{' | '[' => {
                    depth += 1;
                    expect_key = depth == 1;
                }
                '}' | ']' => depth -= 1,
                ',' => expect_key = depth == 1,
                '"' => {
                    let s: String = chars.by_ref().take_while(|&c| c != '"').collect();
                    if expect_key {
                        keys.push(s);
                        expect_key = false;
                    }
                }
                _ => {}
            }
        }
        keys
    }
}
