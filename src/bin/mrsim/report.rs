//! `mrsim report DIR`: redraws a run folder's plots and replay page.
//!
//! A folder that is not a run's (missing files, malformed lines) is refused
//! like a bad scenario (exit 2, the file and line on stderr); a run cut
//! short (no metrics.json, a last line cut mid-way) is drawn as far as it
//! was recorded, with a note. A run whose `[output] trajectory = "none"`
//! is drawn without tracks (walls, starts and goals; the replay page says
//! the run has no trajectory), also with a note; a Parquet trajectory is
//! read like the CSV.

use anyhow::Result;
use mrsim_report::RenderError;
use std::path::Path;

/// Runs `mrsim report DIR`; returns the exit status.
pub fn main(dir: &Path) -> Result<i32> {
    match mrsim_report::render_all(dir) {
        Ok(cut) => {
            for c in &cut {
                eprintln!("note: {c}");
            }
            if !dir.join(mrsim_runfolder::METRICS_FILE).exists() {
                eprintln!(
                    "note: {} has no {}: the run was cut short; drew what was recorded",
                    dir.display(),
                    mrsim_runfolder::METRICS_FILE
                );
            }
            if !dir.join(mrsim_runfolder::TRAJECTORY_FILE).exists()
                && !dir.join(mrsim_runfolder::TRAJECTORY_PARQUET_FILE).exists()
            {
                eprintln!(
                    "note: {} has no trajectory (output.trajectory = \"none\"): drew the scene without tracks",
                    dir.display()
                );
            }
            println!(
                "wrote {0}/{1}, {0}/{2}, {0}/{3}",
                dir.display(),
                mrsim_runfolder::PLOT_SVG_FILE,
                mrsim_runfolder::PLOT_PNG_FILE,
                mrsim_runfolder::REPLAY_FILE
            );
            Ok(0)
        }
        Err(e) => Err(refusal("report on", dir, e)),
    }
}

/// Why `what` could not be done with the run folder `dir`: a folder that
/// is not a run's is refused as bad input (exit 2), anything else is a
/// failure (exit 1).
pub(crate) fn refusal(what: &str, dir: &Path, e: RenderError) -> anyhow::Error {
    match e {
        RenderError::NotADirectory { .. }
        | RenderError::Missing { .. }
        | RenderError::Parse { .. }
        | RenderError::Parquet(_)
        | RenderError::Json { .. } => {
            crate::exit::invalid(format!("cannot {what} {}: {e}", dir.display()))
        }
        e => anyhow::anyhow!("cannot {what} {}: {e}", dir.display()),
    }
}
