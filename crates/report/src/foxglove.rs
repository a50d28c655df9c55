//! `run.mcap`: a finished run for Foxglove (or Lichtblick), the viewer of
//! ROS 2 bags, written from the run folder like the plots.
//!
//! Every message is JSON in one of Foxglove's well-known schemas, so the 3D
//! panel draws it without a plugin:
//!
//! | topic | schema | what |
//! | --- | --- | --- |
//! | `/scene` | `foxglove.SceneUpdate` | each recorded tick: robots in their colour with a heading arrow and their name, obstacles in grey, people in sandy brown, each as its shape (a disc as a cylinder, a rectangle as a cube of its length x width x 0.2 turned by its heading, another polygon as its outline, a line loop in the body's frame posed at its heading); at the first tick also the walls (the arena's, the file's and the map's outlines) and the goals, which last |
//! | `/tf` | `foxglove.FrameTransforms` | each recorded tick: `world` -> each robot's frame (its position; its heading for a unicycle or a body that is not a disc, none for a holonomic disc, which does not turn) |
//! | `/<robot>/scan` | `foxglove.LaserScan` | each scan in scan.csv, in the robot's frame |
//! | `/map` | `foxglove.Grid` | once: the map's occupancy (ROS values: 0 free, 100 occupied, -1 unknown; INT8) |
//! | `/stats` | `mrsim.RobotStats` | each recorded tick: per robot position, velocity, speed, distance to its goal, arrived, contacts so far |
//!
//! Log and publish times are simulated time (ns), so Foxglove's timeline is
//! the run's clock. The schemas written into the file are JSON Schemas of
//! the fields used here, named as Foxglove names them; the tests check
//! every message against Foxglove's own published schemas.

use crate::{BodyKind, EventKind, RenderError, RunData, robot_color, sensing};
use mrsim_scenario::ShapeSpec;
use serde_json::{Value, json};
use std::collections::{BTreeMap, HashMap};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// The file [`write_mcap`] writes in the run folder.
pub use mrsim_runfolder::MCAP_FILE;

/// Height of the discs and walls drawn in the 3D panel, m (the world is
/// flat; a little height makes them visible from any angle).
const HEIGHT: f64 = 0.2;

/// What [`write_mcap`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct McapWritten {
    /// run.mcap's path.
    pub path: PathBuf,
    /// The scenario has a map whose YAML could not be read from where the
    /// run found it (a folder moved elsewhere): the file has the map's
    /// outline among the walls, but no `/map` grid. The YAML's path.
    pub map_not_found: Option<String>,
    /// The files the run was cut in ([`RunData::cut`]): the export goes up
    /// to the cut.
    pub cut: Vec<mrsim_runfolder::stream::Cut>,
}

/// Reads the run folder `dir` and writes `run.mcap` into it.
pub fn export_mcap(dir: &Path) -> Result<McapWritten, RenderError> {
    let run = RunData::load(dir)?;
    write_mcap(&run, dir)
}

/// Writes `run.mcap` for `run` into `dir`.
pub fn write_mcap(run: &RunData, dir: &Path) -> Result<McapWritten, RenderError> {
    let path = dir.join(MCAP_FILE);
    let mcap_err = |e: ::mcap::McapError| RenderError::Mcap {
        path: path.clone(),
        reason: e.to_string(),
    };
    let file = std::fs::File::create(&path).map_err(|source| RenderError::Io {
        path: path.clone(),
        source,
    })?;
    let options = ::mcap::WriteOptions::new()
        .compression(None)
        .profile("")
        .library(concat!("mrsim ", env!("CARGO_PKG_VERSION")));
    let mut out = options.create(BufWriter::new(file)).map_err(mcap_err)?;
    let mut channels = Channels::default();
    let add = |out: &mut ::mcap::Writer<_>,
               topic: &str,
               schema: &str|
     -> Result<u16, ::mcap::McapError> {
        let id = out.add_schema(
            schema,
            "jsonschema",
            schema_of(schema).to_string().as_bytes(),
        )?;
        out.add_channel(id, topic, "json", &BTreeMap::new())
    };
    channels.scene = add(&mut out, "/scene", "foxglove.SceneUpdate").map_err(mcap_err)?;
    channels.tf = add(&mut out, "/tf", "foxglove.FrameTransforms").map_err(mcap_err)?;
    channels.stats = add(&mut out, "/stats", "mrsim.RobotStats").map_err(mcap_err)?;

    let scene = &run.scenario;
    let specs = run.specs_by_name();
    let looks = run.looks_by_name();
    let obstacle_shapes: HashMap<&str, &ShapeSpec> = scene
        .obstacles
        .iter()
        .map(|o| (o.name.as_str(), &o.shape))
        .collect();
    let first_ns = run.trajectory.times.first().map_or(0, |&t| ns(t));
    let mut seq = 0u32;
    let mut write = |out: &mut ::mcap::Writer<_>, channel: u16, ns: u64, msg: &Value| {
        seq = seq.wrapping_add(1);
        out.write_to_known_channel(
            &::mcap::records::MessageHeader {
                channel_id: channel,
                sequence: seq,
                log_time: ns,
                publish_time: ns,
            },
            msg.to_string().as_bytes(),
        )
    };

    // The map, once.
    let grid = map_grid(run, first_ns);
    let map_not_found = match (&grid, &scene.map) {
        (None, Some(info)) => Some(info.file.clone()),
        _ => None,
    };
    if let Some(grid) = grid {
        let id = add(&mut out, "/map", "foxglove.Grid").map_err(mcap_err)?;
        write(&mut out, id, first_ns, &grid).map_err(mcap_err)?;
    }

    // What lasts: walls and goals, at the first tick.
    let mut statics = vec![walls_entity(run, first_ns)];
    for (i, r) in scene.robots.iter().enumerate() {
        statics.push(goal_entity(
            &r.name,
            r.goal,
            r.radius,
            robot_color(i),
            first_ns,
        ));
    }
    write(
        &mut out,
        channels.scene,
        first_ns,
        &json!({ "deletions": [], "entities": statics }),
    )
    .map_err(mcap_err)?;

    // Each recorded tick.
    let mut arrived: HashMap<&str, u64> = HashMap::new();
    let mut contacts: HashMap<&str, Vec<u64>> = HashMap::new();
    for e in &run.events {
        match &e.kind {
            EventKind::GoalReached { robot } => {
                arrived.entry(robot.as_str()).or_insert(e.tick);
            }
            EventKind::Collision { a, b, .. } => {
                contacts.entry(a.as_str()).or_default().push(e.tick);
                contacts.entry(b.as_str()).or_default().push(e.tick);
            }
            _ => {}
        }
    }
    // The robots whose frame turns: unicycles and bodies not discs.
    let turning: std::collections::HashSet<&str> = scene
        .robots
        .iter()
        .filter(|r| r.kinematics == mrsim_scenario::Kinematics::Unicycle || !r.shape.is_disc())
        .map(|r| r.name.as_str())
        .collect();
    for (k, &tick) in run.trajectory.ticks.iter().enumerate() {
        let t_ns = ns(run.trajectory.times[k]);
        let stamp = time(t_ns);
        let mut entities = Vec::new();
        let mut transforms = Vec::new();
        let mut stats = Vec::new();
        for body in &run.trajectory.bodies {
            let Some(s) = body.at(tick) else { continue };
            let name = body.name.as_str();
            match body.kind {
                BodyKind::Robot => {
                    let color = robot_color(run.robot_index(name).unwrap_or(0));
                    let spec = specs.get(name);
                    let look = looks.get(name).copied();
                    let body = Body {
                        name,
                        x: s.x,
                        y: s.y,
                        radius: spec.map_or(run.radius_of(name), |r| r.radius),
                        shape: spec.map_or(&ShapeSpec::Disc, |r| &r.shape),
                        look,
                        heading: look.map_or(0.0, |l| l.heading(Some(s))),
                    };
                    entities.push(robot_entity(&body, s, color, &stamp));
                    let turns = turning.contains(name);
                    transforms.push(json!({
                        "timestamp": stamp,
                        "parent_frame_id": "world",
                        "child_frame_id": name,
                        "translation": { "x": s.x, "y": s.y, "z": 0.0 },
                        "rotation": yaw(if turns { s.theta.unwrap_or(0.0) } else { 0.0 }),
                    }));
                    let goal = specs.get(name).map(|r| r.goal);
                    stats.push(json!({
                        "name": name,
                        "x": s.x, "y": s.y, "vx": s.vx, "vy": s.vy,
                        "speed": s.speed(),
                        "distance_to_goal": goal.map_or(Value::Null, |g| json!((g[0] - s.x).hypot(g[1] - s.y))),
                        "arrived": arrived.get(name).is_some_and(|&t| t <= tick),
                        "contacts": contacts.get(name).map_or(0, |c| c.iter().filter(|&&t| t <= tick).count()),
                    }));
                }
                BodyKind::Obstacle => {
                    let look = looks.get(name).copied();
                    let body = Body {
                        name,
                        x: s.x,
                        y: s.y,
                        radius: run.radius_of(name),
                        shape: obstacle_shapes
                            .get(name)
                            .copied()
                            .unwrap_or(&ShapeSpec::Disc),
                        look,
                        heading: look.map_or(0.0, |l| l.heading(None)),
                    };
                    entities.push(body_entity(&body, [0x88, 0x88, 0x88], &stamp));
                }
                BodyKind::Person => {
                    let body = Body {
                        name,
                        x: s.x,
                        y: s.y,
                        radius: run.radius_of(name),
                        shape: &ShapeSpec::Disc,
                        look: None,
                        heading: 0.0,
                    };
                    entities.push(body_entity(&body, crate::PERSON, &stamp));
                }
            }
        }
        write(
            &mut out,
            channels.scene,
            t_ns,
            &json!({ "deletions": [], "entities": entities }),
        )
        .map_err(mcap_err)?;
        write(
            &mut out,
            channels.tf,
            t_ns,
            &json!({ "transforms": transforms }),
        )
        .map_err(mcap_err)?;
        write(
            &mut out,
            channels.stats,
            t_ns,
            &json!({ "timestamp": stamp, "tick": tick, "robots": stats }),
        )
        .map_err(mcap_err)?;
    }

    // The scans, each on its robot's topic.
    let dt = scene.world.dt;
    let mut scan_topics: HashMap<String, u16> = HashMap::new();
    for row in sensing::scans(dir)?.unwrap_or_default() {
        let id = match scan_topics.get(&row.robot) {
            Some(&id) => id,
            None => {
                let id = add(
                    &mut out,
                    &format!("/{}/scan", row.robot),
                    "foxglove.LaserScan",
                )
                .map_err(mcap_err)?;
                scan_topics.insert(row.robot.clone(), id);
                id
            }
        };
        let t_ns = ns(row.tick as f64 * dt);
        let n = row.ranges.len().max(1);
        let msg = json!({
            "timestamp": time(t_ns),
            "frame_id": row.robot,
            "pose": pose(0.0, 0.0, 0.0),
            "start_angle": row.angle_min,
            "end_angle": row.angle_min + row.angle_increment * (n - 1) as f64,
            // No return: 0, a point at the sensor under the robot's disc
            // (JSON has no NaN or infinity to say it).
            "ranges": row.ranges.iter().map(|r| r.unwrap_or(0.0)).collect::<Vec<_>>(),
            "intensities": [],
        });
        write(&mut out, id, t_ns, &msg).map_err(mcap_err)?;
    }
    out.finish().map_err(mcap_err)?;
    Ok(McapWritten {
        path,
        map_not_found,
        cut: run.cut.clone(),
    })
}

#[derive(Default)]
struct Channels {
    scene: u16,
    tf: u16,
    stats: u16,
}

/// Simulated seconds as nanoseconds.
fn ns(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

/// A Foxglove time.
fn time(ns: u64) -> Value {
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

/// A rotation about z.
fn yaw(theta: f64) -> Value {
    let (s, c) = (theta / 2.0).sin_cos();
    json!({ "x": 0.0, "y": 0.0, "z": s, "w": c })
}

fn pose(x: f64, y: f64, theta: f64) -> Value {
    json!({ "position": { "x": x, "y": y, "z": 0.0 }, "orientation": yaw(theta) })
}

fn color(c: [u8; 3], a: f64) -> Value {
    json!({
        "r": f64::from(c[0]) / 255.0, "g": f64::from(c[1]) / 255.0,
        "b": f64::from(c[2]) / 255.0, "a": a,
    })
}

/// A scene entity with every primitive list present (Foxglove's schema
/// requires them all) and those of `parts` filled in.
fn entity(id: &str, stamp: &Value, parts: Value) -> Value {
    let mut e = json!({
        "timestamp": stamp, "frame_id": "world", "id": id,
        "lifetime": { "sec": 0, "nsec": 0 }, "frame_locked": false, "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [],
        "triangles": [], "texts": [], "models": [],
    });
    if let (Some(e), Some(parts)) = (e.as_object_mut(), parts.as_object()) {
        for (k, v) in parts {
            e.insert(k.clone(), v.clone());
        }
    }
    e
}

fn cylinder(x: f64, y: f64, radius: f64, c: [u8; 3], alpha: f64) -> Value {
    json!({
        "pose": { "position": { "x": x, "y": y, "z": HEIGHT / 2.0 }, "orientation": yaw(0.0) },
        "size": { "x": 2.0 * radius, "y": 2.0 * radius, "z": HEIGHT },
        "bottom_scale": 1.0, "top_scale": 1.0, "color": color(c, alpha),
    })
}

fn label(x: f64, y: f64, text: &str) -> Value {
    json!({
        "pose": { "position": { "x": x, "y": y, "z": HEIGHT * 2.0 }, "orientation": yaw(0.0) },
        "billboard": true, "font_size": 14.0, "scale_invariant": true,
        "color": color([0x20, 0x20, 0x20], 1.0), "text": text,
    })
}

/// A body at one tick, as the scene draws it.
struct Body<'a> {
    name: &'a str,
    x: f64,
    y: f64,
    /// The disc's radius (a polygon's circumscribed one).
    radius: f64,
    /// The scenario's shape: a rectangle is drawn as a cube.
    shape: &'a ShapeSpec,
    /// Its look (`None`: a body the scenario does not list, a disc).
    look: Option<crate::BodyLook>,
    /// Its heading, rad.
    heading: f64,
}

/// A rectangle's cube: `length` along the heading, `width` across, posed
/// at the body's centre turned about z.
fn cube(b: &Body, length: f64, width: f64, c: [u8; 3], alpha: f64) -> Value {
    json!({
        "pose": { "position": { "x": b.x, "y": b.y, "z": HEIGHT / 2.0 }, "orientation": yaw(b.heading) },
        "size": { "x": length, "y": width, "z": HEIGHT },
        "color": color(c, alpha),
    })
}

/// A polygon's outline: a line loop (type 1) through its body-frame
/// vertices, posed at the body turned by its heading.
fn outline(b: &Body, points: &[[f64; 2]], c: [u8; 3]) -> Value {
    let points: Vec<Value> = points
        .iter()
        .map(|p| json!({ "x": p[0], "y": p[1], "z": HEIGHT / 2.0 }))
        .collect();
    json!({
        "type": 1, "pose": pose(b.x, b.y, b.heading), "thickness": 0.04, "scale_invariant": false,
        "points": points, "color": color(c, 1.0), "colors": [], "indices": [],
    })
}

/// A body's entity: its shape (a disc's cylinder, a rectangle's cube, a
/// polygon's outline) and its name.
fn body_entity(b: &Body, c: [u8; 3], stamp: &Value) -> Value {
    let text = json!([label(b.x, b.y + b.radius, b.name)]);
    let polygon = b
        .look
        .filter(|l| !l.is_disc())
        .and_then(|l| l.outline([0.0, 0.0], 0.0));
    let parts = match (b.shape, polygon) {
        (ShapeSpec::Rectangle { length, width }, Some(_)) => {
            json!({ "cubes": [cube(b, *length, *width, c, 0.9)], "texts": text })
        }
        (_, Some(points)) => json!({ "lines": [outline(b, &points, c)], "texts": text }),
        (_, None) => {
            json!({ "cylinders": [cylinder(b.x, b.y, b.radius, c, 0.9)], "texts": text })
        }
    };
    entity(b.name, stamp, parts)
}

/// A robot: its shape, its name and an arrow along its heading (a
/// unicycle, a body that is not a disc) or its velocity (a holonomic disc
/// that moves).
fn robot_entity(b: &Body, s: &crate::Sample, c: [u8; 3], stamp: &Value) -> Value {
    let radius = b.radius;
    let mut e = body_entity(b, c, stamp);
    let heading = s
        .theta
        .or_else(|| (s.speed() > 1e-6).then(|| s.vy.atan2(s.vx)));
    if let Some(th) = heading {
        let length = 1.5 * radius;
        e["arrows"] = json!([{
            "pose": {
                "position": { "x": s.x, "y": s.y, "z": HEIGHT * 1.2 },
                "orientation": yaw(th),
            },
            "shaft_length": 0.7 * length, "shaft_diameter": 0.15 * radius,
            "head_length": 0.3 * length, "head_diameter": 0.4 * radius,
            "color": color([0x10, 0x10, 0x10], 1.0),
        }]);
    }
    e
}

fn goal_entity(name: &str, goal: [f64; 2], radius: f64, c: [u8; 3], ns: u64) -> Value {
    let r = radius.max(0.05);
    let p = |dx: f64, dy: f64| json!({ "x": goal[0] + dx, "y": goal[1] + dy, "z": 0.0 });
    entity(
        &format!("goal/{name}"),
        &time(ns),
        json!({ "lines": [{
            "type": 2, "pose": pose(0.0, 0.0, 0.0), "thickness": 0.03, "scale_invariant": false,
            "points": [p(-r, -r), p(r, r), p(-r, r), p(r, -r)],
            "color": color(c, 1.0), "colors": [], "indices": [],
        }] }),
    )
}

/// Every wall segment (arena, file, map outline) as one line list.
fn walls_entity(run: &RunData, ns: u64) -> Value {
    let mut points = Vec::new();
    for [a, b] in run.scenario.all_walls() {
        points.push(json!({ "x": a[0], "y": a[1], "z": 0.0 }));
        points.push(json!({ "x": b[0], "y": b[1], "z": 0.0 }));
    }
    entity(
        "walls",
        &time(ns),
        json!({ "lines": [{
            "type": 2, "pose": pose(0.0, 0.0, 0.0), "thickness": 0.04, "scale_invariant": false,
            "points": points, "color": color([0x40, 0x40, 0x40], 1.0), "colors": [], "indices": [],
        }] }),
    )
}

/// The scenario's map as a Grid, if it has one and its YAML can still be
/// read from where the run found it.
fn map_grid(run: &RunData, ns: u64) -> Option<Value> {
    use base64_like::encode;
    let info = run.scenario.map.as_ref()?;
    let map = mrsim_scenario::map::load(Path::new(&info.file)).ok()?;
    let scale = run.scenario.length_unit.per_metre();
    let [ox, oy, th] = map.meta.origin;
    let cell = map.meta.resolution * scale;
    let bytes: Vec<u8> = map.values.iter().map(|&v| v as u8).collect();
    Some(json!({
        "timestamp": time(ns),
        "frame_id": "world",
        "pose": pose(ox * scale, oy * scale, th),
        "column_count": map.width,
        "cell_size": { "x": cell, "y": cell },
        "row_stride": map.width,
        "cell_stride": 1,
        "fields": [{ "name": "occupancy", "offset": 0, "type": 2 }],
        "data": encode(&bytes),
    }))
}

/// Base64 (RFC 4648, with padding): how JSON-encoded MCAP carries `bytes`
/// fields.
mod base64_like {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

    pub(super) fn encode(bytes: &[u8]) -> String {
        let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
            for (k, shift) in [18, 12, 6, 0].into_iter().enumerate() {
                if k <= chunk.len() {
                    out.push(ALPHABET[((n >> shift) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    #[cfg(test)]
    mod tests {
        #[test]
        fn encodes_as_rfc_4648_does() {
            assert_eq!(super::encode(b""), "");
            assert_eq!(super::encode(b"f"), "Zg==");
            assert_eq!(super::encode(b"fo"), "Zm8=");
            assert_eq!(super::encode(b"foo"), "Zm9v");
            assert_eq!(super::encode(b"foobar"), "Zm9vYmFy");
            assert_eq!(super::encode(&[0xff, 0xfe]), "//4=");
        }
    }
}

/// The JSON Schema written into the file for each schema name: the fields
/// this module writes, with Foxglove's names and types.
fn schema_of(name: &str) -> Value {
    let number = json!({ "type": "number" });
    let obj = |title: &str, props: Value| -> Value {
        let required: Vec<String> = props
            .as_object()
            .map(|p| p.keys().cloned().collect())
            .unwrap_or_default();
        json!({ "title": title, "type": "object", "properties": props, "required": required })
    };
    let time = obj(
        "time",
        json!({ "sec": { "type": "integer", "minimum": 0 }, "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 } }),
    );
    let vec3 = obj(
        "foxglove.Vector3",
        json!({ "x": number, "y": number, "z": number }),
    );
    let quat = obj(
        "foxglove.Quaternion",
        json!({ "x": number, "y": number, "z": number, "w": number }),
    );
    let pose = obj(
        "foxglove.Pose",
        json!({ "position": vec3, "orientation": quat }),
    );
    let color = obj(
        "foxglove.Color",
        json!({ "r": number, "g": number, "b": number, "a": number }),
    );
    let array = |items: Value| json!({ "type": "array", "items": items });
    match name {
        "foxglove.SceneUpdate" => {
            let arrow = obj(
                "foxglove.ArrowPrimitive",
                json!({ "pose": pose, "shaft_length": number, "shaft_diameter": number,
                        "head_length": number, "head_diameter": number, "color": color }),
            );
            let cube = obj(
                "foxglove.CubePrimitive",
                json!({ "pose": pose, "size": vec3, "color": color }),
            );
            let cylinder = obj(
                "foxglove.CylinderPrimitive",
                json!({ "pose": pose, "size": vec3, "bottom_scale": number, "top_scale": number, "color": color }),
            );
            let line = obj(
                "foxglove.LinePrimitive",
                json!({ "type": { "type": "integer", "enum": [0, 1, 2] }, "pose": pose,
                        "thickness": number, "scale_invariant": { "type": "boolean" },
                        "points": array(vec3.clone()), "color": color, "colors": array(color.clone()),
                        "indices": array(json!({ "type": "integer", "minimum": 0 })) }),
            );
            let text = obj(
                "foxglove.TextPrimitive",
                json!({ "pose": pose, "billboard": { "type": "boolean" }, "font_size": number,
                        "scale_invariant": { "type": "boolean" }, "color": color, "text": { "type": "string" } }),
            );
            let entity = obj(
                "foxglove.SceneEntity",
                json!({ "timestamp": time, "frame_id": { "type": "string" }, "id": { "type": "string" },
                        "lifetime": time, "frame_locked": { "type": "boolean" },
                        "metadata": array(obj("foxglove.KeyValuePair", json!({ "key": { "type": "string" }, "value": { "type": "string" } }))),
                        "arrows": array(arrow), "cubes": array(cube), "spheres": array(json!({})),
                        "cylinders": array(cylinder), "lines": array(line), "triangles": array(json!({})),
                        "texts": array(text), "models": array(json!({})) }),
            );
            let deletion = obj(
                "foxglove.SceneEntityDeletion",
                json!({ "timestamp": time, "type": { "type": "integer", "enum": [0, 1] }, "id": { "type": "string" } }),
            );
            obj(
                name,
                json!({ "deletions": array(deletion), "entities": array(entity) }),
            )
        }
        "foxglove.FrameTransforms" => {
            let tf = obj(
                "foxglove.FrameTransform",
                json!({ "timestamp": time, "parent_frame_id": { "type": "string" },
                        "child_frame_id": { "type": "string" }, "translation": vec3, "rotation": quat }),
            );
            obj(name, json!({ "transforms": array(tf) }))
        }
        "foxglove.LaserScan" => obj(
            name,
            json!({ "timestamp": time, "frame_id": { "type": "string" }, "pose": pose,
                    "start_angle": number, "end_angle": number,
                    "ranges": array(number.clone()), "intensities": array(number.clone()) }),
        ),
        "foxglove.Grid" => obj(
            name,
            json!({ "timestamp": time, "frame_id": { "type": "string" }, "pose": pose,
                    "column_count": { "type": "integer", "minimum": 0 },
                    "cell_size": obj("foxglove.Vector2", json!({ "x": number, "y": number })),
                    "row_stride": { "type": "integer", "minimum": 0 },
                    "cell_stride": { "type": "integer", "minimum": 0 },
                    "fields": array(obj("foxglove.PackedElementField",
                        json!({ "name": { "type": "string" }, "offset": { "type": "integer", "minimum": 0 },
                                "type": { "type": "integer", "minimum": 0, "maximum": 8 } }))),
                    "data": { "type": "string", "contentEncoding": "base64" } }),
        ),
        _ => {
            let robot = obj(
                "mrsim.RobotStat",
                json!({ "name": { "type": "string" }, "x": number, "y": number, "vx": number, "vy": number,
                        "speed": number, "distance_to_goal": { "type": ["number", "null"] },
                        "arrived": { "type": "boolean" }, "contacts": { "type": "integer", "minimum": 0 } }),
            );
            obj(
                name,
                json!({ "timestamp": time, "tick": { "type": "integer", "minimum": 0 }, "robots": array(robot) }),
            )
        }
    }
}
