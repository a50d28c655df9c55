//! `mrsim export DIR --mcap`: writes a run folder as run.mcap for Foxglove
//! (or Lichtblick), from the files the run wrote, like `mrsim report`.

use anyhow::Result;
use std::path::Path;

/// Runs `mrsim export DIR`; returns the exit status.
pub fn main(dir: &Path, mcap: bool) -> Result<i32> {
    if !mcap {
        return Err(crate::exit::invalid(
            "mrsim export: say which format to write (--mcap: run.mcap for Foxglove)",
        ));
    }
    let written =
        mrsim_report::export_mcap(dir).map_err(|e| crate::report::refusal("export", dir, e))?;
    if let Some(yaml) = &written.map_not_found {
        eprintln!(
            "note: the map {yaml} cannot be read from here: run.mcap has its outline among the \
             walls but no /map grid (export from where the run was started)"
        );
    }
    for c in &written.cut {
        eprintln!("note: {c}");
    }
    println!("wrote {}", written.path.display());
    Ok(0)
}
