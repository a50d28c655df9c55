//! The `[world]` table (timing, mode, seed, arena) and the `[[wall]]`
//! segments: the fixed frame every body is placed in.

use crate::checks::{Rule, opt, point};
use crate::error::Fail;
use crate::raw::{Pt, RawCpus, RawWall, RawWorld, S};
use crate::types::*;

pub(super) fn resolve_world(w: Option<&S<RawWorld>>) -> Result<WorldConfig, Fail> {
    let empty = RawWorld::default();
    let raw = w.map_or(&empty, |w| w.get_ref());
    let what = "world";
    let arena = match &raw.arena {
        Some(a) => {
            let min = point(&a.get_ref().min, "arena.min", what)?;
            let max = point(&a.get_ref().max, "arena.max", what)?;
            if !(min[0] < max[0] && min[1] < max[1]) {
                return Err(Fail::new(
                    Some(a.span()),
                    what,
                    format!(
                        "arena min must be < max in x and y, got min [{}, {}], max [{}, {}]",
                        min[0], min[1], max[0], max[1]
                    ),
                ));
            }
            Some(Arena { min, max })
        }
        None => None,
    };
    if let Some(s) = &raw.substeps
        && *s.get_ref() == 0
    {
        return Err(Fail::new(
            Some(s.span()),
            what,
            "substeps must be >= 1, got 0",
        ));
    }
    Ok(WorldConfig {
        dt: opt(&raw.dt, "dt", Rule::Pos, what, 0.1)?,
        substeps: raw.substeps.as_ref().map_or(10, |s| *s.get_ref()),
        duration: opt(&raw.duration, "duration", Rule::Pos, what, 60.0)?,
        mode: raw.mode.as_ref().map_or(Mode::Lockstep, |m| *m.get_ref()),
        on_deadline_miss: raw
            .on_deadline_miss
            .as_ref()
            .map_or(MissPolicy::Hold, |m| *m.get_ref()),
        seed: raw.seed.as_ref().map_or(1, |s| *s.get_ref()),
        arena,
        deadline: opt(&raw.deadline, "deadline", Rule::Fraction, what, 1.0)?,
        stall_timeout: opt(&raw.stall_timeout, "stall_timeout", Rule::Pos, what, 2.0)?,
        robots_per_agent: match &raw.robots_per_agent {
            Some(k) if *k.get_ref() == 0 => {
                return Err(Fail::new(
                    Some(k.span()),
                    what,
                    "robots_per_agent must be >= 1, got 0",
                ));
            }
            Some(k) => *k.get_ref(),
            None => 1,
        },
        stuck_after: opt(
            &raw.stuck_after,
            "stuck_after",
            Rule::Pos,
            what,
            DEFAULT_STUCK_AFTER,
        )?,
        end_when_stuck: raw.end_when_stuck.as_ref().is_some_and(|b| *b.get_ref()),
        end_on: raw
            .end_on
            .as_ref()
            .map(resolve_end_on)
            .transpose()?
            .unwrap_or_default(),
        cpus: raw.cpus.as_ref().map(resolve_cpus).transpose()?,
    })
}

/// `[world] end_on`: a list of `"collision"` and `"timeout"`, each once.
fn resolve_end_on(list: &S<Vec<S<String>>>) -> Result<EndOn, Fail> {
    let what = "world";
    let mut end_on = EndOn::default();
    for name in list.get_ref() {
        let slot = match name.get_ref().as_str() {
            "collision" => &mut end_on.collision,
            "timeout" => &mut end_on.timeout,
            other => {
                return Err(Fail::new(
                    Some(name.span()),
                    what,
                    format!(
                        "end_on: unknown condition `{other}` (known: {})",
                        EndOn::NAMES.join(", ")
                    ),
                ));
            }
        };
        if *slot {
            return Err(Fail::new(
                Some(name.span()),
                what,
                format!("end_on: `{}` is listed twice", name.get_ref()),
            ));
        }
        *slot = true;
    }
    Ok(end_on)
}

/// `[world.cpus]`: `count` required, `scheduler` fair by default,
/// `world_ms` 0 by default.
fn resolve_cpus(c: &S<RawCpus>) -> Result<Cpus, Fail> {
    let what = "world.cpus";
    let raw = c.get_ref();
    let count = match &raw.count {
        Some(k) if (1..=i64::from(u32::MAX)).contains(k.get_ref()) => *k.get_ref() as u32,
        Some(k) => {
            return Err(Fail::new(
                Some(k.span()),
                what,
                format!("count must be a whole number >= 1, got {}", k.get_ref()),
            ));
        }
        None => {
            return Err(Fail::new(
                Some(c.span()),
                what,
                "missing `count` (the cores the agents' CPU work shares, >= 1)",
            ));
        }
    };
    let scheduler = match &raw.scheduler {
        None => Scheduler::Fair,
        Some(s) => match s.get_ref().as_str() {
            "fair" => Scheduler::Fair,
            "fifo" => Scheduler::Fifo,
            "deadline" => Scheduler::Deadline,
            other => {
                return Err(Fail::new(
                    Some(s.span()),
                    what,
                    format!("unknown scheduler `{other}` (known: fair, fifo, deadline)"),
                ));
            }
        },
    };
    Ok(Cpus {
        count,
        scheduler,
        world_ms: opt(&raw.world_ms, "world_ms", Rule::NonNeg, what, 0.0)?,
    })
}

/// Checks one `[[wall]]`: two finite, distinct points.
pub(super) fn resolve_wall(w: &S<RawWall>, i: usize) -> Result<WallSpec, Fail> {
    let what = format!("wall #{}", i + 1);
    let Some(seg) = &w.get_ref().segment else {
        return Err(Fail::new(Some(w.span()), what, "missing `segment`"));
    };
    let [Pt(a), Pt(b)] = seg.get_ref().as_slice() else {
        return Err(Fail::new(
            Some(seg.span()),
            what,
            format!(
                "segment must be two points [[x0, y0], [x1, y1]], got {}",
                seg.get_ref().len()
            ),
        ));
    };
    let (a, b) = (*a, *b);
    if !a.iter().chain(&b).all(|x| x.is_finite()) {
        return Err(Fail::new(
            Some(seg.span()),
            what,
            "segment must be finite numbers",
        ));
    }
    if a == b {
        return Err(Fail::new(
            Some(seg.span()),
            what,
            "segment ends must differ",
        ));
    }
    Ok(WallSpec { segment: [a, b] })
}
