//! What the replay draws of unicycles and laser scanners, read from the
//! run folder beside the rest: the `theta` column of trajectory.csv (only
//! present when the scenario has a unicycle robot) and scan.csv (only when
//! a robot records its scans). Both are optional; a file or column that is
//! missing or unreadable just leaves the page without it.

use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::Path;

/// Adds `theta` (one heading per frame, or null) to each robot of `data`
/// named in `unicycles`
/// and `scans` (per robot name: angleMin, angleIncrement, rangeMax and one
/// list of ranges per frame, null where no scan or no return) to `data`.
pub(crate) fn add(data: &mut Value, dir: &Path, ticks: &[u64], unicycles: &[&str]) {
    let frame_of: HashMap<u64, usize> = ticks.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    if let Ok(text) = std::fs::read_to_string(dir.join(mrsim_runfolder::TRAJECTORY_FILE)) {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        if let Some(col) = header.iter().position(|h| *h == "theta") {
            let mut theta: HashMap<String, Vec<Value>> = HashMap::new();
            for l in lines {
                let f: Vec<&str> = l.split(',').collect();
                let (Some(t), Some(name), Some(th)) = (
                    f.first().and_then(|t| t.parse::<u64>().ok()),
                    f.get(2),
                    f.get(col).and_then(|v| v.parse::<f64>().ok()),
                ) else {
                    continue;
                };
                let Some(&frame) = frame_of.get(&t) else {
                    continue;
                };
                let row = theta
                    .entry(name.to_string())
                    .or_insert_with(|| vec![Value::Null; ticks.len()]);
                row[frame] = json!((th * 1000.0).round() / 1000.0);
            }
            if let Some(robots) = data["robots"].as_array_mut() {
                for r in robots {
                    let name = r["name"].as_str().unwrap_or("").to_string();
                    if !unicycles.contains(&name.as_str()) {
                        continue;
                    }
                    if let Some(t) = theta.remove(&name) {
                        r["theta"] = Value::Array(t);
                    }
                }
            }
        }
    }
    let Ok(text) = std::fs::read_to_string(dir.join("scan.csv")) else {
        return;
    };
    let mut scans: serde_json::Map<String, Value> = serde_json::Map::new();
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() < 5 {
            continue;
        }
        let (Ok(t), Ok(a0), Ok(inc), Ok(max)) = (
            f[0].parse::<u64>(),
            f[2].parse::<f64>(),
            f[3].parse::<f64>(),
            f[4].parse::<f64>(),
        ) else {
            continue;
        };
        let Some(&frame) = frame_of.get(&t) else {
            continue;
        };
        let entry = scans.entry(f[1].to_string()).or_insert_with(|| {
            json!({
                "angleMin": a0, "angleIncrement": inc, "rangeMax": max,
                "frames": vec![Value::Null; ticks.len()],
            })
        });
        let ranges: Vec<Value> = f[5..]
            .iter()
            .filter(|v| !v.is_empty())
            .map(|v| match v.parse::<f64>() {
                Ok(r) if r.is_finite() => json!((r * 1000.0).round() / 1000.0),
                _ => Value::Null,
            })
            .collect();
        entry["frames"][frame] = Value::Array(ranges);
    }
    data["scans"] = Value::Object(scans);
}
