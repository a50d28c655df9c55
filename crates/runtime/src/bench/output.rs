//! What a bench writes besides bench.json: bench.csv's flattened rows and
//! the `--stress` figure.

use mrsim_report::sweep_plot::{Figure, Panel, Point, Series};
use mrsim_runfolder::bench::BenchRow;
use serde_json::Value;

/// `stress.svg`: round trip and misses against the number of CPU-bound
/// processes, one line per transport and agent count, each point the mean
/// over the repetitions with its 95 % interval.
pub(super) fn stress_figure(rows: &[BenchRow], levels: &[usize]) -> Figure {
    let mut lines: Vec<(String, usize)> = Vec::new();
    for r in rows {
        let key = (r.transport.clone(), r.agents);
        if !lines.contains(&key) {
            lines.push(key);
        }
    }
    type Metric = (&'static str, &'static str, fn(&BenchRow) -> Option<f64>);
    let metrics: [Metric; 4] = [
        ("round trip p50", "us", |r| r.roundtrip_us.p50),
        ("round trip p99", "us", |r| r.roundtrip_us.p99),
        ("all-in p99", "us (published -> last command in)", |r| {
            r.allin_us.p99
        }),
        ("deadline misses", "% of agent-ticks", |r| {
            Some(100.0 * r.miss_rate)
        }),
    ];
    let panels = metrics
        .iter()
        .map(|(title, unit, value)| Panel {
            title: title.to_string(),
            y_label: unit.to_string(),
            fraction: false,
            lines: lines
                .iter()
                .map(|(t, n)| {
                    levels
                        .iter()
                        .filter_map(|&k| {
                            let xs: Vec<f64> = rows
                                .iter()
                                .filter(|r| r.transport == *t && r.agents == *n && r.stress == k)
                                .filter_map(value)
                                .collect();
                            let (mean, half_width) = crate::sweep::mean_ci(&xs);
                            Some(Point {
                                x: k as f64,
                                mean: mean?,
                                half_width,
                            })
                        })
                        .collect()
                })
                .collect(),
        })
        .collect();
    Figure {
        title: "mrsim bench --stress: timing against CPU-bound load on the run's CPUs".into(),
        x_label: "CPU-bound processes beside the run".into(),
        series: lines
            .iter()
            .enumerate()
            .map(|(i, (t, n))| Series {
                label: format!("{t}, {n} agents"),
                colour: i,
                measured: false,
            })
            .collect(),
        panels,
    }
}

/// bench.csv: the rows flattened (nested percentiles as `field_p50` ...).
pub(super) fn csv(rows: &[Value]) -> String {
    let mut cols: Vec<String> = Vec::new();
    let flat: Vec<Vec<(String, String)>> = rows
        .iter()
        .map(|r| {
            let mut cells = Vec::new();
            if let Some(o) = r.as_object() {
                for (k, v) in o {
                    match v {
                        Value::Object(inner) => {
                            for (ik, iv) in inner {
                                cells.push((format!("{k}_{ik}"), cell(iv)));
                            }
                        }
                        other => cells.push((k.clone(), cell(other))),
                    }
                }
            }
            cells
        })
        .collect();
    for r in &flat {
        for (k, _) in r {
            if !cols.contains(k) {
                cols.push(k.clone());
            }
        }
    }
    let mut out = cols.join(",");
    out.push('\n');
    for r in &flat {
        let line: Vec<String> = cols
            .iter()
            .map(|c| {
                r.iter()
                    .find(|(k, _)| k == c)
                    .map(|(_, v)| v.clone())
                    .unwrap_or_default()
            })
            .collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

fn cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        Value::Array(a) => a.iter().map(cell).collect::<Vec<_>>().join(" "),
        other => other.to_string(),
    }
}
