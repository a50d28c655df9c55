//! `plot.svg` and `plot.png`: panel 1 the map (arena, walls, trajectories,
//! starts, goals, obstacles' paths, collisions) at equal aspect ratio,
//! panel 2 every robot's speed against time, panel 3 the planners'
//! diagnostics when the run has `diagnostics.csv`.
//!
//! Text in the PNG is drawn by ab_glyph with an embedded ASCII subset of
//! DejaVu Sans (assets/, 20 kB), so no system font is needed and a machine
//! without fonts draws the same picture. The SVG names `sans-serif` and
//! leaves the font to the viewer.

use crate::palette::{COLLISION, robot_color};
use crate::{BodyKind, RenderError, RunData, write_file};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Width of the plots, px.
pub const PLOT_WIDTH: u32 = 1200;
const MAP_HEIGHT: u32 = 800;
const SPEED_HEIGHT: u32 = 300;
const DIAG_HEIGHT: u32 = 220;
/// At most this many diagnostics get a panel.
const MAX_DIAG_PANELS: usize = 6;
/// Robots are named on the map and in the legend up to this many.
const MAX_NAMED: usize = 16;

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans-ascii.ttf");
pub(crate) const FAMILY: &str = "sans-serif";

pub(crate) fn register_font() -> Result<(), String> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .map_err(|_| "the embedded font does not parse".to_string())
    })
    .clone()
}

/// Diagnostic names in order of first appearance.
fn diagnostic_names(run: &RunData) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for d in run.diagnostics.iter().flatten() {
        if !names.contains(&d.name) {
            names.push(d.name.clone());
        }
    }
    names
}

/// Size of `plot.png` (and of `plot.svg`'s canvas) for this run, px.
pub fn plot_size(run: &RunData) -> (u32, u32) {
    let panels = diagnostic_names(run).len().min(MAX_DIAG_PANELS) as u32;
    (PLOT_WIDTH, MAP_HEIGHT + SPEED_HEIGHT + panels * DIAG_HEIGHT)
}

/// Writes `plot.svg` and `plot.png` for `run` into `dir`.
pub fn write_plots(run: &RunData, dir: &Path) -> Result<(), RenderError> {
    let size = plot_size(run);
    let svg_path = dir.join(mrsim_runfolder::PLOT_SVG_FILE);
    let plot_error = |path: &PathBuf| {
        let path = path.clone();
        move |reason: String| RenderError::Plot { path, reason }
    };
    register_font().map_err(plot_error(&svg_path))?;

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(run, &root).map_err(plot_error(&svg_path))?;
        root.present()
            .map_err(|e| plot_error(&svg_path)(e.to_string()))?;
    }
    write_file(&svg_path, svg.as_bytes())?;

    let png_path = dir.join(mrsim_runfolder::PLOT_PNG_FILE);
    let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
        draw(run, &root).map_err(plot_error(&png_path))?;
        root.present()
            .map_err(|e| plot_error(&png_path)(e.to_string()))?;
    }
    write_png(&png_path, &pixels, size)
}

/// Encodes an RGB buffer of `size` pixels (as the bitmap backend fills it)
/// into the PNG file `path`.
pub(crate) fn write_png(path: &Path, pixels: &[u8], size: (u32, u32)) -> Result<(), RenderError> {
    let file = std::fs::File::create(path).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let png_err = |source| RenderError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), size.0, size.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(png_err)?;
    writer.write_image_data(pixels).map_err(png_err)?;
    writer.finish().map_err(png_err)?;
    Ok(())
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn unit(run: &RunData) -> &'static str {
    match run.scenario.length_unit {
        mrsim_scenario::LengthUnit::M => "m",
        mrsim_scenario::LengthUnit::Cm => "cm",
        mrsim_scenario::LengthUnit::Mm => "mm",
    }
}

/// Robots' tracks with their colour index, in colour order.
fn robot_tracks(run: &RunData) -> Vec<(usize, &crate::BodyTrack)> {
    let index: HashMap<String, usize> = run
        .robot_names()
        .into_iter()
        .enumerate()
        .map(|(i, n)| (n, i))
        .collect();
    let mut out: Vec<(usize, &crate::BodyTrack)> = run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Robot)
        .filter_map(|b| index.get(&b.name).map(|&i| (i, b)))
        .collect();
    out.sort_by_key(|(i, _)| *i);
    out
}

/// At most this many robot samples are drawn per panel: a bigger run's
/// tracks are drawn through every k-th sample (and the last), so a
/// 10,000-robot plot stays small and quick to draw.
pub const MAX_PLOT_POINTS: usize = 200_000;

/// Every how many samples a track is drawn through (1 unless the robots'
/// samples together exceed [`MAX_PLOT_POINTS`]).
pub fn plot_every(run: &RunData) -> usize {
    let samples: usize = run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Robot)
        .map(|b| b.samples.len())
        .sum();
    samples.div_ceil(MAX_PLOT_POINTS).max(1)
}

/// Every `every`-th sample of `samples`, and the last.
fn thinned(samples: &[crate::Sample], every: usize) -> impl Iterator<Item = &crate::Sample> {
    let last = samples.len().saturating_sub(1);
    samples
        .iter()
        .enumerate()
        .filter(move |(i, _)| i % every == 0 || *i == last)
        .map(|(_, s)| s)
}

fn draw<DB: DrawingBackend>(run: &RunData, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let (map, rest) = root.split_vertically(MAP_HEIGHT);
    let (speed, diag) = rest.split_vertically(SPEED_HEIGHT);
    draw_map(run, &map)?;
    draw_speeds(run, &speed)?;
    draw_diagnostics(run, &diag)?;
    Ok(())
}

fn draw_map<DB: DrawingBackend>(
    run: &RunData,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), String> {
    let robots = robot_tracks(run);
    let n_robots = run.robot_names().len();
    let collisions: Vec<[f64; 2]> = run
        .events
        .iter()
        .filter_map(|e| run.collision_point(e))
        .collect();
    let n_obstacles = run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Obstacle)
        .count()
        .max(run.scenario.obstacles.len());
    let mut title = format!(
        "{}: {} robot{}, {} obstacle{}, {} collision{}",
        run.scenario.name,
        n_robots,
        if n_robots == 1 { "" } else { "s" },
        n_obstacles,
        if n_obstacles == 1 { "" } else { "s" },
        collisions.len(),
        if collisions.len() == 1 { "" } else { "s" },
    );
    if n_robots > MAX_NAMED {
        title.push_str(" (names omitted)");
    }
    let area = area.titled(&title, (FAMILY, 20)).map_err(err)?;
    let [x0, x1, y0, y1] = run.extent();
    let build = |xr: std::ops::Range<f64>, yr: std::ops::Range<f64>| {
        ChartBuilder::on(&area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xr, yr)
    };
    // Equal aspect ratio: measure the plotting area, then widen the short
    // side of the world box to its proportions.
    let (pw, ph) = build(x0..x1, y0..y1)
        .map_err(err)?
        .plotting_area()
        .dim_in_pixel();
    let scale = (pw.max(1) as f64 / (x1 - x0)).min(ph.max(1) as f64 / (y1 - y0));
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (hw, hh) = (pw as f64 / scale / 2.0, ph as f64 / scale / 2.0);
    let mut chart = build(cx - hw..cx + hw, cy - hh..cy + hh).map_err(err)?;
    let u = unit(run);
    chart
        .configure_mesh()
        .x_desc(format!("x [{u}]"))
        .y_desc(format!("y [{u}]"))
        .bold_line_style(RGBColor(220, 220, 220))
        .light_line_style(RGBColor(242, 242, 242))
        .draw()
        .map_err(err)?;
    let px = |r: f64| (r * scale).round().clamp(0.0, 10_000.0) as i32;

    chart
        .draw_series(run.scenario.all_walls().into_iter().map(|w| {
            PathElement::new(
                vec![(w[0][0], w[0][1]), (w[1][0], w[1][1])],
                BLACK.stroke_width(2),
            )
        }))
        .map_err(err)?;

    let looks = run.looks_by_name();
    let grey = RGBColor(130, 130, 130);
    for body in run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Obstacle)
    {
        let points: Vec<(f64, f64)> = body
            .samples
            .iter()
            .filter(|s| s.x.is_finite() && s.y.is_finite())
            .map(|s| (s.x, s.y))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(
                points.clone(),
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(err)?;
        let ends = [points.first(), points.last()];
        let look = looks.get(body.name.as_str()).filter(|l| !l.is_disc());
        if let Some(look) = look {
            // Its polygon at both ends, turned by its fixed heading.
            let heading = look.heading(None);
            for &p in ends.into_iter().flatten() {
                let outline = drawn_outline(look, [p.0, p.1], heading, scale, 2.0);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        outline,
                        grey.stroke_width(1),
                    )))
                    .map_err(err)?;
            }
            continue;
        }
        let r = px(run.radius_of(&body.name)).max(2);
        chart
            .draw_series(
                ends.into_iter()
                    .flatten()
                    .map(|&p| Circle::new(p, r, grey.stroke_width(1))),
            )
            .map_err(err)?;
    }

    // Routes (routes.csv): thin dashed lines in the robot's colour.
    let names = run.robot_names();
    for (index, name) in names.iter().enumerate() {
        if let Some(route) = run.routes.get(name) {
            let c = rgb(robot_color(index));
            chart
                .draw_series(DashedLineSeries::new(
                    route.iter().map(|p| (p[0], p[1])),
                    5,
                    4,
                    c.stroke_width(1),
                ))
                .map_err(err)?;
        }
    }

    let width = if n_robots > 64 { 1 } else { 2 };
    let every = plot_every(run);
    for (index, body) in &robots {
        let c = rgb(robot_color(*index));
        let points = thinned(&body.samples, every)
            .filter(|s| s.x.is_finite() && s.y.is_finite())
            .map(|s| (s.x, s.y));
        chart
            .draw_series(LineSeries::new(points, c.stroke_width(width)))
            .map_err(err)?;
    }
    // Starts (circles of the robot's radius, at least 4 px), goals
    // (crosses) and names, for every robot of the scenario.
    let specs = run.specs_by_name();
    let tracks = run.tracks_by_name();
    for (index, name) in run.robot_names().iter().enumerate() {
        let c = rgb(robot_color(index));
        let spec = specs.get(name.as_str()).copied();
        let first = tracks
            .get(name.as_str())
            .and_then(|t| t.samples.first())
            .map(|s| [s.x, s.y]);
        let Some(start) = spec.map(|s| s.start).or(first) else {
            continue;
        };
        let start = (start[0], start[1]);
        let r = px(spec.map_or(0.0, |s| s.radius)).max(4);
        match looks.get(name.as_str()).filter(|l| !l.is_disc()) {
            // Its polygon at its start pose, and thinner where it ended.
            Some(look) => {
                let samples = tracks.get(name.as_str()).map(|t| &t.samples[..]);
                let first = samples.and_then(|s| s.first());
                let at_start =
                    drawn_outline(look, [start.0, start.1], look.heading(first), scale, 4.0);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        at_start,
                        c.stroke_width(2),
                    )))
                    .map_err(err)?;
                if let Some(end) = samples
                    .and_then(|s| s.last())
                    .filter(|s| s.x.is_finite() && s.y.is_finite())
                {
                    let at_end =
                        drawn_outline(look, [end.x, end.y], look.heading(Some(end)), scale, 4.0);
                    chart
                        .draw_series(std::iter::once(PathElement::new(at_end, c.stroke_width(1))))
                        .map_err(err)?;
                }
            }
            None => {
                chart
                    .draw_series(std::iter::once(Circle::new(start, r, c.stroke_width(2))))
                    .map_err(err)?;
            }
        }
        if let Some(spec) = spec {
            chart
                .draw_series(std::iter::once(Cross::new(
                    (spec.goal[0], spec.goal[1]),
                    6,
                    c.stroke_width(2),
                )))
                .map_err(err)?;
        }
        if n_robots <= MAX_NAMED {
            let font = (FAMILY, 14).into_font().color(&c);
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at(start) + Text::new(name.clone(), (r + 3, -r - 14), font),
                ))
                .map_err(err)?;
        }
    }
    let red = rgb(COLLISION);
    chart
        .draw_series(
            collisions
                .iter()
                .map(|p| Cross::new((p[0], p[1]), 7, red.stroke_width(3))),
        )
        .map_err(err)?;
    Ok(())
}

/// The closed outline a body of `look` is drawn with at `position` and
/// `heading`, in world coordinates: its polygon, grown about its position
/// so that it reaches at least `min_px` pixels from it at `scale` px per
/// length unit (a body too small to see stays visible, as a disc's circle
/// does). A disc's outline is its position alone.
fn drawn_outline(
    look: &crate::BodyLook,
    position: [f64; 2],
    heading: f64,
    scale: f64,
    min_px: f64,
) -> Vec<(f64, f64)> {
    let Some(mut points) = look.outline(position, heading) else {
        return vec![(position[0], position[1])];
    };
    let reach = look.shape.circumradius() * scale;
    let grow = if reach > 0.0 && reach < min_px {
        min_px / reach
    } else {
        1.0
    };
    for p in &mut points {
        *p = [
            position[0] + (p[0] - position[0]) * grow,
            position[1] + (p[1] - position[1]) * grow,
        ];
    }
    if let Some(&first) = points.first() {
        points.push(first);
    }
    points.into_iter().map(|p| (p[0], p[1])).collect()
}

fn draw_speeds<DB: DrawingBackend>(
    run: &RunData,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), String> {
    let robots = robot_tracks(run);
    let named = run.robot_names().len() <= MAX_NAMED;
    let title = if named {
        "speed"
    } else {
        "speed (colours as on the map)"
    };
    let area = area.titled(title, (FAMILY, 18)).map_err(err)?;
    let times = &run.trajectory.times;
    let t0 = times.first().copied().unwrap_or(0.0);
    let mut t1 = times.last().copied().unwrap_or(1.0);
    if t1 <= t0 {
        t1 = t0 + 1.0;
    }
    let vmax = robots
        .iter()
        .flat_map(|(_, b)| b.samples.iter().map(|s| s.speed()))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let vmax = if vmax > 0.0 { vmax * 1.05 } else { 1.0 };
    let mut chart = ChartBuilder::on(&area)
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(t0..t1, 0.0..vmax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc(format!("speed [{}/s]", unit(run)))
        .bold_line_style(RGBColor(220, 220, 220))
        .light_line_style(RGBColor(242, 242, 242))
        .draw()
        .map_err(err)?;
    let every = plot_every(run);
    for (index, body) in &robots {
        let c = rgb(robot_color(*index));
        let points = thinned(&body.samples, every)
            .map(|s| (s.time, s.speed()))
            .filter(|(t, v)| t.is_finite() && v.is_finite());
        let series = chart
            .draw_series(LineSeries::new(points, c.stroke_width(1)))
            .map_err(err)?;
        if named {
            series.label(body.name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
            });
        }
    }
    if named && !robots.is_empty() {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(180, 180, 180))
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FAMILY, 13))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

fn draw_diagnostics<DB: DrawingBackend>(
    run: &RunData,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), String> {
    let Some(diagnostics) = &run.diagnostics else {
        return Ok(());
    };
    let names = diagnostic_names(run);
    let shown = names.len().min(MAX_DIAG_PANELS);
    if shown == 0 {
        return Ok(());
    }
    let panels = area.split_evenly((shown, 1));
    let robot_names = run.robot_names();
    let colour: HashMap<&str, usize> = robot_names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    for (k, (name, panel)) in names.iter().zip(panels.iter()).enumerate() {
        let mut title = format!("diagnostic: {name}");
        if k + 1 == shown && names.len() > shown {
            title.push_str(&format!(
                " ({} more diagnostics not shown)",
                names.len() - shown
            ));
        }
        let panel = panel.titled(&title, (FAMILY, 16)).map_err(err)?;
        // One series per robot, in colour order.
        let mut by_robot: std::collections::BTreeMap<usize, Vec<(f64, f64)>> = Default::default();
        for d in diagnostics.iter().filter(|d| &d.name == name) {
            if !(d.time.is_finite() && d.value.is_finite()) {
                continue;
            }
            let index = colour.get(d.robot.as_str()).copied().unwrap_or(usize::MAX);
            by_robot.entry(index).or_default().push((d.time, d.value));
        }
        let series: Vec<(usize, Vec<(f64, f64)>)> = by_robot.into_iter().collect();
        let all = series.iter().flat_map(|(_, p)| p.iter());
        let (mut t0, mut t1, mut v0, mut v1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for &(t, v) in all {
            t0 = t0.min(t);
            t1 = t1.max(t);
            v0 = v0.min(v);
            v1 = v1.max(v);
        }
        if !t0.is_finite() {
            (t0, t1, v0, v1) = (0.0, 1.0, 0.0, 1.0);
        }
        if t1 <= t0 {
            t1 = t0 + 1.0;
        }
        let pad = if v1 > v0 {
            0.05 * (v1 - v0)
        } else {
            0.5 * v0.abs().max(1.0)
        };
        let mut chart = ChartBuilder::on(&panel)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(t0..t1, v0 - pad..v1 + pad)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .bold_line_style(RGBColor(220, 220, 220))
            .light_line_style(RGBColor(242, 242, 242))
            .draw()
            .map_err(err)?;
        for (index, points) in series {
            let c = if index == usize::MAX {
                RGBColor(90, 90, 90)
            } else {
                rgb(robot_color(index))
            };
            chart
                .draw_series(LineSeries::new(points, c.stroke_width(1)))
                .map_err(err)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn embedded_font_parses_and_registers() {
        assert_eq!(super::register_font(), Ok(()));
    }

    #[test]
    fn collision_marks_are_not_a_robot_colour() {
        assert!(!crate::PALETTE.contains(&crate::COLLISION));
    }
}
