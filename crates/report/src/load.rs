//! Reading a run's folder: `scenario.json`, the trajectory
//! (`trajectory.csv` or `trajectory.parquet`, read with the run folder
//! crate's readers), `events.jsonl`, `metrics.json`, `diagnostics.csv`,
//! `encounters.csv` and `routes.csv`, each error naming the file and, where
//! there is one, the line. A run that was cut (its world killed) is read up
//! to the cut: a torn last row is left out, a Parquet trajectory without
//! its footer is read from its journal, and [`RunData::cut`] says so.

use crate::RenderError;
use crate::records::{BodyKind, BodyTrack, DiagnosticSample, Event, EventKind, Sample, Trajectory};
use crate::run::RunData;
use mrsim_runfolder::csv::{Columns, CsvError, numbered_lines, trajectory_rows};
use mrsim_runfolder::stream::{Cut, read_whole_rows};
use mrsim_runfolder::trajectory::{TrajectoryError, TrajectoryRow, read_parquet_trajectory};
use mrsim_runfolder::{
    DIAGNOSTICS_FILE, EVENTS_FILE, METRICS_FILE, ROUTES_FILE, RowsError, SCENARIO_FILE,
    TRAJECTORY_FILE, TRAJECTORY_JOURNAL_FILE, TRAJECTORY_PARQUET_FILE,
};
use mrsim_scenario::{Scenario, TrajectoryFormat};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

impl RunData {
    /// Reads a run folder. `scenario.json`, the trajectory its `[output]`
    /// names (`trajectory.csv`, `trajectory.parquet`, or none at all for
    /// `trajectory = "none"`: then [`RunData::trajectory`] is empty) and
    /// `events.jsonl` are required; `metrics.json` and `diagnostics.csv` are
    /// read when present. Errors name the file and, for CSV and JSONL, the
    /// line; a torn last row (a cut run) is left out and named in
    /// [`RunData::cut`].
    pub fn load(dir: &Path) -> Result<RunData, RenderError> {
        if !dir.is_dir() {
            return Err(RenderError::NotADirectory {
                path: dir.to_path_buf(),
            });
        }
        let scenario_path = dir.join(SCENARIO_FILE);
        let scenario: Scenario =
            serde_json::from_str(&read_json_text(&scenario_path)?.ok_or_else(|| {
                RenderError::Missing {
                    path: scenario_path.clone(),
                }
            })?)
            .map_err(|source| RenderError::Json {
                path: scenario_path.clone(),
                source,
            })?;
        let mut cut = Vec::new();
        let trajectory = match scenario.output.trajectory {
            TrajectoryFormat::Csv => {
                let trajectory_path = dir.join(TRAJECTORY_FILE);
                let text = read_required(&trajectory_path, &mut cut)?;
                parse_trajectory(&trajectory_path, &text)?
            }
            TrajectoryFormat::Parquet => load_parquet(dir, &mut cut)?,
            // Nothing was recorded: the pictures show the scene alone.
            TrajectoryFormat::None => Trajectory::default(),
        };
        let events_path = dir.join(EVENTS_FILE);
        let events = parse_events(&events_path, &read_required(&events_path, &mut cut)?)?;
        let metrics_path = dir.join(METRICS_FILE);
        let metrics = match read_json_text(&metrics_path)? {
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
        let diagnostics = match read_optional(&diagnostics_path, &mut cut)? {
            // An empty file (no header either) means no diagnostics, as no file.
            Some(text) if text.trim().is_empty() => None,
            Some(text) => Some(parse_diagnostics(&diagnostics_path, &text)?),
            None => None,
        };
        let routes_path = dir.join(ROUTES_FILE);
        let routes = match read_json_text(&routes_path)? {
            Some(text) => parse_routes(&routes_path, &text)?,
            None => BTreeMap::new(),
        };
        let (encounters, torn) =
            mrsim_runfolder::encounters::read_encounters(dir).map_err(file_error)?;
        cut.extend(torn);
        Ok(RunData {
            dir: dir.to_path_buf(),
            scenario,
            trajectory,
            events,
            metrics,
            diagnostics,
            routes,
            encounters,
            cut,
        })
    }
}

/// A run folder reader's error as the report's.
pub(crate) fn file_error(e: RowsError) -> RenderError {
    match e {
        RowsError::Io { path, source } => RenderError::Io { path, source },
        RowsError::Row { path, line, reason } => RenderError::Parse { path, line, reason },
    }
}

/// The text of a file written whole at the end of a run (a JSON file,
/// routes.csv), `None` if there is none.
fn read_json_text(path: &Path) -> Result<Option<String>, RenderError> {
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(RenderError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// The whole rows of the file at `path`, which must exist; a torn last row
/// is left out and added to `cut`.
fn read_required(path: &Path, cut: &mut Vec<Cut>) -> Result<String, RenderError> {
    read_optional(path, cut)?.ok_or_else(|| RenderError::Missing {
        path: path.to_path_buf(),
    })
}

/// The whole rows of the file at `path`, `None` if there is none; a torn
/// last row is left out and added to `cut`.
pub(crate) fn read_optional(
    path: &Path,
    cut: &mut Vec<Cut>,
) -> Result<Option<String>, RenderError> {
    match read_whole_rows(path) {
        Ok(Some((text, torn))) => {
            cut.extend(torn);
            Ok(Some(text))
        }
        Ok(None) => Ok(None),
        Err(source) => Err(RenderError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// A malformed line of the file at `path`.
fn parse_error(path: &Path, e: CsvError) -> RenderError {
    RenderError::Parse {
        path: path.to_path_buf(),
        line: e.line,
        reason: e.reason,
    }
}

fn parse_trajectory(path: &Path, text: &str) -> Result<Trajectory, RenderError> {
    let mut tracks = Tracks::default();
    for row in trajectory_rows(text).map_err(|e| parse_error(path, e))? {
        let (line_no, row) = row.map_err(|e| parse_error(path, e))?;
        tracks.push_row(&row).map_err(|reason| {
            parse_error(
                path,
                CsvError {
                    line: line_no,
                    reason,
                },
            )
        })?;
    }
    Ok(tracks.finish())
}

/// Reads `dir`'s Parquet trajectory, or, if the run was cut before its
/// footer was written, its journal (noted in `cut`).
fn load_parquet(dir: &Path, cut: &mut Vec<Cut>) -> Result<Trajectory, RenderError> {
    let path = &dir.join(TRAJECTORY_PARQUET_FILE);
    let journal = dir.join(TRAJECTORY_JOURNAL_FILE);
    if !path.exists() {
        return Err(RenderError::Missing {
            path: path.to_path_buf(),
        });
    }
    let table = match read_parquet_trajectory(path) {
        Ok(table) => table,
        Err(TrajectoryError::Parquet { .. }) if journal.exists() => {
            let mut torn = Vec::new();
            let text = read_required(&journal, &mut torn)?;
            cut.push(Cut {
                path: path.to_path_buf(),
                line: 0,
                detail: format!(
                    "no Parquet footer; read its journal {TRAJECTORY_JOURNAL_FILE}{}",
                    torn.first().map_or(String::new(), |c| format!(" ({c})"))
                ),
            });
            return parse_trajectory(&journal, &text);
        }
        Err(TrajectoryError::Io { path, source }) => return Err(RenderError::Io { path, source }),
        Err(other) => return Err(RenderError::Parquet(other)),
    };
    let mut tracks = Tracks::default();
    for (i, row) in table.rows().enumerate() {
        tracks.push_row(&row).map_err(|reason| RenderError::Parse {
            path: path.to_path_buf(),
            line: i + 1,
            reason,
        })?;
    }
    Ok(tracks.finish())
}

/// A trajectory's rows grouped into tracks, whatever file they come from.
#[derive(Default)]
struct Tracks {
    bodies: Vec<BodyTrack>,
    index: HashMap<String, usize>,
    tick_times: BTreeMap<u64, f64>,
}

impl Tracks {
    /// Adds one row; the error says what is wrong with it.
    fn push(&mut self, name: &str, kind: &str, sample: Sample) -> Result<(), String> {
        if name.is_empty() {
            return Err("column `body` is empty".into());
        }
        let kind = match kind {
            "robot" => BodyKind::Robot,
            "obstacle" => BodyKind::Obstacle,
            "person" => BodyKind::Person,
            other => {
                return Err(format!(
                    "column `kind`: `{other}` is none of robot, obstacle, person"
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

    /// Adds a row read from either file.
    fn push_row(&mut self, row: &TrajectoryRow) -> Result<(), String> {
        let sample = Sample {
            tick: row.tick,
            time: row.time,
            x: row.x,
            y: row.y,
            vx: row.vx,
            vy: row.vy,
            theta: row.theta,
        };
        self.push(row.body, row.kind, sample)
    }

    /// The tracks, each sorted by tick without repeats.
    fn finish(mut self) -> Trajectory {
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
        let event: Event = serde_json::from_str(line).map_err(|e| {
            parse_error(
                path,
                CsvError {
                    line: line_no,
                    reason: e.to_string(),
                },
            )
        })?;
        if event.kind != EventKind::Unknown {
            events.push(event);
        }
    }
    Ok(events)
}

fn parse_diagnostics(path: &Path, text: &str) -> Result<Vec<DiagnosticSample>, RenderError> {
    const COLUMNS: [&str; 5] = ["tick", "time", "robot", "name", "value"];
    let mut lines = numbered_lines(text);
    let csv =
        Columns::new(lines.next().map(|(_, l)| l), &COLUMNS).map_err(|e| parse_error(path, e))?;
    let row = |line_no: usize, line: &str| -> Result<DiagnosticSample, CsvError> {
        let f = csv.fields(line_no, line)?;
        Ok(DiagnosticSample {
            tick: csv.tick(line_no, f[0])?,
            time: csv.number(line_no, "time", f[1])?,
            robot: f[2].to_string(),
            name: f[3].to_string(),
            value: csv.number(line_no, "value", f[4])?,
        })
    };
    lines
        .map(|(line_no, line)| row(line_no, line).map_err(|e| parse_error(path, e)))
        .collect()
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
