//! The output folder of a run, a sweep or a bench.

use crate::error::Invalid;
use std::path::{Path, PathBuf};

/// The output folder: `out`, or a fresh folder under `runs/` named after
/// `name` and the time; created and checked writable.
pub fn prepare(out: Option<&Path>, name: &str) -> Result<PathBuf, Invalid> {
    let dir = match out {
        Some(d) => d.to_path_buf(),
        None => fresh(name)?,
    };
    std::fs::create_dir_all(&dir).map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot create it: {e}",
            dir.display()
        ))
    })?;
    let probe = dir.join(".mrsim-write-test");
    std::fs::write(&probe, b"ok").map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot write in it: {e}",
            dir.display()
        ))
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(dir)
}

/// A new folder `runs/<name>-<secs>-<n>`.
fn fresh(name: &str) -> Result<PathBuf, Invalid> {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let safe: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let base = PathBuf::from("runs");
    std::fs::create_dir_all(&base).map_err(|e| {
        Invalid(format!(
            "output folder {}: cannot create it: {e}",
            base.display()
        ))
    })?;
    // create_dir fails if the folder exists: two launchers started in the
    // same second never share a folder.
    let mut n = 0;
    loop {
        let d = base.join(format!("{safe}-{secs}-{n}"));
        match std::fs::create_dir(&d) {
            Ok(()) => return Ok(d),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 10_000 => n += 1,
            Err(e) => {
                return Err(Invalid(format!(
                    "output folder {}: cannot create it: {e}",
                    d.display()
                )));
            }
        }
    }
}
