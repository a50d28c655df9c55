//! Reading a finished run's folder: `scenario.json`, `trajectory.csv`,
//! `events.jsonl`, `metrics.json` and, when the run had diagnostics,
//! `diagnostics.csv`.

use crate::RenderError;
use mrsim_scenario::Scenario;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

pub use mrsim_runfolder::{
    DIAGNOSTICS_FILE, EVENTS_FILE, METRICS_FILE, Percentiles, RobotMetrics, SCENARIO_FILE,
    TRAJECTORY_FILE, TRAJECTORY_PARQUET_FILE,
};
use mrsim_scenario::TrajectoryFormat;

/// `metrics.json`, the run folder crate's schema (the name this crate has
/// always used for it).
pub type Metrics = mrsim_runfolder::RunMetrics;

/// What a body in `trajectory.csv` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Driven by an agent.
    Robot,
    /// Moved by the world.
    Obstacle,
}

/// One row of `trajectory.csv` (the body is the track it belongs to).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Tick number.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Position x.
    pub x: f64,
    /// Position y.
    pub y: f64,
    /// Velocity x.
    pub vx: f64,
    /// Velocity y.
    pub vy: f64,
}

impl Sample {
    /// Speed, |v|.
    pub fn speed(&self) -> f64 {
        self.vx.hypot(self.vy)
    }
}

/// Every sample of one body, in tick order.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyTrack {
    /// The body's name (robot or obstacle name from the scenario).
    pub name: String,
    /// Robot or obstacle.
    pub kind: BodyKind,
    /// Samples sorted by tick.
    pub samples: Vec<Sample>,
}

impl BodyTrack {
    /// The sample at `tick`, if the body has one.
    pub fn at(&self, tick: u64) -> Option<&Sample> {
        self.samples
            .binary_search_by_key(&tick, |s| s.tick)
            .ok()
            .map(|i| &self.samples[i])
    }
}

/// `trajectory.csv`, grouped by body.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    /// Every tick that has at least one row, sorted, without repeats.
    pub ticks: Vec<u64>,
    /// Simulated time of each entry of `ticks`.
    pub times: Vec<f64>,
    /// One track per body, in order of first appearance in the file.
    pub bodies: Vec<BodyTrack>,
}

impl Trajectory {
    /// The track of the body called `name`.
    pub fn body(&self, name: &str) -> Option<&BodyTrack> {
        self.bodies.iter().find(|b| b.name == name)
    }
}

/// What happened, from one line of `events.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum EventKind {
    /// Two bodies touched.
    Collision {
        /// One body.
        a: String,
        /// The other body.
        b: String,
        /// Contact point x (absent: the plots use body `a`'s position).
        #[serde(default)]
        x: Option<f64>,
        /// Contact point y.
        #[serde(default)]
        y: Option<f64>,
    },
    /// A robot reached its goal.
    GoalReached {
        /// The robot.
        robot: String,
    },
    /// A robot's command came after the deadline (realtime).
    DeadlineMiss {
        /// The robot.
        robot: String,
        /// How late, µs.
        #[serde(default)]
        late_us: Option<f64>,
    },
    /// A robot's agent stopped answering.
    AgentLost {
        /// The robot.
        robot: String,
        /// Why.
        #[serde(default)]
        reason: String,
    },
    /// A lost agent answered again.
    AgentRejoined {
        /// The robot.
        robot: String,
    },
    /// The world refused a command.
    CommandRejected {
        /// The robot named in the command.
        robot: String,
        /// Why.
        #[serde(default)]
        reason: String,
    },
    /// A type this reader does not know; dropped while loading.
    #[serde(other)]
    Unknown,
}

/// One line of `events.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// Tick it happened in.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
    /// What happened.
    #[serde(flatten)]
    pub kind: EventKind,
}

/// One row of `diagnostics.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnosticSample {
    /// Tick number.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Robot whose planner reported it.
    pub robot: String,
    /// Diagnostic name.
    pub name: String,
    /// Its value.
    pub value: f64,
}

/// Everything in a finished run's folder.
#[derive(Debug, Clone, PartialEq)]
pub struct RunData {
    /// The folder it was read from.
    pub dir: PathBuf,
    /// `scenario.json`.
    pub scenario: Scenario,
    /// `trajectory.csv`.
    pub trajectory: Trajectory,
    /// `events.jsonl`, known types only, in file order.
    pub events: Vec<Event>,
    /// `metrics.json`, `None` if the file is absent (a run cut short).
    pub metrics: Option<Metrics>,
    /// `diagnostics.csv`, `None` if the file is absent or empty. Values may
    /// be `inf`, `-inf` or `NaN` (the plots leave them out).
    pub diagnostics: Option<Vec<DiagnosticSample>>,
    /// `routes.csv`: each routed robot's route, start to goal (empty if
    /// the file is absent).
    pub routes: BTreeMap<String, Vec<[f64; 2]>>,
    /// `encounters.csv`'s rows (empty if the file is absent).
    pub encounters: Vec<mrsim_runfolder::metrics::Encounter>,
}

impl RunData {
    /// Reads a run folder. `scenario.json`, the trajectory its `[output]`
    /// names (`trajectory.csv`, `trajectory.parquet`, or none at all for
    /// `trajectory = "none"`: then [`RunData::trajectory`] is empty) and
    /// `events.jsonl` are required; `metrics.json` and `diagnostics.csv` are
    /// read when present. Errors name the file and, for CSV and JSONL, the
    /// line.
    pub fn load(dir: &Path) -> Result<RunData, RenderError> {
        if !dir.is_dir() {
            return Err(RenderError::NotADirectory {
                path: dir.to_path_buf(),
            });
        }
        let scenario_path = dir.join(SCENARIO_FILE);
        let scenario: Scenario =
            serde_json::from_str(&read_required(&scenario_path)?).map_err(|source| {
                RenderError::Json {
                    path: scenario_path.clone(),
                    source,
                }
            })?;
        let trajectory = match scenario.output.trajectory {
            TrajectoryFormat::Csv => {
                let trajectory_path = dir.join(TRAJECTORY_FILE);
                cut_short(
                    &trajectory_path,
                    &read_required(&trajectory_path)?,
                    parse_trajectory,
                )?
            }
            TrajectoryFormat::Parquet => crate::parquet::load(&dir.join(TRAJECTORY_PARQUET_FILE))?,
            // Nothing was recorded: the pictures show the scene alone.
            TrajectoryFormat::None => Trajectory::default(),
        };
        let events_path = dir.join(EVENTS_FILE);
        let events = cut_short(&events_path, &read_required(&events_path)?, parse_events)?;
        let metrics_path = dir.join(METRICS_FILE);
        let metrics = match read_optional(&metrics_path)? {
            Some(text) => {
                Some(
                    serde_json::from_str(&text).map_err(|source| RenderError::Json {
                        path: metrics_path.clone(),
                        source,
                    })?,
                )
            }
            None => None,
        };
        let diagnostics_path = dir.join(DIAGNOSTICS_FILE);
        let diagnostics = match read_optional(&diagnostics_path)? {
            // An empty file (no header either) means no diagnostics, as no file.
            Some(text) if text.trim().is_empty() => None,
            Some(text) => Some(parse_diagnostics(&diagnostics_path, &text)?),
            None => None,
        };
        let routes_path = dir.join(mrsim_runfolder::ROUTES_FILE);
        let routes = match read_optional(&routes_path)? {
            Some(text) => parse_routes(&routes_path, &text)?,
            None => BTreeMap::new(),
        };
        let encounters_path = dir.join(mrsim_runfolder::ENCOUNTERS_FILE);
        let encounters = read_optional(&encounters_path)?
            .map(|text| mrsim_runfolder::metrics::parse_encounters(&text))
            .unwrap_or_default();
        Ok(RunData {
            dir: dir.to_path_buf(),
            scenario,
            trajectory,
            events,
            metrics,
            diagnostics,
            routes,
            encounters,
        })
    }

    /// Colour index of a robot: its place in the scenario, or after the
    /// scenario's robots in trajectory order for a robot the scenario does
    /// not list.
    pub fn robot_index(&self, name: &str) -> Option<usize> {
        if let Some(i) = self.scenario.robot_index(name) {
            return Some(i);
        }
        self.trajectory
            .bodies
            .iter()
            .filter(|b| b.kind == BodyKind::Robot && self.scenario.robot_index(&b.name).is_none())
            .position(|b| b.name == name)
            .map(|i| self.scenario.robots.len() + i)
    }

    /// The scenario's robot entries by name (one lookup per robot, not a
    /// scan: pictures of 10,000 robots look each one up).
    pub fn specs_by_name(&self) -> HashMap<&str, &mrsim_scenario::RobotSpec> {
        self.scenario
            .robots
            .iter()
            .map(|r| (r.name.as_str(), r))
            .collect()
    }

    /// The recorded tracks by body name.
    pub fn tracks_by_name(&self) -> HashMap<&str, &crate::BodyTrack> {
        self.trajectory
            .bodies
            .iter()
            .map(|b| (b.name.as_str(), b))
            .collect()
    }

    /// Robot names in colour order: the scenario's, then any other robot in
    /// the trajectory.
    pub fn robot_names(&self) -> Vec<String> {
        let listed: std::collections::HashSet<&str> = self
            .scenario
            .robots
            .iter()
            .map(|r| r.name.as_str())
            .collect();
        let mut names: Vec<String> = self
            .scenario
            .robots
            .iter()
            .map(|r| r.name.clone())
            .collect();
        for b in &self.trajectory.bodies {
            if b.kind == BodyKind::Robot && !listed.contains(b.name.as_str()) {
                names.push(b.name.clone());
            }
        }
        names
    }
}

fn read_required(path: &Path) -> Result<String, RenderError> {
    read_optional(path)?.ok_or_else(|| RenderError::Missing {
        path: path.to_path_buf(),
    })
}

fn read_optional(path: &Path) -> Result<Option<String>, RenderError> {
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(RenderError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// A CSV file whose columns are found by the header's names.
struct Csv<'a> {
    path: &'a Path,
    columns: Vec<usize>,
    width: usize,
}

impl<'a> Csv<'a> {
    /// Reads the header (line 1) and finds `wanted` in it.
    fn new(path: &'a Path, header: Option<&str>, wanted: &[&str]) -> Result<Self, RenderError> {
        let header = header.ok_or_else(|| parse_error(path, 1, "empty file: no header".into()))?;
        let names: Vec<&str> = header
            .trim_end_matches('\r')
            .split(',')
            .map(str::trim)
            .collect();
        let mut columns = Vec::with_capacity(wanted.len());
        for w in wanted {
            let i = names.iter().position(|n| n == w).ok_or_else(|| {
                parse_error(
                    path,
                    1,
                    format!("header has no `{w}` column (expected {})", wanted.join(",")),
                )
            })?;
            columns.push(i);
        }
        Ok(Csv {
            path,
            columns,
            width: names.len(),
        })
    }

    /// Splits a data row into the wanted fields, in `wanted` order.
    fn fields<'l>(&self, line_no: usize, line: &'l str) -> Result<Vec<&'l str>, RenderError> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != self.width {
            return Err(parse_error(
                self.path,
                line_no,
                format!("{} fields, the header has {}", cells.len(), self.width),
            ));
        }
        Ok(self.columns.iter().map(|&i| cells[i]).collect())
    }

    fn number(&self, line_no: usize, column: &str, cell: &str) -> Result<f64, RenderError> {
        cell.parse::<f64>().map_err(|_| {
            parse_error(
                self.path,
                line_no,
                format!("column `{column}`: `{cell}` is not a number"),
            )
        })
    }

    fn tick(&self, line_no: usize, cell: &str) -> Result<u64, RenderError> {
        cell.parse::<u64>().map_err(|_| {
            parse_error(
                self.path,
                line_no,
                format!("column `tick`: `{cell}` is not a tick number"),
            )
        })
    }
}

fn parse_error(path: &Path, line: usize, reason: String) -> RenderError {
    RenderError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// Parses `text` with `parse`; if that fails on the last line and the text
/// does not end with a newline, the line was cut by a writer that was
/// killed (the world flushes its files about once a second): it is dropped
/// and the rest parsed.
fn cut_short<T>(
    path: &Path,
    text: &str,
    parse: impl Fn(&Path, &str) -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    match parse(path, text) {
        Err(RenderError::Parse { line, .. })
            if !text.ends_with('\n') && line == text.lines().count() =>
        {
            let whole = text.rfind('\n').map_or("", |i| &text[..=i]);
            parse(path, whole)
        }
        r => r,
    }
}

/// Non-blank lines with their 1-based line numbers, `\r` removed.
fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty())
}

fn parse_trajectory(path: &Path, text: &str) -> Result<Trajectory, RenderError> {
    const COLUMNS: [&str; 8] = ["tick", "time", "body", "kind", "x", "y", "vx", "vy"];
    let mut lines = numbered_lines(text);
    let csv = Csv::new(path, lines.next().map(|(_, l)| l), &COLUMNS)?;
    let mut tracks = Tracks::default();
    for (line_no, line) in lines {
        let f = csv.fields(line_no, line)?;
        let tick = csv.tick(line_no, f[0])?;
        let time = csv.number(line_no, "time", f[1])?;
        let mut v = [0.0; 4];
        for (k, col) in ["x", "y", "vx", "vy"].iter().enumerate() {
            v[k] = csv.number(line_no, col, f[4 + k])?;
        }
        let sample = Sample {
            tick,
            time,
            x: v[0],
            y: v[1],
            vx: v[2],
            vy: v[3],
        };
        tracks
            .push(f[2], f[3], sample)
            .map_err(|reason| parse_error(path, line_no, reason))?;
    }
    Ok(tracks.finish())
}

/// A trajectory's rows grouped into tracks, whatever file they come from.
#[derive(Default)]
pub(crate) struct Tracks {
    bodies: Vec<BodyTrack>,
    index: HashMap<String, usize>,
    tick_times: BTreeMap<u64, f64>,
}

impl Tracks {
    /// Adds one row; the error says what is wrong with it.
    pub(crate) fn push(&mut self, name: &str, kind: &str, sample: Sample) -> Result<(), String> {
        if name.is_empty() {
            return Err("column `body` is empty".into());
        }
        let kind = match kind {
            "robot" => BodyKind::Robot,
            "obstacle" => BodyKind::Obstacle,
            other => {
                return Err(format!(
                    "column `kind`: `{other}` is neither robot nor obstacle"
                ));
            }
        };
        let i = match self.index.get(name) {
            Some(&i) => i,
            None => {
                self.index.insert(name.to_string(), self.bodies.len());
                self.bodies.push(BodyTrack {
                    name: name.to_string(),
                    kind,
                    samples: Vec::new(),
                });
                self.bodies.len() - 1
            }
        };
        if self.bodies[i].kind != kind {
            return Err(format!(
                "body `{name}` was a {:?} on an earlier line",
                self.bodies[i].kind
            )
            .to_lowercase());
        }
        self.tick_times.entry(sample.tick).or_insert(sample.time);
        self.bodies[i].samples.push(sample);
        Ok(())
    }

    /// The tracks, each sorted by tick without repeats.
    pub(crate) fn finish(mut self) -> Trajectory {
        for b in &mut self.bodies {
            b.samples.sort_by_key(|s| s.tick);
            b.samples.dedup_by_key(|s| s.tick);
        }
        Trajectory {
            ticks: self.tick_times.keys().copied().collect(),
            times: self.tick_times.values().copied().collect(),
            bodies: self.bodies,
        }
    }
}

fn parse_events(path: &Path, text: &str) -> Result<Vec<Event>, RenderError> {
    let mut events = Vec::new();
    for (line_no, line) in numbered_lines(text) {
        let event: Event =
            serde_json::from_str(line).map_err(|e| parse_error(path, line_no, e.to_string()))?;
        if event.kind != EventKind::Unknown {
            events.push(event);
        }
    }
    Ok(events)
}

fn parse_diagnostics(path: &Path, text: &str) -> Result<Vec<DiagnosticSample>, RenderError> {
    const COLUMNS: [&str; 5] = ["tick", "time", "robot", "name", "value"];
    let mut lines = numbered_lines(text);
    let csv = Csv::new(path, lines.next().map(|(_, l)| l), &COLUMNS)?;
    let mut out = Vec::new();
    for (line_no, line) in lines {
        let f = csv.fields(line_no, line)?;
        out.push(DiagnosticSample {
            tick: csv.tick(line_no, f[0])?,
            time: csv.number(line_no, "time", f[1])?,
            robot: f[2].to_string(),
            name: f[3].to_string(),
            value: csv.number(line_no, "value", f[4])?,
        });
    }
    Ok(out)
}

impl RunData {
    /// `[xmin, xmax, ymin, ymax]` of the smallest box holding the arena,
    /// the walls, every robot's start and goal and every sample, grown by
    /// the largest body radius and 2% of its larger side. Never empty: a
    /// side of zero length becomes one length unit.
    pub fn extent(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut add = |x: f64, y: f64| {
            if x.is_finite() && y.is_finite() {
                b[0] = b[0].min(x);
                b[1] = b[1].max(x);
                b[2] = b[2].min(y);
                b[3] = b[3].max(y);
            }
        };
        for w in self.scenario.all_walls() {
            add(w[0][0], w[0][1]);
            add(w[1][0], w[1][1]);
        }
        for r in &self.scenario.robots {
            add(r.start[0], r.start[1]);
            add(r.goal[0], r.goal[1]);
        }
        for o in &self.scenario.obstacles {
            add(o.start[0], o.start[1]);
        }
        for body in &self.trajectory.bodies {
            for s in &body.samples {
                add(s.x, s.y);
            }
        }
        if !b[0].is_finite() {
            b = [-1.0, 1.0, -1.0, 1.0];
        }
        let radius = self
            .scenario
            .robots
            .iter()
            .map(|r| r.radius)
            .chain(self.scenario.obstacles.iter().map(|o| o.radius))
            .filter(|r| r.is_finite())
            .fold(0.0, f64::max);
        let pad = radius + 0.02 * (b[1] - b[0]).max(b[3] - b[2]);
        b = [b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad];
        for k in [0, 2] {
            if b[k + 1] - b[k] <= 0.0 {
                b[k] -= 0.5;
                b[k + 1] += 0.5;
            }
        }
        b
    }

    /// Radius of a body by name, from the scenario (0 if it is not there).
    pub fn radius_of(&self, name: &str) -> f64 {
        self.scenario
            .robots
            .iter()
            .find(|r| r.name == name)
            .map(|r| r.radius)
            .or_else(|| {
                self.scenario
                    .obstacles
                    .iter()
                    .find(|o| o.name == name)
                    .map(|o| o.radius)
            })
            .unwrap_or(0.0)
    }

    /// Where a collision is drawn: its contact point, or else body `a`'s
    /// position at that tick.
    pub fn collision_point(&self, event: &Event) -> Option<[f64; 2]> {
        match &event.kind {
            EventKind::Collision {
                x: Some(x),
                y: Some(y),
                ..
            } => Some([*x, *y]),
            EventKind::Collision { a, .. } => self
                .trajectory
                .body(a)
                .and_then(|t| t.at(event.tick))
                .map(|s| [s.x, s.y]),
            _ => None,
        }
    }
}

/// routes.csv (`robot,seq,x,y`): the points of each robot's route, in
/// file order.
fn parse_routes(path: &Path, text: &str) -> Result<BTreeMap<String, Vec<[f64; 2]>>, RenderError> {
    let mut out: BTreeMap<String, Vec<[f64; 2]>> = BTreeMap::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |reason: &str| RenderError::Parse {
            path: path.to_path_buf(),
            line: n + 1,
            reason: reason.to_string(),
        };
        let cols: Vec<&str> = line.rsplitn(4, ',').collect();
        let [y, x, _seq, robot] = cols[..] else {
            return Err(bad("expected robot,seq,x,y"));
        };
        let num = |v: &str| {
            v.trim()
                .parse::<f64>()
                .map_err(|_| bad("x and y must be numbers"))
        };
        out.entry(robot.to_string())
            .or_default()
            .push([num(x)?, num(y)?]);
    }
    Ok(out)
}
