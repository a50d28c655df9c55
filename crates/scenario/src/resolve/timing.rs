//! A robot's `timing` from its layers: each key from the highest layer that
//! has it (`compute`'s model and each of its numbers too, so that
//! `--set defaults.timing.compute.ms=40` changes only the time), every
//! value checked where it is written.

use super::robots::Layer;
use crate::checks::{Rule, check};
use crate::error::Fail;
use crate::raw::{RawCompute, RawPriority, RawTiming, S};
use crate::timing::{Compute, Priority, Reservation, Timing};

/// The known compute models and the numbers each takes.
const MODELS: &[(&str, &[&str])] = &[
    ("none", &[]),
    ("fixed", &["ms"]),
    ("uniform", &["min_ms", "max_ms"]),
    ("lognormal", &["median_ms", "sigma"]),
    ("per-body", &["base_ms", "per_body_ms"]),
];

/// A compute number by key.
fn number<'a>(c: &'a RawCompute, key: &str) -> &'a Option<S<f64>> {
    match key {
        "ms" => &c.ms,
        "min_ms" => &c.min_ms,
        "max_ms" => &c.max_ms,
        "median_ms" => &c.median_ms,
        "sigma" => &c.sigma,
        "base_ms" => &c.base_ms,
        _ => &c.per_body_ms,
    }
}

/// Every compute number key.
const NUMBERS: &[&str] = &[
    "ms",
    "min_ms",
    "max_ms",
    "median_ms",
    "sigma",
    "base_ms",
    "per_body_ms",
];

/// The robot's timing, or `None` when no layer has a `timing` table.
pub(super) fn resolve_timing(layers: &[Layer]) -> Result<Option<Timing>, Fail> {
    let tables: Vec<(&S<RawTiming>, &str)> = layers
        .iter()
        .filter_map(|l| l.raw.timing.as_ref().map(|t| (t, l.what.as_str())))
        .collect();
    if tables.is_empty() {
        return Ok(None);
    }
    let mut t = Timing::default();
    let num = |f: fn(&RawTiming) -> &Option<S<f64>>, key: &str, default: f64| {
        let mut chosen = None;
        for (raw, what) in &tables {
            if let Some(v) = f(raw.get_ref()) {
                let x = check(v, &format!("timing.{key}"), Rule::NonNeg, what)?;
                chosen.get_or_insert(x);
            }
        }
        Ok::<f64, Fail>(chosen.unwrap_or(default))
    };
    let prob = |f: fn(&RawTiming) -> &Option<S<f64>>, key: &str| {
        let mut chosen = None;
        for (raw, what) in &tables {
            if let Some(v) = f(raw.get_ref()) {
                let x = check(v, &format!("timing.{key}"), Rule::Finite, what)?;
                if !(0.0..=1.0).contains(&x) {
                    return Err(Fail::new(
                        Some(v.span()),
                        *what,
                        format!("timing.{key} is a probability, in [0, 1], got {x}"),
                    ));
                }
                chosen.get_or_insert(x);
            }
        }
        Ok(chosen.unwrap_or(0.0))
    };
    t.observation_delay_ms = num(|r| &r.observation_delay_ms, "observation_delay_ms", 0.0)?;
    t.actuation_delay_ms = num(|r| &r.actuation_delay_ms, "actuation_delay_ms", 0.0)?;
    t.snapshot_loss = prob(|r| &r.snapshot_loss, "snapshot_loss")?;
    t.command_loss = prob(|r| &r.command_loss, "command_loss")?;
    let mut period = None;
    for (raw, what) in &tables {
        if let Some(v) = &raw.get_ref().period_ticks {
            let k = *v.get_ref();
            if k < 1 || k > i64::from(u32::MAX) {
                return Err(Fail::new(
                    Some(v.span()),
                    *what,
                    format!("timing.period_ticks must be a whole number >= 1, got {k}"),
                ));
            }
            period.get_or_insert(k as u32);
        }
    }
    t.period_ticks = period.unwrap_or(1);
    t.compute = compute(&tables)?;
    t.cpu = tables
        .iter()
        .filter_map(|(raw, _)| raw.get_ref().compute.as_ref())
        .find_map(|c| c.get_ref().cpu.as_ref())
        .is_some_and(|c| *c.get_ref());
    t.priority = priority(&tables)?;
    t.reservation = reservation(&tables)?;
    Ok(Some(t))
}

/// `priority`: from the highest layer that has it, each checked.
fn priority(tables: &[(&S<RawTiming>, &str)]) -> Result<Option<Priority>, Fail> {
    let mut chosen = None;
    for (raw, what) in tables {
        let Some(p) = &raw.get_ref().priority else {
            continue;
        };
        let bad = |got: String| {
            Err(Fail::new(
                Some(p.span()),
                *what,
                format!(
                    "timing.priority must be a whole number 1..99 or \"rate-monotonic\", got {got}"
                ),
            ))
        };
        let value = match p.get_ref() {
            RawPriority::Level(l) if (1..=99).contains(l) => Priority::Level(*l as u8),
            RawPriority::Level(l) => return bad(l.to_string()),
            RawPriority::Name(n) if n == "rate-monotonic" => Priority::RateMonotonic,
            RawPriority::Name(n) => return bad(format!("\"{n}\"")),
        };
        chosen.get_or_insert(value);
    }
    Ok(chosen)
}

/// `reservation`: each of its numbers from the highest layer that has it
/// (so `--set robot.r0.timing.reservation.runtime_ms=30` changes only the
/// runtime), both needed, runtime at most the period.
fn reservation(tables: &[(&S<RawTiming>, &str)]) -> Result<Option<Reservation>, Fail> {
    let tables: Vec<_> = tables
        .iter()
        .filter_map(|(raw, what)| raw.get_ref().reservation.as_ref().map(|r| (r, *what)))
        .collect();
    let Some((top, top_what)) = tables.first().copied() else {
        return Ok(None);
    };
    let get = |key: &str| {
        let mut chosen = None;
        for (r, what) in &tables {
            let v = match key {
                "runtime_ms" => &r.get_ref().runtime_ms,
                _ => &r.get_ref().period_ms,
            };
            if let Some(v) = v {
                let x = check(v, &format!("timing.reservation.{key}"), Rule::Pos, what)?;
                chosen.get_or_insert(x);
            }
        }
        chosen.ok_or_else(|| {
            Fail::new(
                Some(top.span()),
                top_what,
                format!(
                    "timing.reservation needs `{key}` (reservation = {{ runtime_ms, period_ms }})"
                ),
            )
        })
    };
    let (runtime_ms, period_ms) = (get("runtime_ms")?, get("period_ms")?);
    if runtime_ms > period_ms {
        return Err(Fail::new(
            Some(top.span()),
            top_what,
            format!(
                "timing.reservation runtime_ms ({runtime_ms}) must be <= period_ms ({period_ms})"
            ),
        ));
    }
    Ok(Some(Reservation {
        runtime_ms,
        period_ms,
    }))
}

/// The model no layer names, from the numbers given: each number belongs
/// to one model (`ms` to fixed, `min_ms` and `max_ms` to uniform, ...), so
/// `--set defaults.timing.compute.ms=40` alone means fixed 40 ms. `None`
/// if no number is given or numbers of two models are.
fn inferred<'a>(
    computes: &[(&'a S<RawCompute>, &'a str)],
) -> Option<(S<String>, &'a str, &'a RawCompute)> {
    let mut found: Option<(S<String>, &str, &RawCompute)> = None;
    for (c, what) in computes {
        for (model, keys) in MODELS {
            for key in *keys {
                let Some(v) = number(c.get_ref(), key) else {
                    continue;
                };
                match &found {
                    Some((m, ..)) if m.get_ref() != model => return None,
                    Some(_) => {}
                    None => {
                        found = Some((S::new(v.span(), model.to_string()), *what, c.get_ref()));
                    }
                }
            }
        }
    }
    found
}

/// `compute`: the model from the highest layer that names one (or the one
/// its numbers belong to), each of its numbers from the highest layer that
/// has it.
fn compute(tables: &[(&S<RawTiming>, &str)]) -> Result<Compute, Fail> {
    let computes: Vec<(&S<RawCompute>, &str)> = tables
        .iter()
        .filter_map(|(t, what)| t.get_ref().compute.as_ref().map(|c| (c, *what)))
        .collect();
    let Some((top, top_what)) = computes.first().copied() else {
        return Ok(Compute::None);
    };
    let named = computes
        .iter()
        .find_map(|(c, what)| c.get_ref().model.clone().map(|m| (m, *what, c.get_ref())));
    let Some((model, model_what, model_table)) = named.or_else(|| inferred(&computes)) else {
        return Err(Fail::new(
            Some(top.span()),
            top_what,
            "timing.compute needs `model` (none, fixed, uniform, lognormal, per-body), or \
             the numbers of one model (`ms` alone is fixed)",
        ));
    };
    let model = &model;
    let Some((_, keys)) = MODELS.iter().find(|(m, _)| m == model.get_ref()) else {
        return Err(Fail::new(
            Some(model.span()),
            model_what,
            format!(
                "unknown timing.compute model `{}` (known: none, fixed, uniform, lognormal, per-body)",
                model.get_ref()
            ),
        ));
    };
    // A number the model does not take, written beside the model: a typo
    // or a misunderstanding, never silently ignored.
    for key in NUMBERS.iter().filter(|k| !keys.contains(k)) {
        if let Some(v) = number(model_table, key) {
            return Err(Fail::new(
                Some(v.span()),
                model_what,
                format!(
                    "timing.compute model `{}` takes no `{key}` (it takes: {})",
                    model.get_ref(),
                    if keys.is_empty() {
                        "nothing".to_string()
                    } else {
                        keys.join(", ")
                    }
                ),
            ));
        }
    }
    let get = |key: &str, rule: Rule| {
        let mut chosen = None;
        for (c, what) in &computes {
            if let Some(v) = number(c.get_ref(), key) {
                let x = check(v, &format!("timing.compute.{key}"), rule, what)?;
                chosen.get_or_insert(x);
            }
        }
        chosen.ok_or_else(|| {
            Fail::new(
                Some(model.span()),
                model_what,
                format!("timing.compute model `{}` needs `{key}`", model.get_ref()),
            )
        })
    };
    Ok(match model.get_ref().as_str() {
        "none" => Compute::None,
        "fixed" => Compute::Fixed {
            ms: get("ms", Rule::NonNeg)?,
        },
        "uniform" => {
            let (min_ms, max_ms) = (get("min_ms", Rule::NonNeg)?, get("max_ms", Rule::NonNeg)?);
            if max_ms < min_ms {
                return Err(Fail::new(
                    Some(model.span()),
                    model_what,
                    format!("timing.compute max_ms ({max_ms}) must be >= min_ms ({min_ms})"),
                ));
            }
            Compute::Uniform { min_ms, max_ms }
        }
        "lognormal" => Compute::Lognormal {
            median_ms: get("median_ms", Rule::Pos)?,
            sigma: get("sigma", Rule::NonNeg)?,
        },
        _ => Compute::PerBody {
            base_ms: get("base_ms", Rule::NonNeg)?,
            per_body_ms: get("per_body_ms", Rule::NonNeg)?,
        },
    })
}
