//! `bench.svg` of `mrsim bench`: p99 round trip (top) and deadline-miss
//! rate (bottom) against the number of agents, one line per transport.

use crate::RenderError;
use crate::palette::robot_color;
use plotters::prelude::*;
use std::path::Path;

/// One measured combination.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Line it belongs to (the transport).
    pub series: String,
    /// Number of agents.
    pub agents: f64,
    /// p99 round trip, ms.
    pub roundtrip_p99_ms: f64,
    /// Deadline misses, % of agent-ticks.
    pub miss_pct: f64,
}

fn draw_err(path: &Path, e: impl std::fmt::Display) -> RenderError {
    RenderError::Plot {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

/// A panel's y label and the value it plots.
type Panel = (&'static str, fn(&Point) -> f64);

/// Writes the two panels to `path` (SVG).
pub fn write(points: &[Point], path: &Path) -> Result<(), RenderError> {
    crate::plot::register_font().map_err(|e| draw_err(path, e))?;
    let mut names: Vec<&str> = Vec::new();
    for p in points {
        if !names.contains(&p.series.as_str()) {
            names.push(&p.series);
        }
    }
    let x_max = points.iter().map(|p| p.agents).fold(1.0, f64::max) * 1.05;
    let panels: [Panel; 2] = [
        ("p99 round trip, ms", |p| p.roundtrip_p99_ms),
        ("deadline misses, %", |p| p.miss_pct),
    ];
    let root = SVGBackend::new(path, (900, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| draw_err(path, e))?;
    let areas = root.split_evenly((2, 1));
    for (area, (label, value)) in areas.iter().zip(panels) {
        let y_max = points.iter().map(value).fold(0.0, f64::max).max(1e-3) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..x_max, 0.0..y_max)
            .map_err(|e| draw_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc("agents")
            .y_desc(label)
            .draw()
            .map_err(|e| draw_err(path, e))?;
        for (k, name) in names.iter().enumerate() {
            let [r, g, b] = robot_color(k);
            let color = RGBColor(r, g, b);
            let mut line: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.series == *name)
                .map(|p| (p.agents, value(p)))
                .collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(|e| draw_err(path, e))?
                .label(name.to_string())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
            chart
                .draw_series(line.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                .map_err(|e| draw_err(path, e))?;
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| draw_err(path, e))?;
    }
    root.present().map_err(|e| draw_err(path, e))?;
    Ok(())
}
