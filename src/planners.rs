//! `mrsim planners`: what is available.

use anyhow::Result;

/// Lists the planners with a line each.
pub fn main() -> Result<i32> {
    for p in mrsim_planners::PLANNERS {
        println!("{:<20} {}", p.name, p.summary);
    }
    Ok(0)
}
