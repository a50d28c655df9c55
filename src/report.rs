//! `mrsim report DIR`: redraws a run folder's plots and replay page.
//!
//! A folder that is not a run's (missing files, malformed lines) is refused
//! like a bad scenario (exit 2, the file and line on stderr); a run cut
//! short (no metrics.json, a last line cut mid-way) is drawn as far as it
//! was recorded, with a note.

use anyhow::Result;
use mrsim_report::RenderError;
use std::path::Path;

/// Runs `mrsim report DIR`; returns the exit status.
pub fn main(dir: &Path) -> Result<i32> {
    match mrsim_report::render_all(dir) {
        Ok(()) => {
            if !dir.join(mrsim_runfolder::METRICS_FILE).exists() {
                eprintln!(
                    "note: {} has no {}: the run was cut short; drew what was recorded",
                    dir.display(),
                    mrsim_runfolder::METRICS_FILE
                );
            }
            println!(
                "wrote {0}/plot.svg, {0}/plot.png, {0}/replay.html",
                dir.display()
            );
            Ok(0)
        }
        Err(
            e @ (RenderError::NotADirectory { .. }
            | RenderError::Missing { .. }
            | RenderError::Parse { .. }
            | RenderError::Json { .. }),
        ) => Err(crate::exit::invalid(format!(
            "cannot report on {}: {e}",
            dir.display()
        ))),
        Err(e) => Err(anyhow::anyhow!("cannot report on {}: {e}", dir.display())),
    }
}
