//! What the replay page and run.mcap show of unicycles and laser scanners,
//! read from the run folder beside the rest: the `theta` column of
//! trajectory.csv (only present when the scenario has a unicycle robot) and
//! scan.csv (only when a robot records its scans). Both are optional; a
//! file or column that is missing or unreadable just leaves the page (or
//! the MCAP file) without it.

use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::Path;

/// One row of scan.csv: a robot's scan at a tick, in the robot's frame
/// (beam `k` points at `angle_min + k * angle_increment` from its heading).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ScanRow {
    pub tick: u64,
    pub robot: String,
    pub angle_min: f64,
    pub angle_increment: f64,
    pub range_max: f64,
    /// One range per beam, `None` where the beam has no return.
    pub ranges: Vec<Option<f64>>,
}

/// Headings by robot name, as (tick, theta) in file order, from the `theta`
/// column of trajectory.csv; empty when the file has no such column.
pub(crate) fn headings(dir: &Path) -> HashMap<String, Vec<(u64, f64)>> {
    let mut out: HashMap<String, Vec<(u64, f64)>> = HashMap::new();
    let Ok(text) = std::fs::read_to_string(dir.join(mrsim_runfolder::TRAJECTORY_FILE)) else {
        return out;
    };
    let Ok(rows) = mrsim_runfolder::csv::trajectory_rows(&text) else {
        return out;
    };
    for (_, row) in rows.flatten() {
        if let Some(theta) = row.theta {
            out.entry(row.body.to_string())
                .or_default()
                .push((row.tick, theta));
        }
    }
    out
}

/// Every readable row of scan.csv, in file order (empty without the file).
pub(crate) fn scans(dir: &Path) -> Vec<ScanRow> {
    let Ok(text) = std::fs::read_to_string(dir.join("scan.csv")) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        if f.len() < 5 {
            continue;
        }
        let (Ok(tick), Ok(angle_min), Ok(angle_increment), Ok(range_max)) = (
            f[0].parse::<u64>(),
            f[2].parse::<f64>(),
            f[3].parse::<f64>(),
            f[4].parse::<f64>(),
        ) else {
            continue;
        };
        let ranges = f[5..]
            .iter()
            .filter(|v| !v.is_empty())
            .map(|v| v.parse::<f64>().ok().filter(|r| r.is_finite()))
            .collect();
        out.push(ScanRow {
            tick,
            robot: f[1].to_string(),
            angle_min,
            angle_increment,
            range_max,
            ranges,
        });
    }
    out
}

/// Adds `theta` (one heading per frame, or null) to each robot of `data`
/// named in `unicycles`
/// and `scans` (per robot name: angleMin, angleIncrement, rangeMax and one
/// list of ranges per frame, null where no scan or no return) to `data`.
pub(crate) fn add(data: &mut Value, dir: &Path, ticks: &[u64], unicycles: &[&str]) {
    let frame_of: HashMap<u64, usize> = ticks.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    let mut theta = headings(dir);
    if !theta.is_empty()
        && let Some(robots) = data["robots"].as_array_mut()
    {
        for r in robots {
            let name = r["name"].as_str().unwrap_or("").to_string();
            if !unicycles.contains(&name.as_str()) {
                continue;
            }
            if let Some(rows) = theta.remove(&name) {
                let mut frames = vec![Value::Null; ticks.len()];
                for (t, th) in rows {
                    if let Some(&frame) = frame_of.get(&t) {
                        frames[frame] = json!((th * 1000.0).round() / 1000.0);
                    }
                }
                r["theta"] = Value::Array(frames);
            }
        }
    }
    let rows = scans(dir);
    if rows.is_empty() && !dir.join("scan.csv").exists() {
        return;
    }
    let mut out: serde_json::Map<String, Value> = serde_json::Map::new();
    for row in rows {
        let Some(&frame) = frame_of.get(&row.tick) else {
            continue;
        };
        let entry = out.entry(row.robot.clone()).or_insert_with(|| {
            json!({
                "angleMin": row.angle_min, "angleIncrement": row.angle_increment,
                "rangeMax": row.range_max,
                "frames": vec![Value::Null; ticks.len()],
            })
        });
        let ranges: Vec<Value> = row
            .ranges
            .iter()
            .map(|r| r.map_or(Value::Null, |r| json!((r * 1000.0).round() / 1000.0)))
            .collect();
        entry["frames"][frame] = Value::Array(ranges);
    }
    data["scans"] = Value::Object(out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder_with_trajectory(name: &str, csv: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("mrsim-sensing-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(dir.join(mrsim_runfolder::TRAJECTORY_FILE), csv).expect("write");
        dir
    }

    #[test]
    fn headings_are_read_per_body_from_the_theta_column_skipping_unreadable_rows() {
        let dir = folder_with_trajectory(
            "theta",
            "tick,time,body,kind,x,y,vx,vy,theta\n\
             0,0,u0,robot,0,0,0,0,0.5\n\
             0,0,o1,obstacle,1,1,0,0,0\n\
             1,0.1,u0,robot,0,0,0,0,x\n\
             2,0.2,u0,robot,0,0,0,0,-1.25\n",
        );
        let h = headings(&dir);
        assert_eq!(h["u0"], vec![(0, 0.5), (2, -1.25)]);
        assert_eq!(h["o1"], vec![(0, 0.0)]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_trajectory_without_a_theta_column_has_no_headings() {
        let dir = folder_with_trajectory(
            "notheta",
            "tick,time,body,kind,x,y,vx,vy\n0,0,r0,robot,0,0,0,0\n",
        );
        assert!(headings(&dir).is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
