//! Speed against time of the first robot of several runs, one line per run
//! (like Sugiyama et al.'s figs 17 and 20), with each run's peak speed and
//! largest tick-to-tick velocity change in its legend.
//!
//! ```sh
//! cargo run --release -p mrsim-report --example speed_plot -- OUT.svg RUN_DIR...
//! ```
//!
//! Writes OUT.svg and, next to it, the same chart as a PNG.

use mrsim_report::{BodyKind, RunData, robot_color};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

const FONT: &[u8] = include_bytes!("../assets/DejaVuSans-ascii.ttf");
const SIZE: (u32, u32) = (900, 500);

/// One run's line: label, (time, speed) samples, peak, largest |dv|.
struct Line {
    label: String,
    points: Vec<(f64, f64)>,
    peak: f64,
    jump: f64,
    unit: &'static str,
}

fn line(dir: &Path) -> Result<Line, String> {
    let run = RunData::load(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let robot = run
        .trajectory
        .bodies
        .iter()
        .find(|b| b.kind == BodyKind::Robot)
        .ok_or_else(|| format!("{}: no robot in trajectory.csv", dir.display()))?;
    let points: Vec<(f64, f64)> = robot.samples.iter().map(|s| (s.time, s.speed())).collect();
    let peak = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let jump = robot
        .samples
        .windows(2)
        .map(|w| (w[1].vx - w[0].vx).hypot(w[1].vy - w[0].vy))
        .fold(0.0, f64::max);
    let unit = match run.scenario.length_unit {
        mrsim_scenario::LengthUnit::M => "m",
        mrsim_scenario::LengthUnit::Cm => "cm",
        mrsim_scenario::LengthUnit::Mm => "mm",
    };
    Ok(Line {
        unit,
        label: run.scenario.name.clone(),
        points,
        peak,
        jump,
    })
}

fn draw<DB: DrawingBackend>(
    lines: &[Line],
    root: DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let t1 = lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.0))
        .fold(1e-9, f64::max);
    let v1 = lines.iter().map(|l| l.peak).fold(1e-9, f64::max) * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption("robot speed against time", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, 0.0..v1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc(format!("speed [{}/s]", lines[0].unit))
        .bold_line_style(RGBColor(220, 220, 220))
        .light_line_style(RGBColor(242, 242, 242))
        .draw()
        .map_err(e)?;
    for (i, l) in lines.iter().enumerate() {
        let [r, g, b] = robot_color(i);
        let c = RGBColor(r, g, b);
        chart
            .draw_series(LineSeries::new(l.points.iter().copied(), c.stroke_width(2)))
            .map_err(e)?
            .label(format!(
                "{}: peak {:.3} {u}/s, max |dv| per tick {:.3} {u}/s",
                l.label,
                l.peak,
                l.jump,
                u = l.unit
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(180, 180, 180))
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        return Err("usage: speed_plot OUT.svg RUN_DIR...".into());
    }
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the embedded font does not parse".to_string())?;
    let out = PathBuf::from(&args[0]);
    let lines = args[1..]
        .iter()
        .map(|d| line(Path::new(d)))
        .collect::<Result<Vec<_>, _>>()?;
    for l in &lines {
        println!(
            "{}: peak speed {:.3} m/s, max tick-to-tick velocity change {:.4} m/s",
            l.label, l.peak, l.jump
        );
    }
    let mut svg = String::new();
    draw(
        &lines,
        SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(),
    )?;
    std::fs::write(&out, svg).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut pixels = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    draw(
        &lines,
        BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area(),
    )?;
    let png_path = out.with_extension("png");
    let file =
        std::fs::File::create(&png_path).map_err(|e| format!("{}: {e}", png_path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), SIZE.0, SIZE.1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let pe = |e: png::EncodingError| format!("{}: {e}", png_path.display());
    let mut w = enc.write_header().map_err(pe)?;
    w.write_image_data(&pixels).map_err(pe)?;
    w.finish().map_err(pe)?;
    Ok(())
}
