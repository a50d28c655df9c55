//! What a bench takes from a run: bench.json's row from the run folder's
//! metrics.json and usage.json, and the overhead over the bare fan-out
//! from pairs of rows.

use crate::transport::Transport;
use mrsim_runfolder::bench::{BenchRow, MedianP99, Overhead, Quantiles};
use mrsim_runfolder::usage::Usage;
use mrsim_runfolder::{Percentiles, RunMetrics};

/// Percentiles of a metrics.json histogram; none where it has no samples.
pub(super) fn quantiles(p: &Percentiles) -> Quantiles {
    let has = p.count > 0;
    Quantiles {
        p50: has.then_some(p.p50),
        p99: has.then_some(p.p99),
        p999: has.then_some(p.p999),
        max: has.then_some(p.max),
    }
}

/// Median and 99th percentile of a metrics.json histogram; none where it
/// has no samples.
pub(super) fn median_p99(p: &Percentiles) -> MedianP99 {
    let q = quantiles(p);
    MedianP99 {
        p50: q.p50,
        p99: q.p99,
    }
}

/// One row of bench.json from a run folder's metrics.json and usage.json
/// (the bench's own fields, `cpus`, `rt`, `planner`, `run_dir`, left
/// empty).
pub(super) fn row_from_run(
    agents: usize,
    transport: Transport,
    rate: f64,
    metrics: &RunMetrics,
    usage: &Usage,
) -> BenchRow {
    let t = &metrics.timing;
    let wall = t.wall_s;
    let ticks = metrics.ticks;
    let misses: u64 = metrics.robots.values().map(|r| r.deadline_misses).sum();
    let slots = ticks * agents as u64;
    let agents_cpu = usage.agents_cpu_s;
    // In-process, the world's process holds the agent threads too.
    let world_cpu = match transport {
        Transport::Shm | Transport::Zenoh => t.process_cpu_s,
        Transport::Inproc => (t.process_cpu_s - agents_cpu).max(0.0),
    };
    let pct_of_wall = |s: f64| if wall > 0.0 { 100.0 * s / wall } else { 0.0 };
    let mb = |kb: u64| kb as f64 / 1024.0;
    BenchRow {
        agents,
        transport: transport.name().to_string(),
        rate_hz: rate,
        roundtrip_us: quantiles(&t.latency_us),
        allin_us: median_p99(&t.allin_us),
        miss_rate: if slots > 0 {
            misses as f64 / slots as f64
        } else {
            0.0
        },
        jitter_us_p99: quantiles(&t.jitter_us).p99,
        world_cpu_pct: pct_of_wall(world_cpu),
        agents_cpu_pct: pct_of_wall(agents_cpu),
        steal_pct: t.cpus_steal_s.map(pct_of_wall),
        world_rss_mb: Some(mb(t.process_maxrss_kb)),
        agent_rss_mb: usage.agent_maxrss_kb.map(mb),
        wake_us: quantiles(&t.wake_us),
        compute_us: quantiles(&t.compute_us),
        world_tick_us: quantiles(&t.world_tick_us),
        physics_us: quantiles(&t.physics_us),
        ticks,
        deadline_misses: misses,
        wall_s: wall,
        // Simulated over wall time of the tick loop: below 1 the world could
        // not hold the rate (ticks started ever later, see the jitter), and
        // the miss rate alone understates how far it fell behind.
        realtime_factor: metrics.realtime_factor,
        ..Default::default()
    }
}

/// The value at fraction `q` of sorted `xs`, interpolated linearly between
/// neighbours (as numpy's default).
pub(super) fn quantile(xs: &[f64], q: f64) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    let pos = q * (xs.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    xs[lo] + (xs[hi] - xs[lo]) * (pos - lo as f64)
}

/// Per agent count, transport and load: the ratio of mrsim's all-in
/// median to the bare fan-out's measured right after it, over the
/// repetitions, with its median, quartiles and range.
pub(super) fn overhead(rows: &[BenchRow]) -> Vec<Overhead> {
    let mut out: Vec<Overhead> = Vec::new();
    for r in rows {
        let ratio = match (r.allin_us.p50, r.baseline_allin_us.and_then(|b| b.p50)) {
            (Some(a), Some(b)) if b > 0.0 => a / b,
            _ => continue,
        };
        match out
            .iter_mut()
            .find(|o| o.agents == r.agents && o.transport == r.transport && o.stress == r.stress)
        {
            Some(o) => o.ratios.push(ratio),
            None => out.push(Overhead {
                agents: r.agents,
                transport: r.transport.clone(),
                stress: r.stress,
                ratios: vec![ratio],
                ..Default::default()
            }),
        }
    }
    for o in &mut out {
        let mut xs = o.ratios.clone();
        xs.sort_by(f64::total_cmp);
        o.pairs = xs.len();
        o.median = quantile(&xs, 0.5);
        o.q1 = quantile(&xs, 0.25);
        o.q3 = quantile(&xs, 0.75);
        o.min = xs[0];
        o.max = xs[xs.len() - 1];
    }
    out
}
