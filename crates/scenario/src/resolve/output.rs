//! The `[output]` table: the trajectory's format, how often it records,
//! whether the run also writes run.mcap, and the gap at which two bodies
//! meet (encounters.csv).

use crate::checks::{Rule, opt};
use crate::error::Fail;
use crate::raw::{RawOutput, S};
use crate::types::{DEFAULT_ENCOUNTER_GAP, OutputConfig, TrajectoryFormat};

/// Checks `[output]`: `every` is a whole number of ticks, at least 1.
pub(super) fn resolve_output(o: Option<&S<RawOutput>>) -> Result<OutputConfig, Fail> {
    let Some(o) = o else {
        return Ok(OutputConfig::default());
    };
    let raw = o.get_ref();
    let every = match &raw.every {
        Some(e) => {
            let k = *e.get_ref();
            u32::try_from(k).ok().filter(|&k| k >= 1).ok_or_else(|| {
                Fail::new(
                    Some(e.span()),
                    "output",
                    format!("every must be a whole number of ticks >= 1, got {k}"),
                )
            })?
        }
        None => 1,
    };
    let encounter_gap = opt(
        &raw.encounter_gap,
        "encounter_gap",
        Rule::Pos,
        "output",
        DEFAULT_ENCOUNTER_GAP,
    )?;
    Ok(OutputConfig {
        trajectory: raw
            .trajectory
            .as_ref()
            .map_or(TrajectoryFormat::Csv, |t| *t.get_ref()),
        every,
        mcap: raw.mcap.as_ref().is_some_and(|m| *m.get_ref()),
        encounter_gap,
    })
}
