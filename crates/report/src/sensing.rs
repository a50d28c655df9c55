//! What the replay page and run.mcap show of unicycles and laser scanners,
//! read from the run folder beside the rest: the `theta` column of
//! trajectory.csv (only present when the scenario has a unicycle robot) and
//! scan.csv (only when a robot records its scans; read by
//! [`mrsim_runfolder::scan`]). Both are optional: a missing file or column
//! leaves the page (or the MCAP file) without it; a bad line is an error
//! naming it, and a torn last row (a cut run) is left out.

use crate::RenderError;
use crate::load::{file_error, read_optional};
pub(crate) use mrsim_runfolder::scan::ScanRow;
use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::Path;

/// Headings by robot name, as (tick, theta) in file order, from the `theta`
/// column of trajectory.csv; empty when the file or the column is absent.
pub(crate) fn headings(dir: &Path) -> Result<HashMap<String, Vec<(u64, f64)>>, RenderError> {
    let mut out: HashMap<String, Vec<(u64, f64)>> = HashMap::new();
    let path = dir.join(mrsim_runfolder::TRAJECTORY_FILE);
    let Some(text) = read_optional(&path, &mut Vec::new())? else {
        return Ok(out);
    };
    let parse = |e: mrsim_runfolder::csv::CsvError| RenderError::Parse {
        path: path.clone(),
        line: e.line,
        reason: e.reason,
    };
    for row in mrsim_runfolder::csv::trajectory_rows(&text).map_err(parse)? {
        let (_, row) = row.map_err(parse)?;
        if let Some(theta) = row.theta {
            out.entry(row.body.to_string())
                .or_default()
                .push((row.tick, theta));
        }
    }
    Ok(out)
}

/// Every row of scan.csv, in file order; `None` without the file.
pub(crate) fn scans(dir: &Path) -> Result<Option<Vec<ScanRow>>, RenderError> {
    Ok(mrsim_runfolder::scan::read_scans(dir)
        .map_err(file_error)?
        .map(|(rows, _)| rows))
}

/// Adds `theta` (one heading per frame, or null) to each robot of `data`
/// named in `unicycles`
/// and `scans` (per robot name: angleMin, angleIncrement, rangeMax and one
/// list of ranges per frame, null where no scan or no return) to `data`.
pub(crate) fn add(
    data: &mut Value,
    dir: &Path,
    ticks: &[u64],
    unicycles: &[&str],
) -> Result<(), RenderError> {
    let frame_of: HashMap<u64, usize> = ticks.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    let mut theta = headings(dir)?;
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
    let Some(rows) = scans(dir)? else {
        return Ok(());
    };
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
    Ok(())
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
    fn headings_are_read_per_body_from_the_theta_column_up_to_a_torn_last_row() {
        let dir = folder_with_trajectory(
            "theta",
            "tick,time,body,kind,x,y,vx,vy,theta\n\
             0,0,u0,robot,0,0,0,0,0.5\n\
             0,0,o1,obstacle,1,1,0,0,0\n\
             2,0.2,u0,robot,0,0,0,0,-1.25\n\
             3,0.3,u0,robot,0,0,0,0,-1.",
        );
        let h = headings(&dir).expect("headings");
        assert_eq!(h["u0"], vec![(0, 0.5), (2, -1.25)]);
        assert_eq!(h["o1"], vec![(0, 0.0)]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_bad_heading_in_the_middle_is_an_error_at_its_line() {
        let dir = folder_with_trajectory(
            "badtheta",
            "tick,time,body,kind,x,y,vx,vy,theta\n\
             0,0,u0,robot,0,0,0,0,0.5\n\
             1,0.1,u0,robot,0,0,0,0,x\n\
             2,0.2,u0,robot,0,0,0,0,-1.25\n",
        );
        let e = headings(&dir).expect_err("bad theta").to_string();
        assert!(
            e.contains("trajectory.csv:3:") && e.contains("`theta`"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_trajectory_without_a_theta_column_has_no_headings() {
        let dir = folder_with_trajectory(
            "notheta",
            "tick,time,body,kind,x,y,vx,vy\n0,0,r0,robot,0,0,0,0\n",
        );
        assert!(headings(&dir).expect("headings").is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
