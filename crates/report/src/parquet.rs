//! Reading `trajectory.parquet` (the run folder crate's schema) into the
//! same tracks as `trajectory.csv`.

use crate::RenderError;
use crate::run::{Sample, Tracks, Trajectory};
use mrsim_runfolder::trajectory::{TrajectoryError, read_parquet_trajectory};
use std::path::Path;

/// Reads the Parquet trajectory at `path`.
pub(crate) fn load(path: &Path) -> Result<Trajectory, RenderError> {
    if !path.exists() {
        return Err(RenderError::Missing {
            path: path.to_path_buf(),
        });
    }
    let table = read_parquet_trajectory(path).map_err(|e| match e {
        TrajectoryError::Io { path, source } => RenderError::Io { path, source },
        other => RenderError::Parquet(other),
    })?;
    let mut tracks = Tracks::default();
    for (i, row) in table.rows().enumerate() {
        let sample = Sample {
            tick: row.tick,
            time: row.time,
            x: row.x,
            y: row.y,
            vx: row.vx,
            vy: row.vy,
        };
        tracks
            .push(row.body, row.kind, sample)
            .map_err(|reason| RenderError::Parse {
                path: path.to_path_buf(),
                line: i + 1,
                reason,
            })?;
    }
    Ok(tracks.finish())
}
