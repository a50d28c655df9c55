//! `mrsim planners`: what is available.

use anyhow::Result;

/// Lists the planners with a line each: the built-in ones, then
/// `external` (a robot driven by the user's own program).
pub fn main() -> Result<i32> {
    for p in mrsim_planners::Registry::builtin().entries() {
        println!("{:<20} {}", p.name(), p.summary());
    }
    Ok(0)
}
