//! The sweep's figure: every metric against a swept number, one line per
//! combination of the other keys, with its 95 % band (`sweep.svg`,
//! `sweep.png`).

use super::axes::numeric_axis;
use super::metrics::METRICS;
use super::{Summary, Sweep, SweepMode};
use mrsim_report::sweep_plot::{Figure, Panel, Point, Series, write_figure};
use mrsim_scenario::Mode;

impl Sweep {
    /// The swept key on the figure's x axis: `--x`, else the first swept
    /// key whose values are all numbers (none: no figure).
    pub fn x_axis(&self) -> Option<usize> {
        match &self.plan.x {
            Some(x) => numeric_axis(&self.axes, x).ok(),
            // The first swept number with more than one value (a key
            // given one value is a setting, not an axis), else the first.
            None => {
                let numeric = |vs: &Vec<String>| vs.iter().all(|v| v.parse::<f64>().is_ok());
                self.axes
                    .iter()
                    .position(|(_, vs)| vs.len() > 1 && numeric(vs))
                    .or_else(|| self.axes.iter().position(|(_, vs)| numeric(vs)))
            }
        }
    }

    /// The figure of `summaries` ([`Sweep::summarize`]): every metric
    /// against the swept number [`Sweep::x_axis`], one line per combination
    /// of the other keys (and per mode), with its 95 % band. None if no
    /// swept key is a number.
    pub fn figure(&self, summaries: &[Summary]) -> Option<Figure> {
        let xi = self.x_axis()?;
        let others = |combo: usize| -> Vec<&String> {
            self.combos[combo]
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != xi)
                .map(|(_, v)| v)
                .collect()
        };
        // Lines: (other values, mode), in order of first appearance.
        let mut lines: Vec<(Vec<&String>, Mode)> = Vec::new();
        for s in summaries {
            let key = (others(s.combo), s.mode);
            if !lines.contains(&key) {
                lines.push(key);
            }
        }
        let mut colours: Vec<&Vec<&String>> = Vec::new();
        let both = self.plan.mode == SweepMode::Both;
        let series: Vec<Series> = lines
            .iter()
            .map(|(rest, mode)| {
                let colour = match colours.iter().position(|c| *c == rest) {
                    Some(c) => c,
                    None => {
                        colours.push(rest);
                        colours.len() - 1
                    }
                };
                let pairs: Vec<String> = self
                    .axes
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != xi)
                    .zip(rest)
                    .map(|((_, (k, _)), v)| short_pair(k, v))
                    .collect();
                let how = match mode {
                    Mode::Lockstep => "lockstep (modelled)",
                    Mode::Realtime => "realtime (measured)",
                };
                let label = match (pairs.is_empty(), both) {
                    (true, _) => how.to_string(),
                    (false, false) => pairs.join(", "),
                    (false, true) => format!("{}, {how}", pairs.join(", ")),
                };
                Series {
                    label,
                    colour,
                    measured: *mode == Mode::Realtime,
                }
            })
            .collect();
        // The metrics asked for, in the order asked (all by default).
        let drawn: Vec<usize> = if self.plan.metrics.is_empty() {
            (0..METRICS.len()).collect()
        } else {
            self.plan
                .metrics
                .iter()
                .filter_map(|want| METRICS.iter().position(|(name, _)| name == want))
                .collect()
        };
        let panels = drawn
            .into_iter()
            .map(|m| {
                let name = METRICS[m].0;
                let (y_label, fraction) = metric_axis(name, self.length_unit);
                let lines = lines
                    .iter()
                    .map(|(rest, mode)| {
                        summaries
                            .iter()
                            .filter(|s| s.mode == *mode && others(s.combo) == *rest)
                            .filter_map(|s| {
                                let x = self.combos[s.combo][xi].parse::<f64>().ok()?;
                                let (mean, half_width) = s.stats[m];
                                Some(Point {
                                    x,
                                    mean: mean?,
                                    half_width,
                                })
                            })
                            .collect()
                    })
                    .collect();
                Panel {
                    title: name.to_string(),
                    y_label,
                    fraction,
                    lines,
                }
            })
            .collect();
        let key = &self.axes[xi].0;
        let modes = match self.plan.mode {
            SweepMode::Lockstep => "lockstep runs",
            SweepMode::Realtime => "realtime runs",
            SweepMode::Both => "lockstep (solid) and realtime (dashed) runs",
        };
        Some(Figure {
            title: format!(
                "{}: mean over seeds 1..{} with its 95 % interval, {modes}",
                self.name, self.plan.seeds
            ),
            x_label: match key_unit(key, self.length_unit) {
                Some(u) => format!("{key} [{u}]"),
                None => key.clone(),
            },
            series,
            panels,
        })
    }

    /// Draws [`Sweep::figure`] into `sweep.svg` and `sweep.png` in the
    /// sweep's folder; false (nothing drawn) if no swept key is a number.
    pub fn draw(&self, summaries: &[Summary]) -> Result<bool, mrsim_report::RenderError> {
        match self.figure(summaries) {
            Some(f) => write_figure(
                &f,
                &self.dir.join(mrsim_runfolder::SWEEP_SVG_FILE),
                &self.dir.join(mrsim_runfolder::SWEEP_PNG_FILE),
            )
            .map(|()| true),
            None => Ok(false),
        }
    }
}

/// A metric's axis label (with its unit) and whether it is a fraction (an
/// axis from 0 to 1), for the figure.
pub(super) fn metric_axis(name: &str, length: &str) -> (String, bool) {
    match name {
        "success_rate" => ("robots at their goal (fraction)".into(), true),
        "collisions_total" => ("contacts per run".into(), false),
        "collided" => ("runs with a contact (fraction)".into(), true),
        "makespan" => ("last arrival [s]".into(), false),
        "path_length_ratio" => ("path / straight line".into(), false),
        "min_clearance" => (format!("smallest gap [{length}]"), false),
        "time_to_goal" => ("mean time to goal [s]".into(), false),
        "agents_lost" => ("agents lost per run".into(), false),
        "ticks" => ("ticks per run".into(), false),
        "miss_rate" => ("deadline misses per robot and tick".into(), true),
        "predicted_missing" => ("robots predicted to miss (fraction)".into(), true),
        "spl" => ("success weighted by path length".into(), true),
        "deadlocks" => ("deadlocks per run".into(), false),
        "time_not_moving" | "time_intimate" | "time_personal" | "time_social" | "stuck_time" => {
            (format!("{other} [s]", other = name), false)
        }
        "ttc_min" => ("smallest time to collision [s]".into(), false),
        other => (other.to_string(), false),
    }
}

/// The unit of a swept key's values, where its name says it (`[ms]` for a
/// key ending `ms`, seconds for `world.dt`, the length unit for a radius).
pub(super) fn key_unit(key: &str, length: &str) -> Option<String> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let unit = match last {
        "ms" => "ms".to_string(),
        "dt" | "duration" | "stall_timeout" | "horizon" => "s".to_string(),
        "max_speed" => format!("{length}/s"),
        "max_accel" => format!("{length}/s^2"),
        "radius" | "sensing_range" | "goal_tolerance" => length.to_string(),
        _ if last.ends_with("_ms") => "ms".to_string(),
        _ if last.ends_with("_deg") => "deg".to_string(),
        _ if last.ends_with("_s") => "s".to_string(),
        _ => return None,
    };
    Some(unit)
}

/// A legend's text: `key=value` with the key's last part, cut short.
fn short_pair(key: &str, value: &str) -> String {
    let short = key.rsplit('.').next().unwrap_or(key);
    let mut v: String = value.chars().take(32).collect();
    if value.chars().count() > 32 {
        v.push_str("...");
    }
    format!("{short}={v}")
}
