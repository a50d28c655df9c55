//! What the replay page and run.mcap show of laser scanners, read from the
//! run folder beside the rest: scan.csv (only when a robot records its
//! scans; read by [`mrsim_runfolder::scan`]). It is optional: without the
//! file the page (or the MCAP file) has no scans; a bad line is an error
//! naming it, and a torn last row (a cut run) is left out.

use crate::RenderError;
use crate::load::file_error;
pub(crate) use mrsim_runfolder::scan::ScanRow;
use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::Path;

/// Every row of scan.csv, in file order; `None` without the file.
pub(crate) fn scans(dir: &Path) -> Result<Option<Vec<ScanRow>>, RenderError> {
    Ok(mrsim_runfolder::scan::read_scans(dir)
        .map_err(file_error)?
        .map(|(rows, _)| rows))
}

/// Adds `scans` (per robot name: angleMin, angleIncrement, rangeMax and
/// one list of ranges per frame, null where no scan or no return) to
/// `data`.
pub(crate) fn add(data: &mut Value, dir: &Path, ticks: &[u64]) -> Result<(), RenderError> {
    let frame_of: HashMap<u64, usize> = ticks.iter().enumerate().map(|(i, &t)| (t, i)).collect();
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
