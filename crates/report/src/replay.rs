//! `replay.html`: one self-contained page (no network, no external
//! libraries) that animates the run on a canvas, with the run's data
//! embedded as JSON.
//!
//! Layout, fixed so a screenshot's pixels can be checked: the map canvas is
//! [`MAP_WIDTH`] x [`MAP_HEIGHT`] CSS px at the page's top-left corner, the
//! timing strip (deadline misses and lost agents over time) is
//! [`STRIP_HEIGHT`] px right under it, the controls under that, and the
//! legend and event list to the right from x = 816. World point (x, y) is
//! drawn at [`ReplayView::world_to_canvas`], which is also the page's
//! `window.mrsimReplay.worldToCanvas`.
//!
//! `replay.html?tick=N` (or `#tick=N`) seeks to tick N and stays paused, so
//! a headless screenshot shows a known frame:
//! `chromium --headless --window-size=1100,800 --screenshot=out.png
//! 'file:///…/replay.html?tick=N'`.

use crate::palette::{COLLISION, hex, robot_color};
use crate::{BodyKind, EventKind, RenderError, RunData, write_file};
use serde_json::{Value, json};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Width of the replay's map canvas, CSS px.
pub const MAP_WIDTH: u32 = 800;
/// Height of the replay's map canvas, CSS px.
pub const MAP_HEIGHT: u32 = 600;
/// Height of the timing strip under the map, CSS px.
pub const STRIP_HEIGHT: u32 = 120;
/// Margin inside the map canvas around [`RunData::extent`], px.
const MARGIN: f64 = 12.0;
/// The page lists at most this many encounters.
const MAX_LISTED_ENCOUNTERS: usize = 2000;

/// The event list shows at most this many events.
const MAX_LISTED_EVENTS: usize = 500;
/// At most this many positions (bodies x frames) go into the page: a
/// bigger run is shown at every k-th recorded tick (and its last), so a
/// 10,000-robot page stays a few MB and opens in a few seconds.
pub const MAX_REPLAY_POSITIONS: usize = 1_000_000;

const TEMPLATE: &str = include_str!("replay.html");
const PLACEHOLDER: &str = "__MRSIM_DATA__";

/// The world-to-canvas transform of the replay's map (y up in the world,
/// down on the canvas; equal scale on both axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplayView {
    /// Canvas px per length unit.
    pub scale: f64,
    /// Canvas x of world x = 0.
    pub origin_x: f64,
    /// Canvas y of world y = 0.
    pub origin_y: f64,
}

impl ReplayView {
    /// The transform that fits [`RunData::extent`] into the map canvas,
    /// centred, with a 12 px margin.
    pub fn of(run: &RunData) -> ReplayView {
        let [x0, x1, y0, y1] = run.extent();
        let (w, h) = (MAP_WIDTH as f64, MAP_HEIGHT as f64);
        let scale = ((w - 2.0 * MARGIN) / (x1 - x0)).min((h - 2.0 * MARGIN) / (y1 - y0));
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        ReplayView {
            scale,
            origin_x: w / 2.0 - scale * cx,
            origin_y: h / 2.0 + scale * cy,
        }
    }

    /// Canvas position (CSS px from the map's top-left corner, which is
    /// the page's) of world point (x, y).
    pub fn world_to_canvas(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.origin_x + self.scale * x,
            self.origin_y - self.scale * y,
        )
    }

    /// Radius in px the page draws a body of world radius `radius` with
    /// (robots at least 4 px, obstacles at least 2 px).
    pub fn radius_px(&self, radius: f64, kind: BodyKind) -> f64 {
        let min = match kind {
            BodyKind::Robot => 4.0,
            BodyKind::Obstacle | BodyKind::Person => 2.0,
        };
        (radius * self.scale).max(min)
    }
}

/// Writes `replay.html` for `run` into `dir`.
pub fn write_replay(run: &RunData, dir: &Path) -> Result<(), RenderError> {
    let mut data = replay_data(run);
    crate::sensing::add(&mut data, dir, &run.trajectory.ticks)?;
    // `<` only occurs inside JSON strings, where \u003c means the same:
    // no `</script>` can end the data block early.
    let json = data.to_string().replace('<', "\\u003c");
    let page = TEMPLATE.replacen(PLACEHOLDER, &json, 1);
    write_file(&dir.join(mrsim_runfolder::REPLAY_FILE), page.as_bytes())
}

/// Every how many recorded ticks the page shows a frame: 1 unless bodies
/// x ticks exceeds [`MAX_REPLAY_POSITIONS`].
pub fn replay_every(run: &RunData) -> usize {
    let bodies = run.robot_names().len()
        + run
            .trajectory
            .bodies
            .iter()
            .filter(|b| b.kind != BodyKind::Robot)
            .count();
    let positions = bodies.max(1) * run.trajectory.ticks.len();
    positions.div_ceil(MAX_REPLAY_POSITIONS).max(1)
}

/// Rounds to `decimals` places (NaN and infinities become null).
fn round(v: f64, decimals: i32) -> Value {
    if !v.is_finite() {
        return Value::Null;
    }
    let f = 10f64.powi(decimals);
    json!((v * f).round() / f)
}

fn replay_data(run: &RunData) -> Value {
    let view = ReplayView::of(run);
    // Positions to about 1/20 px: keeps the page small for big runs.
    let decimals = (20.0 * view.scale).log10().ceil().clamp(0.0, 9.0) as i32;
    let every = replay_every(run);
    let recorded = &run.trajectory.ticks;
    let mut picked: Vec<usize> = (0..recorded.len()).step_by(every).collect();
    if let Some(last) = recorded.len().checked_sub(1)
        && picked.last() != Some(&last)
    {
        picked.push(last);
    }
    let ticks: Vec<u64> = picked.iter().map(|&i| recorded[i]).collect();
    let times: Vec<Value> = picked
        .iter()
        .map(|&i| round(run.trajectory.times[i], 6))
        .collect();
    let ticks = &ticks;
    let frame_of = |tick: u64| ticks.partition_point(|&t| t <= tick).saturating_sub(1);
    let names = run.robot_names();
    let by_name = run.tracks_by_name();
    let specs = run.specs_by_name();

    let track = |name: &str| -> (Vec<Value>, Vec<Value>) {
        match by_name.get(name) {
            Some(body) => ticks
                .iter()
                .map(|&t| match body.at(t) {
                    Some(s) => (round(s.x, decimals), round(s.y, decimals)),
                    None => (Value::Null, Value::Null),
                })
                .unzip(),
            None => (
                vec![Value::Null; ticks.len()],
                vec![Value::Null; ticks.len()],
            ),
        }
    };

    let looks = run.looks_by_name();
    // A polygon's vertices in the body frame, to the page's precision.
    let shape_of = |name: &str| -> Option<Value> {
        let look = looks.get(name).filter(|l| !l.is_disc())?;
        let points = look.outline([0.0, 0.0], 0.0)?;
        Some(Value::Array(
            points
                .iter()
                .map(|p| json!([round(p[0], decimals), round(p[1], decimals)]))
                .collect(),
        ))
    };
    // One heading per frame (null where the body has no sample or no
    // heading), for the robots whose heading shows: unicycles, which turn,
    // and bodies that are not discs.
    let headings = |name: &str| -> Value {
        let body = by_name.get(name);
        Value::Array(
            ticks
                .iter()
                .map(
                    |&t| match body.and_then(|b| b.at(t)).and_then(|s| s.theta) {
                        Some(th) => json!((th * 1000.0).round() / 1000.0),
                        None => Value::Null,
                    },
                )
                .collect(),
        )
    };
    let has_theta = |name: &str| {
        by_name
            .get(name)
            .is_some_and(|b| b.samples.iter().any(|s| s.theta.is_some()))
    };

    let robots: Vec<Value> = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let spec = specs.get(name.as_str());
            let (x, y) = track(name);
            let shape = shape_of(name);
            let turns = spec.is_some_and(|s| s.kinematics == mrsim_scenario::Kinematics::Unicycle)
                || shape.is_some();
            let mut r = json!({
                "name": name,
                "color": hex(robot_color(i)),
                "radius": spec.map_or(0.0, |s| s.radius),
                "planner": spec.map(|s| s.planner.clone()),
                "goal": spec.map(|s| [round(s.goal[0], decimals), round(s.goal[1], decimals)]),
                "route": run.routes.get(name).map(|r| {
                    r.iter()
                        .map(|p| [round(p[0], decimals), round(p[1], decimals)])
                        .collect::<Vec<_>>()
                }),
                "x": x,
                "y": y,
            });
            if turns && has_theta(name) {
                r["theta"] = headings(name);
            }
            if let Some(shape) = shape {
                r["shape"] = shape;
            }
            r
        })
        .collect();
    let obstacles: Vec<Value> = run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Obstacle)
        .map(|b| {
            let (x, y) = track(&b.name);
            let mut o = json!({ "name": b.name, "radius": run.radius_of(&b.name), "x": x, "y": y });
            if let Some(shape) = shape_of(&b.name) {
                let heading = looks.get(b.name.as_str()).map_or(0.0, |l| l.heading(None));
                o["shape"] = shape;
                o["heading"] = round(heading, 6);
            }
            o
        })
        .collect();
    // People: discs in their own colour, as the plot draws them.
    let people: Vec<Value> = run
        .trajectory
        .bodies
        .iter()
        .filter(|b| b.kind == BodyKind::Person)
        .map(|b| {
            let (x, y) = track(&b.name);
            json!({ "name": b.name, "radius": run.radius_of(&b.name), "x": x, "y": y })
        })
        .collect();
    let walls: Vec<Value> = run
        .scenario
        .all_walls()
        .iter()
        .map(|w| json!([w[0][0], w[0][1], w[1][0], w[1][1]]))
        .collect();

    let index: HashMap<&str, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    let robot_of = |name: &str| index.get(name).copied();
    let mut collisions = Vec::new();
    // Columns, not an object per miss: a run that misses every tick has a
    // miss per robot and tick.
    let (mut miss_frames, mut miss_robots) = (Vec::new(), Vec::new());
    let mut goals = Vec::new();
    let mut lost: Vec<Value> = Vec::new();
    let mut open_lost: BTreeMap<usize, usize> = BTreeMap::new();
    let mut listed = Vec::new();
    let last_frame = ticks.len().saturating_sub(1);
    // In tick order (stable), whatever order the world logged them in.
    let mut events: Vec<&crate::Event> = run.events.iter().collect();
    events.sort_by_key(|e| e.tick);
    for e in events {
        let frame = frame_of(e.tick);
        let text = match &e.kind {
            EventKind::Collision { a, b, .. } => {
                if let Some(p) = run.collision_point(e) {
                    collisions.push(json!({
                        "frame": frame, "tick": e.tick, "a": a, "b": b,
                        "x": round(p[0], decimals), "y": round(p[1], decimals),
                    }));
                }
                format!("collision {a} - {b}")
            }
            EventKind::GoalReached { robot } => {
                if let Some(i) = robot_of(robot) {
                    goals.push(json!({ "frame": frame, "robot": i }));
                }
                format!("{robot} reached its goal")
            }
            EventKind::DeadlineMiss { robot, late_us } => {
                if let Some(i) = robot_of(robot) {
                    miss_frames.push(frame);
                    miss_robots.push(i);
                }
                match late_us {
                    Some(us) => format!("{robot} missed the deadline by {us:.0} us"),
                    None => format!("{robot} missed the deadline"),
                }
            }
            EventKind::AgentLost { robot, reason } => {
                if let Some(i) = robot_of(robot) {
                    open_lost.entry(i).or_insert(frame);
                }
                format!("{robot}'s agent lost: {reason}")
            }
            EventKind::AgentRejoined { robot } => {
                if let Some(i) = robot_of(robot)
                    && let Some(from) = open_lost.remove(&i)
                {
                    lost.push(json!({ "robot": i, "from": from, "to": frame }));
                }
                format!("{robot}'s agent rejoined")
            }
            EventKind::CommandRejected { robot, reason } => {
                format!("command for {robot} rejected: {reason}")
            }
            EventKind::Unknown => continue,
        };
        if listed.len() < MAX_LISTED_EVENTS {
            listed.push(json!({ "frame": frame, "tick": e.tick, "time": e.time, "text": text }));
        }
    }
    // Encounters (encounters.csv), in the order they began: the page lists
    // them and highlights the two bodies of the one picked.
    let mut met: Vec<&mrsim_runfolder::metrics::Encounter> = run.encounters.iter().collect();
    met.sort_by_key(|e| (e.start_tick, e.end_tick));
    let encounters: Vec<Value> = met
        .iter()
        .take(MAX_LISTED_ENCOUNTERS)
        .map(|e| {
            json!({
                "a": e.a, "b": e.b,
                "from": frame_of(e.start_tick), "to": frame_of(e.end_tick),
                "startTick": e.start_tick, "endTick": e.end_tick,
                "minGap": round(e.min_gap, 3),
                "minTtc": e.min_ttc.map(|t| round(t, 3)),
                "kind": e.kind, "gaveWay": e.gave_way, "bKind": e.b_kind,
            })
        })
        .collect();
    for (i, from) in open_lost {
        lost.push(json!({ "robot": i, "from": from, "to": last_frame }));
    }

    json!({
        "name": run.scenario.name,
        "description": run.scenario.description,
        "unit": match run.scenario.length_unit {
            mrsim_scenario::LengthUnit::M => "m",
            mrsim_scenario::LengthUnit::Cm => "cm",
            mrsim_scenario::LengthUnit::Mm => "mm",
        },
        "mode": run.scenario.world.mode.to_string(),
        "dt": run.scenario.world.dt,
        "view": {
            "width": MAP_WIDTH, "height": MAP_HEIGHT,
            "scale": view.scale, "ox": view.origin_x, "oy": view.origin_y,
        },
        "strip": { "height": STRIP_HEIGHT },
        "collisionColor": hex(COLLISION),
        "ticks": ticks,
        "times": times,
        "decimation": { "every": every, "ticksRecorded": recorded.len() },
        "walls": walls,
        "robots": robots,
        "obstacles": obstacles,
        "people": people,
        "personColor": hex(crate::PERSON),
        "collisions": collisions,
        "misses": { "frame": miss_frames, "robot": miss_robots },
        "goals": goals,
        "lost": lost,
        "events": listed,
        "encounters": encounters,
        "encountersTotal": run.encounters.len(),
        "eventsTotal": run.events.len(),
        "metrics": run.metrics,
        "cut": run.cut.iter().map(|c| c.to_string()).collect::<Vec<_>>(),
    })
}
