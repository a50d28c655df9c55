//! Bodies that are not discs: the trajectory's headings are read, the plot
//! draws each polygon where and as turned as the run had it, the replay
//! page carries the shapes and headings, and run.mcap draws rectangles as
//! cubes and other polygons as line loops; disc runs are drawn as before.

mod common;

use common::*;
use mrsim_report::{RunData, write_mcap, write_plots, write_replay};
use mrsim_scenario::ShapeSpec;
use std::fmt::Write as _;
use std::path::Path;

/// r0's rectangle: 2 m along its heading, 1 m across.
const LENGTH: f64 = 2.0;
const WIDTH: f64 = 1.0;
/// o1's triangle, in its body frame.
const TRIANGLE: [[f64; 2]; 3] = [[-0.5, -0.4], [0.5, -0.4], [0.0, 0.5]];
/// o1's fixed heading: 30 degrees.
const O1_HEADING: f64 = std::f64::consts::FRAC_PI_6;

/// r0's heading at `tick`: it turns from 0.3 to 1.1 rad over the run.
fn r0_heading(tick: u64) -> f64 {
    0.3 + 0.8 * tick as f64 / TICKS as f64
}

/// The one-robot synthetic run with r0 a 2 x 1 rectangle that turns and o1
/// a triangle turned by 30 degrees, its trajectory with a theta column.
fn write_shaped_run(dir: &Path) {
    write_run(dir, 1, false);
    let mut sc = scenario(1);
    sc.robots[0].shape = ShapeSpec::Rectangle {
        length: LENGTH,
        width: WIDTH,
    };
    sc.robots[0].radius = (LENGTH / 2.0).hypot(WIDTH / 2.0);
    sc.obstacles[0].shape = ShapeSpec::Polygon {
        points: TRIANGLE.to_vec(),
    };
    sc.obstacles[0].radius = 0.5;
    sc.obstacles[0].heading = O1_HEADING;
    std::fs::write(
        dir.join("scenario.json"),
        serde_json::to_string_pretty(&sc).unwrap(),
    )
    .unwrap();
    let mut csv = String::from("tick,time,body,kind,x,y,vx,vy,theta\n");
    for tick in 0..=TICKS {
        let t = tick as f64 * DT;
        let p = robot_at(0, 1, tick);
        writeln!(
            csv,
            "{tick},{t},r0,robot,{},{},2,0,{}",
            p[0],
            p[1],
            r0_heading(tick)
        )
        .unwrap();
        let o = obstacle_at(tick);
        writeln!(
            csv,
            "{tick},{t},o1,obstacle,{},{},0,-0.5,{O1_HEADING}",
            o[0], o[1]
        )
        .unwrap();
    }
    std::fs::write(dir.join("trajectory.csv"), csv).unwrap();
}

/// The corners of a body-frame polygon at `position` turned by `heading`.
fn placed(points: &[[f64; 2]], position: [f64; 2], heading: f64) -> Vec<[f64; 2]> {
    let (s, c) = heading.sin_cos();
    points
        .iter()
        .map(|p| {
            [
                position[0] + c * p[0] - s * p[1],
                position[1] + s * p[0] + c * p[1],
            ]
        })
        .collect()
}

fn rectangle() -> Vec<[f64; 2]> {
    let (x, y) = (LENGTH / 2.0, WIDTH / 2.0);
    vec![[-x, -y], [x, -y], [x, y], [-x, y]]
}

/// One `<polyline>` of the SVG: its stroke colour, width and points.
#[derive(Debug)]
struct Polyline {
    stroke: String,
    width: String,
    points: Vec<[f64; 2]>,
}

fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let end = start + tag[start..].find('"')?;
    Some(&tag[start..end])
}

fn polylines(svg: &str) -> Vec<Polyline> {
    svg.split("<polyline")
        .skip(1)
        .map(|rest| {
            let tag = &rest[..rest.find("/>").unwrap()];
            let points = attribute(tag, "points")
                .unwrap()
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    [x.parse().unwrap(), y.parse().unwrap()]
                })
                .collect();
            Polyline {
                stroke: attribute(tag, "stroke").unwrap().to_uppercase(),
                width: attribute(tag, "stroke-width").unwrap().to_string(),
                points,
            }
        })
        .collect()
}

/// The map's world-to-pixel transform, found from the arena's outline
/// ([-5, 5] square, drawn black, 2 px, after the mesh): (scale, x0, y0)
/// with pixel = (x0 + scale * x, y0 - scale * y).
fn map_transform(lines: &[Polyline]) -> (f64, f64, f64) {
    let walls: Vec<&Polyline> = lines
        .iter()
        .filter(|l| l.stroke == "#000000" && l.width == "2" && l.points.len() == 2)
        .collect();
    // The file's wall, then the arena's bottom side (-5,-5)->(5,-5) and its
    // right side (5,-5)->(5,5).
    let n = walls.len();
    assert!(n >= 5, "{walls:?}");
    let bottom = &walls[n - 4].points;
    let right = &walls[n - 3].points;
    let scale = (bottom[1][0] - bottom[0][0]) / 10.0;
    assert!(scale > 10.0, "{bottom:?}");
    assert!(
        ((right[0][1] - right[1][1]) / 10.0 - scale).abs() < 0.2,
        "equal aspect ratio: {right:?}"
    );
    (
        scale,
        bottom[0][0] + 5.0 * scale,
        bottom[0][1] - 5.0 * scale,
    )
}

/// Every point of `got` within `tol` px of the same point of `want`.
fn assert_near(got: &[[f64; 2]], want: &[[f64; 2]], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g[0] - w[0]).abs() <= tol && (g[1] - w[1]).abs() <= tol,
            "{what}: {got:?} vs {want:?}"
        );
    }
}

#[test]
fn the_trajectory_headings_are_read_into_each_sample_from_csv_and_parquet() {
    let dir = temp_dir("shape-load");
    write_shaped_run(&dir);
    let run = RunData::load(&dir).unwrap();
    let r0 = run.trajectory.body("r0").unwrap();
    assert_eq!(r0.at(0).unwrap().theta, Some(r0_heading(0)));
    assert_eq!(r0.at(TICKS).unwrap().theta, Some(r0_heading(TICKS)));
    let o1 = run.trajectory.body("o1").unwrap();
    assert_eq!(o1.at(7).unwrap().theta, Some(O1_HEADING));
    // The same rows in trajectory.parquet give the same samples.
    let pq = temp_dir("shape-load-pq");
    for f in ["scenario.json", "events.jsonl"] {
        std::fs::copy(dir.join(f), pq.join(f)).unwrap();
    }
    let mut sc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pq.join("scenario.json")).unwrap()).unwrap();
    sc["output"]["trajectory"] = "parquet".into();
    std::fs::write(pq.join("scenario.json"), sc.to_string()).unwrap();
    use mrsim_runfolder::trajectory::{BodyCells, ParquetTrajectoryWriter};
    let mut w = ParquetTrajectoryWriter::create(&pq.join("trajectory.parquet"), true).unwrap();
    for b in &run.trajectory.bodies {
        let kind = if b.kind == mrsim_report::BodyKind::Robot {
            "robot"
        } else {
            "obstacle"
        };
        let cells = BodyCells::new(&b.name, kind);
        for s in &b.samples {
            w.push(
                s.tick,
                s.time,
                &cells,
                [s.x, s.y, s.vx, s.vy],
                s.theta.unwrap(),
            )
            .unwrap();
        }
    }
    w.finish().unwrap();
    let from_parquet = RunData::load(&pq).unwrap();
    for b in &run.trajectory.bodies {
        assert_eq!(
            from_parquet.trajectory.body(&b.name).unwrap().samples,
            b.samples
        );
    }
    // A run without the column has no headings.
    let plain = temp_dir("shape-load-plain");
    write_run(&plain, 1, false);
    let run = RunData::load(&plain).unwrap();
    assert!(
        run.trajectory
            .bodies
            .iter()
            .all(|b| b.samples.iter().all(|s| s.theta.is_none()))
    );
}

#[test]
fn a_bad_heading_is_refused_at_its_line_and_a_torn_last_one_left_out() {
    let dir = temp_dir("shape-bad-theta");
    write_shaped_run(&dir);
    let path = dir.join("trajectory.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line 4 is r0's row at tick 1.
    lines[3] = lines[3].rsplit_once(',').unwrap().0.to_string() + ",x";
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let e = RunData::load(&dir).unwrap_err().to_string();
    assert!(
        e.contains("trajectory.csv:4:") && e.contains("`theta`"),
        "{e}"
    );
    // Cut inside the last row's heading: that row is left out, the rest kept.
    write_shaped_run(&dir);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, &text[..text.len() - 4]).unwrap();
    let run = RunData::load(&dir).unwrap();
    assert_eq!(run.cut.len(), 1, "{:?}", run.cut);
    let o1 = run.trajectory.body("o1").unwrap();
    assert_eq!(o1.samples.len(), TICKS as usize);
    let r0 = run.trajectory.body("r0").unwrap();
    assert_eq!(r0.at(TICKS).unwrap().theta, Some(r0_heading(TICKS)));
}

#[test]
fn a_body_look_turns_a_robot_by_its_samples_and_an_obstacle_by_its_fixed_heading() {
    let dir = temp_dir("shape-look");
    write_shaped_run(&dir);
    let run = RunData::load(&dir).unwrap();
    let looks = run.looks_by_name();
    let r0 = looks["r0"];
    assert!(!r0.is_disc());
    let s = run.trajectory.body("r0").unwrap().at(20).unwrap();
    assert_eq!(r0.heading(Some(s)), r0_heading(20));
    // A sample without a heading: the start heading (a holonomic robot: 0).
    assert_eq!(r0.heading(None), 0.0);
    let outline = r0.outline([1.0, 2.0], std::f64::consts::FRAC_PI_2).unwrap();
    assert_near(
        &outline,
        &[[1.5, 1.0], [1.5, 3.0], [0.5, 3.0], [0.5, 1.0]],
        1e-12,
        "r0 turned a quarter",
    );
    let o1 = looks["o1"];
    let moving = run.trajectory.body("o1").unwrap().at(3).unwrap();
    assert_eq!(o1.heading(Some(moving)), O1_HEADING);
    assert_eq!(o1.heading(None), O1_HEADING);
    // Discs have no outline.
    let plain = temp_dir("shape-look-plain");
    write_run(&plain, 1, false);
    let run = RunData::load(&plain).unwrap();
    let looks = run.looks_by_name();
    assert!(looks["r0"].is_disc() && looks["o1"].is_disc());
    assert_eq!(looks["r0"].outline([0.0, 0.0], 0.0), None);
}

#[test]
fn the_plot_draws_the_rectangle_at_its_start_and_end_poses_and_the_turned_triangle() {
    let dir = temp_dir("shape-plot");
    write_shaped_run(&dir);
    let run = RunData::load(&dir).unwrap();
    write_plots(&run, &dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("plot.svg")).unwrap();
    let lines = polylines(&svg);
    let (scale, x0, y0) = map_transform(&lines);
    let px = |p: &[f64; 2]| [x0 + scale * p[0], y0 - scale * p[1]];
    let closed = |pts: Vec<[f64; 2]>| {
        let mut v: Vec<[f64; 2]> = pts.iter().map(px).collect();
        v.push(v[0]);
        v
    };
    let colour = mrsim_report::hex(mrsim_report::robot_color(0)).to_uppercase();
    let robot: Vec<&Polyline> = lines
        .iter()
        .filter(|l| l.stroke == colour && l.points.len() == 5)
        .collect();
    assert_eq!(robot.len(), 2, "r0 at its start and its end: {robot:?}");
    // At its start (2 px) and where it ended (1 px), each turned as the
    // trajectory has it then; the start and end points, in pixels.
    let (start, end) = (robot_at(0, 1, 0), robot_at(0, 1, TICKS));
    assert_eq!(robot[0].width, "2");
    assert_near(
        &robot[0].points,
        &closed(placed(&rectangle(), start, r0_heading(0))),
        1.5,
        "r0 at its start",
    );
    assert_eq!(robot[1].width, "1");
    assert_near(
        &robot[1].points,
        &closed(placed(&rectangle(), end, r0_heading(TICKS))),
        1.5,
        "r0 at its end",
    );
    // The triangle at both ends of its path, at 30 degrees, in grey.
    let grey: Vec<&Polyline> = lines
        .iter()
        .filter(|l| l.stroke == "#828282" && l.points.len() == 4 && l.points[0] == l.points[3])
        .collect();
    assert_eq!(grey.len(), 2, "{grey:?}");
    for (line, tick) in grey.iter().zip([0, TICKS]) {
        assert_near(
            &line.points,
            &closed(placed(&TRIANGLE, obstacle_at(tick), O1_HEADING)),
            1.5,
            "o1",
        );
    }
    // No circle is drawn for either body.
    assert!(!svg.contains("<circle"), "a disc was drawn");
}

#[test]
fn a_disc_run_plot_draws_circles_and_no_polygon() {
    let dir = temp_dir("shape-plot-disc");
    write_run(&dir, 1, false);
    let run = RunData::load(&dir).unwrap();
    write_plots(&run, &dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("plot.svg")).unwrap();
    // r0's start, o1 at both ends.
    assert_eq!(svg.matches("<circle").count(), 3);
    let colour = mrsim_report::hex(mrsim_report::robot_color(0)).to_uppercase();
    assert!(
        !polylines(&svg)
            .iter()
            .any(|l| l.stroke == colour && l.points.len() == 5)
    );
}

#[test]
fn the_replay_page_carries_each_polygon_and_the_headings_it_is_drawn_at() {
    let dir = temp_dir("shape-replay");
    write_shaped_run(&dir);
    let run = RunData::load(&dir).unwrap();
    write_replay(&run, &dir).unwrap();
    let data = replay_json(&dir);
    let r0 = &data["robots"][0];
    let shape: Vec<[f64; 2]> = serde_json::from_value(r0["shape"].clone()).unwrap();
    assert_near(&shape, &rectangle(), 1e-9, "r0's shape");
    let theta = r0["theta"].as_array().unwrap();
    assert_eq!(theta.len(), TICKS as usize + 1);
    for (tick, th) in theta.iter().enumerate() {
        let want = (r0_heading(tick as u64) * 1000.0).round() / 1000.0;
        assert_eq!(th.as_f64(), Some(want), "tick {tick}");
    }
    let o1 = &data["obstacles"][0];
    let shape: Vec<[f64; 2]> = serde_json::from_value(o1["shape"].clone()).unwrap();
    assert_near(&shape, &TRIANGLE, 1e-9, "o1's shape");
    assert!((o1["heading"].as_f64().unwrap() - O1_HEADING).abs() < 1e-6);
}

#[test]
fn a_disc_run_replay_has_no_shapes_and_no_headings() {
    let dir = temp_dir("shape-replay-disc");
    write_run(&dir, 2, false);
    let run = RunData::load(&dir).unwrap();
    write_replay(&run, &dir).unwrap();
    let data = replay_json(&dir);
    for body in data["robots"]
        .as_array()
        .unwrap()
        .iter()
        .chain(data["obstacles"].as_array().unwrap())
    {
        let keys: Vec<&String> = body.as_object().unwrap().keys().collect();
        assert!(
            !keys
                .iter()
                .any(|k| ["shape", "theta", "heading"].contains(&k.as_str())),
            "{keys:?}"
        );
    }
}

#[test]
fn run_mcap_draws_the_rectangle_as_a_cube_and_the_triangle_as_a_line_loop() {
    let dir = temp_dir("shape-mcap");
    write_shaped_run(&dir);
    let run = RunData::load(&dir).unwrap();
    write_mcap(&run, &dir).unwrap();
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    // The file is JSON messages, uncompressed: find the scene at tick 10
    // by r0's position in it.
    let scenes: Vec<serde_json::Value> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/scene")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    // The first holds the walls and goals, then one per tick.
    assert_eq!(scenes.len(), TICKS as usize + 2);
    let at10 = &scenes[11]["entities"];
    let entity = |id: &str| {
        at10.as_array()
            .unwrap()
            .iter()
            .find(|e| e["id"] == id)
            .unwrap()
            .clone()
    };
    let r0 = entity("r0");
    assert!(r0["cylinders"].as_array().unwrap().is_empty());
    let cube = &r0["cubes"][0];
    assert_eq!(cube["size"]["x"], LENGTH);
    assert_eq!(cube["size"]["y"], WIDTH);
    let p = robot_at(0, 1, 10);
    assert!((cube["pose"]["position"]["x"].as_f64().unwrap() - p[0]).abs() < 1e-9);
    let q = &cube["pose"]["orientation"];
    let yaw = 2.0 * q["z"].as_f64().unwrap().atan2(q["w"].as_f64().unwrap());
    assert!((yaw - r0_heading(10)).abs() < 1e-9, "{yaw}");
    let o1 = entity("o1");
    assert!(o1["cylinders"].as_array().unwrap().is_empty());
    let line = &o1["lines"][0];
    assert_eq!(line["type"], 1, "LINE_LOOP");
    let points: Vec<[f64; 2]> = line["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| [p["x"].as_f64().unwrap(), p["y"].as_f64().unwrap()])
        .collect();
    assert_near(&points, &TRIANGLE, 1e-12, "o1's loop, body frame");
    let q = &line["pose"]["orientation"];
    let yaw = 2.0 * q["z"].as_f64().unwrap().atan2(q["w"].as_f64().unwrap());
    assert!((yaw - O1_HEADING).abs() < 1e-9, "{yaw}");
}
