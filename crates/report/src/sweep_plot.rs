//! Curves against one number, one panel per metric: `sweep.svg` and
//! `sweep.png` of `mrsim sweep` (every outcome against a swept value, one
//! line per combination of the other swept keys, each point the mean over
//! seeds with its 95 % interval drawn as a band) and `stress.svg`/`.png` of
//! `mrsim bench --stress` (round trip and misses against the load). A
//! measured curve (realtime runs) is dashed with hollow markers; a modelled
//! one (lockstep) is solid with filled markers, so both modes of one sweep
//! can share a panel and a colour.

use crate::palette::robot_color;
use crate::plot::{FAMILY, register_font, write_png};
use crate::{RenderError, write_file};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Width of the figure, px.
const WIDTH: u32 = 1200;
/// Height of one panel, px.
const PANEL_HEIGHT: u32 = 330;
/// Height of the title line, px.
const TITLE_HEIGHT: u32 = 36;
/// Height of one legend row, px.
const LEGEND_ROW: u32 = 24;
/// Width of one legend entry, px.
const LEGEND_ENTRY: u32 = 390;
/// Panels per row.
const COLUMNS: usize = 3;

/// One line of the figure: its name in the legend and how it is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Its label (the other keys' values, and the mode when both are shown).
    pub label: String,
    /// Colour index into the palette.
    pub colour: usize,
    /// Measured (realtime runs: dashed, hollow markers) rather than
    /// modelled (lockstep: solid, filled markers).
    pub measured: bool,
}

/// One point of a line: the mean over seeds at a swept value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// The swept value.
    pub x: f64,
    /// Mean over the runs.
    pub mean: f64,
    /// Half-width of the 95 % interval (none with a single run).
    pub half_width: Option<f64>,
}

/// One metric's panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// The metric's column name (as in summary.csv), the panel's title.
    pub title: String,
    /// The y axis' label, with its unit.
    pub y_label: String,
    /// A fraction: the y axis spans 0 to 1.
    pub fraction: bool,
    /// The points of each series, in [`Figure::series`] order.
    pub lines: Vec<Vec<Point>>,
}

/// The whole figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Its title line.
    pub title: String,
    /// The x axis' label, with its unit.
    pub x_label: String,
    /// The lines, as the legend lists them.
    pub series: Vec<Series>,
    /// One per metric.
    pub panels: Vec<Panel>,
}

impl Figure {
    fn legend_rows(&self) -> u32 {
        let per_row = (WIDTH / LEGEND_ENTRY).max(1) as usize;
        self.series.len().div_ceil(per_row) as u32
    }

    /// The canvas' size, px.
    pub fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(COLUMNS).max(1) as u32;
        (
            WIDTH,
            TITLE_HEIGHT + self.legend_rows() * LEGEND_ROW + 8 + rows * PANEL_HEIGHT,
        )
    }
}

/// Writes `figure` to `svg_path` and `png_path`.
pub fn write_figure(figure: &Figure, svg_path: &Path, png_path: &Path) -> Result<(), RenderError> {
    let size = figure.size();
    let plot_error = |path: &Path| {
        let path = path.to_path_buf();
        move |reason: String| RenderError::Plot { path, reason }
    };
    register_font().map_err(plot_error(svg_path))?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(figure, &root).map_err(plot_error(svg_path))?;
        root.present()
            .map_err(|e| plot_error(svg_path)(e.to_string()))?;
    }
    write_file(svg_path, svg.as_bytes())?;
    let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
        draw(figure, &root).map_err(plot_error(png_path))?;
        root.present()
            .map_err(|e| plot_error(png_path)(e.to_string()))?;
    }
    write_png(png_path, &pixels, size)
}

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn colour(s: &Series) -> RGBColor {
    let [r, g, b] = robot_color(s.colour);
    RGBColor(r, g, b)
}

fn draw<DB: DrawingBackend>(fig: &Figure, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let (head, body) = root.split_vertically(TITLE_HEIGHT + fig.legend_rows() * LEGEND_ROW + 8);
    head.draw(&Text::new(
        fig.title.clone(),
        (14, 8),
        (FAMILY, 20).into_font(),
    ))
    .map_err(err)?;
    let per_row = (WIDTH / LEGEND_ENTRY).max(1) as usize;
    for (i, s) in fig.series.iter().enumerate() {
        let x = 20 + (i % per_row) as i32 * LEGEND_ENTRY as i32;
        let y = (TITLE_HEIGHT + (i / per_row) as u32 * LEGEND_ROW) as i32 + 10;
        let c = colour(s);
        if s.measured {
            for k in 0..3 {
                head.draw(&PathElement::new(
                    vec![(x + k * 11, y), (x + k * 11 + 6, y)],
                    c.stroke_width(2),
                ))
                .map_err(err)?;
            }
            head.draw(&Circle::new((x + 14, y), 6, c.stroke_width(2)))
                .map_err(err)?;
        } else {
            head.draw(&PathElement::new(
                vec![(x, y), (x + 28, y)],
                c.stroke_width(2),
            ))
            .map_err(err)?;
            head.draw(&Circle::new((x + 14, y), 4, c.filled()))
                .map_err(err)?;
        }
        head.draw(&Text::new(
            s.label.clone(),
            (x + 36, y - 8),
            (FAMILY, 15).into_font(),
        ))
        .map_err(err)?;
    }
    let rows = fig.panels.len().div_ceil(COLUMNS).max(1);
    let cells = body.split_evenly((rows, COLUMNS));
    for (panel, area) in fig.panels.iter().zip(&cells) {
        draw_panel(fig, panel, area)?;
    }
    Ok(())
}

/// The axis' range: every point and interval, padded; a fraction spans
/// 0 to 1 (and more if an interval reaches beyond).
fn y_range(panel: &Panel) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for p in panel.lines.iter().flatten() {
        let h = p.half_width.unwrap_or(0.0);
        if (p.mean - h).is_finite() && (p.mean + h).is_finite() {
            lo = lo.min(p.mean - h);
            hi = hi.max(p.mean + h);
        }
    }
    if panel.fraction {
        return (lo.min(0.0), hi.max(1.0) + 0.04);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        // A flat line: a count or a time that never went below 0 keeps 0
        // at the bottom of its axis.
        if lo >= 0.0 {
            return (0.0, if hi > 0.0 { hi * 1.5 } else { 1.0 });
        }
        let pad = (hi.abs() * 0.1).max(0.5);
        return (lo - pad, hi + pad);
    }
    let pad = 0.06 * (hi - lo);
    // A positive quantity keeps 0 on its axis when it is near.
    let bottom = if lo >= 0.0 && lo < 0.35 * hi {
        0.0
    } else {
        lo - pad
    };
    (bottom, hi + pad)
}

fn x_range(fig: &Figure) -> (f64, f64) {
    let xs = fig
        .panels
        .iter()
        .flat_map(|p| p.lines.iter().flatten())
        .map(|p| p.x)
        .filter(|x| x.is_finite());
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        let pad = (hi.abs() * 0.1).max(0.5);
        return (lo - pad, hi + pad);
    }
    let pad = 0.04 * (hi - lo);
    (lo - pad, hi + pad)
}

fn draw_panel<DB: DrawingBackend>(
    fig: &Figure,
    panel: &Panel,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), String> {
    let (x0, x1) = x_range(fig);
    let (y0, y1) = y_range(panel);
    let mut chart = ChartBuilder::on(area)
        .caption(panel.title.clone(), (FAMILY, 17))
        .margin(10)
        .x_label_area_size(42)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(fig.x_label.clone())
        .y_desc(panel.y_label.clone())
        .x_labels(7)
        .y_labels(6)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 14))
        .bold_line_style(RGBColor(220, 220, 220))
        .light_line_style(RGBColor(249, 249, 249))
        .draw()
        .map_err(err)?;
    // Bands first, so that every line is drawn over every band.
    for (s, line) in fig.series.iter().zip(&panel.lines) {
        let pts = sorted(line);
        if pts.len() < 2 || pts.iter().all(|p| p.half_width.is_none()) {
            continue;
        }
        let mut outline: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| (p.x, p.mean + p.half_width.unwrap_or(0.0)))
            .collect();
        outline.extend(
            pts.iter()
                .rev()
                .map(|p| (p.x, p.mean - p.half_width.unwrap_or(0.0))),
        );
        let alpha = if s.measured { 0.12 } else { 0.18 };
        chart
            .draw_series(std::iter::once(Polygon::new(
                outline,
                colour(s).mix(alpha).filled(),
            )))
            .map_err(err)?;
    }
    // Measured curves last, their markers rings around the modelled dots:
    // where both modes agree the two curves coincide and the rings show it.
    let order = fig
        .series
        .iter()
        .zip(&panel.lines)
        .filter(|(s, _)| !s.measured)
        .chain(
            fig.series
                .iter()
                .zip(&panel.lines)
                .filter(|(s, _)| s.measured),
        );
    for (s, line) in order {
        let c = colour(s);
        let pts: Vec<(f64, f64)> = sorted(line).iter().map(|p| (p.x, p.mean)).collect();
        if s.measured {
            // Slightly translucent: a reader of the SVG tells the measured
            // curve's dashes from a modelled line by their opacity.
            chart
                .draw_series(DashedLineSeries::new(
                    pts.clone(),
                    7,
                    5,
                    c.mix(0.9).stroke_width(2),
                ))
                .map_err(err)?;
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 7, c.stroke_width(2))))
                .map_err(err)?;
        } else {
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(err)?;
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map_err(err)?;
        }
    }
    Ok(())
}

/// The finite points of a line, by swept value.
fn sorted(line: &[Point]) -> Vec<Point> {
    let mut pts: Vec<Point> = line
        .iter()
        .copied()
        .filter(|p| p.x.is_finite() && p.mean.is_finite())
        .collect();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x));
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, mean: f64, h: f64) -> Point {
        Point {
            x,
            mean,
            half_width: Some(h),
        }
    }

    #[test]
    fn a_fraction_spans_zero_to_one_and_a_flat_line_gets_room() {
        let mut p = Panel {
            title: "collided".into(),
            y_label: "runs with a contact".into(),
            fraction: true,
            lines: vec![vec![point(1.0, 0.5, 0.1)]],
        };
        let (lo, hi) = y_range(&p);
        assert_eq!(lo, 0.0);
        assert!(hi >= 1.0);
        p.fraction = false;
        p.lines = vec![vec![point(1.0, 3.0, 0.0), point(2.0, 3.0, 0.0)]];
        let (lo, hi) = y_range(&p);
        assert!(lo < 3.0 && hi > 3.0, "{lo} {hi}");
    }

    #[test]
    fn the_figure_draws_one_line_per_series_in_each_panel() {
        let dir = std::env::temp_dir().join(format!("mrsim-sweep-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let series = vec![
            Series {
                label: "planner=orca".into(),
                colour: 0,
                measured: false,
            },
            Series {
                label: "planner=dwa".into(),
                colour: 1,
                measured: false,
            },
        ];
        let line = |m: f64| {
            vec![
                point(0.05, m, 0.1),
                point(0.1, m + 1.0, 0.2),
                point(0.2, m + 1.5, 0.2),
            ]
        };
        let fig = Figure {
            title: "t".into(),
            x_label: "world.dt [s]".into(),
            series,
            panels: vec![
                Panel {
                    title: "makespan".into(),
                    y_label: "s".into(),
                    fraction: false,
                    lines: vec![line(1.0), line(2.0)],
                };
                2
            ],
        };
        let (svg_path, png_path) = (dir.join("f.svg"), dir.join("f.png"));
        write_figure(&fig, &svg_path, &png_path).expect("drawn");
        let svg = std::fs::read_to_string(&svg_path).expect("svg");
        // Two solid lines of three points in each of two panels (the
        // legend's samples have two), and their labels.
        let lines = svg
            .split("<polyline")
            .filter(|p| p.contains("stroke-width=\"2\""))
            .filter(|p| {
                let points = p.split("points=\"").nth(1).unwrap_or("");
                points
                    .split('"')
                    .next()
                    .unwrap_or("")
                    .split_whitespace()
                    .count()
                    == 3
            })
            .count();
        assert_eq!(lines, 4, "{svg}");
        assert!(svg.contains("planner=orca") && svg.contains("planner=dwa"));
        assert!(png_path.is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
