//! The bench's unit tests: rows from a run's files and the overhead of
//! pairs of rows.

use super::rows::{overhead, quantile, row_from_run};
use crate::transport::Transport;
use mrsim_runfolder::RunMetrics;
use mrsim_runfolder::bench::{BenchRow, MedianP99};
use mrsim_runfolder::usage::Usage;

fn run(transport: &str) -> (RunMetrics, Usage) {
    let metrics: RunMetrics = serde_json::from_value(serde_json::json!({
        "ticks": 10,
        "realtime_factor": 0.9,
        "robots": {"a": {"deadline_misses": 3}, "b": {"deadline_misses": 1}},
        "timing": {
            "wall_s": 2.0, "process_cpu_s": 1.0, "process_maxrss_kb": 2048,
            "latency_us": {"p50": 10.0, "p99": 20.0, "p999": 30.0, "max": 40.0, "count": 5},
            "allin_us": {"count": 0}
        }
    }))
    .expect("metrics.json");
    let usage = Usage {
        transport: transport.into(),
        agents_reported: 2,
        agents_cpu_s: 0.4,
        agent_maxrss_kb: (transport == "shm").then_some(1024),
    };
    (metrics, usage)
}

#[test]
fn a_row_counts_misses_per_slot_and_leaves_empty_histograms_null() {
    let (m, u) = run("shm");
    let row = row_from_run(2, Transport::Shm, 5.0, &m, &u);
    assert_eq!(row.miss_rate, 4.0 / 20.0);
    assert_eq!(row.roundtrip_us.p99, Some(20.0));
    assert_eq!(row.allin_us, MedianP99::default(), "no sample: null");
    assert_eq!((row.world_rss_mb, row.agent_rss_mb), (Some(2.0), Some(1.0)));
    assert_eq!(row.world_cpu_pct, 50.0);
}

fn pair(agents: usize, stress: usize, mrsim: f64, bare: f64) -> BenchRow {
    BenchRow {
        agents,
        stress,
        transport: "shm".into(),
        allin_us: MedianP99 {
            p50: Some(mrsim),
            p99: None,
        },
        baseline_allin_us: Some(MedianP99 {
            p50: Some(bare),
            p99: None,
        }),
        ..Default::default()
    }
}

#[test]
fn the_overhead_is_the_median_of_the_pairs_ratios_with_quartiles_and_range() {
    let rows = [
        pair(64, 0, 120.0, 100.0),
        pair(64, 0, 150.0, 100.0),
        pair(64, 0, 100.0, 100.0),
        pair(64, 0, 260.0, 200.0),
        pair(64, 0, 140.0, 100.0),
        pair(64, 1, 300.0, 100.0),
        // No baseline median: not a pair.
        BenchRow {
            agents: 64,
            stress: 1,
            transport: "shm".into(),
            ..Default::default()
        },
    ];
    let o = overhead(&rows);
    assert_eq!(o.len(), 2);
    assert_eq!(o[0].ratios, [1.2, 1.5, 1.0, 1.3, 1.4]);
    assert_eq!(o[0].pairs, 5);
    assert!((o[0].median - 1.3).abs() < 1e-12);
    // Sorted 1.0 1.2 1.3 1.4 1.5: quartiles at positions 1 and 3.
    assert!((o[0].q1 - 1.2).abs() < 1e-12 && (o[0].q3 - 1.4).abs() < 1e-12);
    assert_eq!((o[0].min, o[0].max), (1.0, 1.5));
    assert_eq!((o[1].stress, o[1].pairs, o[1].median), (1, 1, 3.0));
}

#[test]
fn quantiles_interpolate_between_neighbours() {
    assert_eq!(quantile(&[1.0, 2.0], 0.5), 1.5);
    assert_eq!(quantile(&[1.0, 2.0, 4.0, 8.0], 0.25), 1.75);
    assert!(quantile(&[], 0.5).is_nan());
}

#[test]
fn in_process_the_agents_cpu_is_taken_out_of_the_worlds() {
    let (m, u) = run("inproc");
    let row = row_from_run(2, Transport::Inproc, 5.0, &m, &u);
    assert!(
        (row.world_cpu_pct - 30.0).abs() < 1e-9,
        "{}",
        row.world_cpu_pct
    );
    assert!((row.agents_cpu_pct - 20.0).abs() < 1e-9);
    assert_eq!(row.agent_rss_mb, None);
}
