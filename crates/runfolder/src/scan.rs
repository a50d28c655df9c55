//! `scan.csv`: the laser scans of the robots whose `sensor` has `record =
//! true`, one row per robot and tick, written by the world's recording
//! thread.
//!
//! Columns: `tick,robot,angle_min,angle_increment,range_max,r0,...`; angles
//! in radians in the robot's frame (ROS LaserScan's meanings, written in
//! full precision), ranges with six decimals, `inf` where a beam hit
//! nothing within `range_max`. Robots with fewer beams than the most leave
//! the last fields empty.

use crate::RowsError;
use crate::stream::{Cut, read_whole_rows};
use std::path::Path;

/// The columns before the ranges.
pub const FIXED_COLUMNS: [&str; 5] = ["tick", "robot", "angle_min", "angle_increment", "range_max"];

/// The header of a file whose widest scan has `beams` beams.
pub fn header(beams: usize) -> String {
    let mut h = FIXED_COLUMNS.join(",");
    for k in 0..beams {
        h.push_str(&format!(",r{k}"));
    }
    h
}

/// One row: a robot's scan at a tick, in the robot's frame (beam `k`
/// points at `angle_min + k * angle_increment` from its heading).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRow {
    /// The tick.
    pub tick: u64,
    /// The robot's name.
    pub robot: String,
    /// First beam's angle, rad.
    pub angle_min: f64,
    /// Angle between beams, rad.
    pub angle_increment: f64,
    /// Longest range measured.
    pub range_max: f64,
    /// One range per beam, `None` where the beam has no return.
    pub ranges: Vec<Option<f64>>,
}

/// Parses scan.csv's text (whole rows); the first bad line is the error
/// (`(line, reason)`).
pub fn parse_scans(text: &str) -> Result<Vec<ScanRow>, (usize, String)> {
    let mut out = Vec::new();
    let mut lines = crate::csv::numbered_lines(text);
    let Some((_, head)) = lines.next() else {
        return Ok(out);
    };
    let names: Vec<&str> = head.split(',').map(str::trim).collect();
    if names.len() < FIXED_COLUMNS.len() || names[..FIXED_COLUMNS.len()] != FIXED_COLUMNS {
        return Err((
            1,
            format!("expected a header starting `{}`", FIXED_COLUMNS.join(",")),
        ));
    }
    let width = names.len();
    for (n, line) in lines {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != width {
            return Err((n, format!("{} fields, the header has {width}", f.len())));
        }
        let num = |k: usize| {
            f[k].parse::<f64>().map_err(|_| {
                (
                    n,
                    format!("column `{}`: `{}` is not a number", names[k], f[k]),
                )
            })
        };
        let tick = f[0]
            .parse::<u64>()
            .map_err(|_| (n, format!("column `tick`: `{}` is not a tick number", f[0])))?;
        let mut ranges = Vec::with_capacity(width - FIXED_COLUMNS.len());
        for (k, cell) in f.iter().enumerate().skip(FIXED_COLUMNS.len()) {
            if cell.is_empty() {
                continue;
            }
            ranges.push(Some(num(k)?).filter(|r| r.is_finite()));
        }
        out.push(ScanRow {
            tick,
            robot: f[1].to_string(),
            angle_min: num(2)?,
            angle_increment: num(3)?,
            range_max: num(4)?,
            ranges,
        });
    }
    Ok(out)
}

/// scan.csv's rows and, if its last row is torn, the cut.
pub type ScanFile = (Vec<ScanRow>, Option<Cut>);

/// Reads `dir/scan.csv`: `None` without the file, else its rows and the
/// cut, if its last row is torn.
pub fn read_scans(dir: &Path) -> Result<Option<ScanFile>, RowsError> {
    let path = dir.join(crate::SCAN_FILE);
    let Some((text, cut)) = read_whole_rows(&path).map_err(|source| RowsError::Io {
        path: path.clone(),
        source,
    })?
    else {
        return Ok(None);
    };
    let rows =
        parse_scans(&text).map_err(|(line, reason)| RowsError::Row { path, line, reason })?;
    Ok(Some((rows, cut)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_read_with_empty_cells_left_out_and_inf_as_no_return() {
        let text = format!("{}\n3,r0,-1.5,0.5,4,1.000000,inf,\n", header(3));
        let rows = parse_scans(&text).expect("rows");
        assert_eq!(rows.len(), 1);
        assert_eq!((rows[0].tick, rows[0].robot.as_str()), (3, "r0"));
        assert_eq!(rows[0].ranges, vec![Some(1.0), None]);
    }

    #[test]
    fn a_bad_middle_row_is_an_error_at_its_line_and_a_torn_last_row_a_cut() {
        let dir = std::env::temp_dir().join(format!("mrsim-scan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join(crate::SCAN_FILE);
        let good = "3,r0,-1.5,0.5,4,1.000000,inf\n";
        std::fs::write(&path, format!("{}\n{good}3,r1,x,0.5,4,1,1\n", header(2))).expect("w");
        let e = read_scans(&dir).expect_err("bad").to_string();
        assert!(
            e.ends_with("scan.csv:3: column `angle_min`: `x` is not a number"),
            "{e}"
        );
        std::fs::write(&path, format!("{}\n{good}{good}4,r0,-1.5,0.", header(2))).expect("w");
        let (rows, cut) = read_scans(&dir).expect("read").expect("file");
        assert_eq!(rows.len(), 2);
        assert_eq!(cut.expect("cut").line, 4);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
