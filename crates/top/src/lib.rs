//! `mrsim top`: a live terminal dashboard of a running world.
//!
//! It attaches as a read-only observer ([`ObserverTransport`]): it reads the
//! run's setup (robot names, planners, walls), the newest snapshot (where
//! every body is) and the world's live statistics (each agent's state,
//! latency p50/p99, deadline misses, collisions), and never joins, sends
//! or wakes the world. It redraws about 8 times a second and ends on `q`,
//! Esc or Ctrl-C, or when the run finishes.
//!
//! [`TopModel`] holds what is known about the run and [`draw`] renders it
//! on any ratatui backend, so the screen can be tested without a terminal.
#![warn(missing_docs)]

use mrsim_proto::{
    BodyState, RobotStats, SnapshotHeader, StatsHeader, agent_state, body_kind, run_phase,
};
use mrsim_scenario::Scenario;
use mrsim_transport::shm::ShmObserver;
use mrsim_transport::zenoh::{ZenohObserver, ZenohOptions};
use mrsim_transport::{Namespace, ObserverTransport, TransportError};
use ratatui::Frame;
use ratatui::layout::{Constraint, Direction, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Circle, Line as Segment, Points};
use ratatui::widgets::{Block, Borders, Paragraph};
use table::table_width;
pub use table::{Order, TableView, summary_lines, worst_first};

mod table;
use std::time::{Duration, Instant};

/// Why the dashboard cannot follow a run.
#[derive(Debug, thiserror::Error)]
pub enum TopError {
    /// The world's setup message is not JSON.
    #[error("the world's setup is not JSON")]
    SetupNotJson(#[source] serde_json::Error),
    /// The world's setup holds no scenario this program can read.
    #[error("the world's setup has no readable scenario")]
    SetupScenario(#[source] serde_json::Error),
    /// No world runs with this run id (or it cannot be reached).
    #[error(
        "no world is running with run id `{run_id}` (start one with `mrsim world --run {run_id}` or `mrsim run --run {run_id}`): {cause}"
    )]
    NoWorld {
        /// The run id.
        run_id: String,
        /// Why it was not reached (in the message).
        cause: TransportError,
    },
    /// Reading from the world failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The world published no setup in time.
    #[error("the world did not publish its setup within {0:.0} s")]
    NoSetup(f64),
    /// The world ended before its setup arrived.
    #[error("the world is gone")]
    WorldGone,
}

/// Time between two screen updates.
pub const REFRESH: Duration = Duration::from_millis(125);

/// Everything `top` knows about a run: the setup, and the newest snapshot
/// and statistics.
#[derive(Debug, Clone)]
pub struct TopModel {
    /// The run id.
    pub run_id: String,
    /// The run's output folder, as the world reported it.
    pub out_dir: String,
    /// The resolved scenario.
    pub scenario: Scenario,
    /// Newest snapshot header (default until the first tick).
    pub snapshot: SnapshotHeader,
    /// Newest snapshot's bodies (empty until the first tick).
    pub bodies: Vec<BodyState>,
    /// Newest statistics header, if any arrived.
    pub stats: Option<StatsHeader>,
    /// Newest statistics, one per robot.
    pub robots: Vec<RobotStats>,
    bounds: [[f64; 2]; 2],
    /// Every body's shape by body id (robots, then obstacles).
    shapes: Vec<mrsim_shape::Shape>,
}

impl TopModel {
    /// A model from the world's setup message (JSON with `run_id`,
    /// `out_dir` and `scenario`).
    pub fn from_setup(setup: &[u8]) -> Result<Self, TopError> {
        let v: serde_json::Value = serde_json::from_slice(setup).map_err(TopError::SetupNotJson)?;
        let scenario: Scenario =
            serde_json::from_value(v["scenario"].clone()).map_err(TopError::SetupScenario)?;
        let mut points: Vec<[f64; 2]> = Vec::new();
        if let Some(a) = &scenario.world.arena {
            points.extend([a.min, a.max]);
        } else {
            for r in &scenario.robots {
                points.extend([r.start, r.goal]);
            }
            points.extend(scenario.obstacles.iter().map(|o| o.start));
            for w in &scenario.walls {
                points.extend(w.segment);
            }
        }
        let mut bounds = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        for p in &points {
            grow(&mut bounds, *p, 0.0);
        }
        if !bounds[0][0].is_finite() {
            bounds = [[-1.0, -1.0], [1.0, 1.0]];
        }
        // A margin of a tenth of the extent (at least one unit).
        let margin =
            ((bounds[1][0] - bounds[0][0]).max(bounds[1][1] - bounds[0][1]) * 0.1).max(1.0);
        let bounds = [
            [bounds[0][0] - margin, bounds[0][1] - margin],
            [bounds[1][0] + margin, bounds[1][1] + margin],
        ];
        Ok(Self {
            run_id: v["run_id"].as_str().unwrap_or("").to_string(),
            out_dir: v["out_dir"].as_str().unwrap_or("").to_string(),
            shapes: scenario.body_shapes(),
            scenario,
            snapshot: SnapshotHeader::default(),
            bodies: Vec::new(),
            stats: None,
            robots: Vec::new(),
            bounds,
        })
    }

    /// Takes in the newest snapshot and statistics, if any arrived.
    pub fn poll(&mut self, obs: &mut dyn ObserverTransport) -> Result<(), TransportError> {
        let mut header = SnapshotHeader::default();
        if obs.latest_snapshot(&mut header, &mut self.bodies)? {
            self.snapshot = header;
            for b in &self.bodies {
                let r = b.radius.max(0.0);
                grow(&mut self.bounds, b.position, r);
            }
        }
        let mut stats = StatsHeader::default();
        if obs.latest_stats(&mut stats, &mut self.robots)? {
            self.stats = Some(stats);
        }
        Ok(())
    }

    /// True once the world has said the run is over.
    pub fn finished(&self) -> bool {
        self.snapshot.finished == 1 || self.stats.is_some_and(|s| s.phase == run_phase::FINISHED)
    }

    /// Newest tick the world reported.
    pub fn tick(&self) -> u64 {
        self.stats
            .map_or(self.snapshot.tick, |s| s.tick.max(self.snapshot.tick))
    }

    /// A robot's state as shown: `waiting`, `live`, `lost`, `at goal`, or
    /// `?` before the first statistics.
    pub fn state_of(&self, robot: usize) -> &'static str {
        match self.robots.get(robot) {
            None => "?",
            Some(r) if r.state == agent_state::LOST => "lost",
            Some(r) if r.reached_goal == 1 => "at goal",
            Some(r) if r.state == agent_state::LIVE => "live",
            Some(_) => "waiting",
        }
    }

    /// One line for the end: where the run got to.
    pub fn summary(&self) -> String {
        let n = self.scenario.robots.len();
        let at_goal = self.robots.iter().filter(|r| r.reached_goal == 1).count();
        let collisions = self.stats.map_or(0, |s| s.collisions_total);
        format!(
            "run `{}` finished at tick {}: {at_goal}/{n} robots at goal, {collisions} collisions; outputs in {}",
            self.run_id,
            self.tick(),
            self.out_dir
        )
    }

    /// The map's bounds, widened so one unit is as long across as up
    /// (a terminal cell is about twice as tall as wide).
    fn map_bounds(&self, area: Rect) -> ([f64; 2], [f64; 2]) {
        let [lo, hi] = self.bounds;
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let cols = f64::from(area.width.saturating_sub(2).max(1));
        let rows = f64::from(area.height.saturating_sub(2).max(1)) * 2.0;
        let scale = (w / cols).max(h / rows);
        let (cx, cy) = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0);
        let (hw, hh) = (scale * cols / 2.0, scale * rows / 2.0);
        ([cx - hw, cx + hw], [cy - hh, cy + hh])
    }
}

fn grow(b: &mut [[f64; 2]; 2], p: [f64; 2], r: f64) {
    if !(p[0].is_finite() && p[1].is_finite()) {
        return;
    }
    b[0][0] = b[0][0].min(p[0] - r);
    b[0][1] = b[0][1].min(p[1] - r);
    b[1][0] = b[1][0].max(p[0] + r);
    b[1][1] = b[1][1].max(p[1] + r);
}

fn robot_color(i: usize) -> Color {
    let [r, g, b] = mrsim_report::robot_color(i);
    Color::Rgb(r, g, b)
}

fn micros(us: f64, commands: u64) -> String {
    if commands == 0 {
        "-".to_string()
    } else if us >= 100.0 {
        format!("{us:.0}")
    } else {
        format!("{us:.1}")
    }
}

fn status_line(m: &TopModel) -> Line<'static> {
    let n = m.scenario.robots.len();
    let mode = m.scenario.world.mode.to_string();
    let what = match m.stats {
        None => "waiting for the world's statistics".to_string(),
        Some(s) if s.phase == run_phase::JOINING => {
            let joined = m
                .robots
                .iter()
                .filter(|r| r.state != agent_state::WAITING)
                .count();
            format!("waiting for agents: {joined}/{n} joined")
        }
        Some(s) => {
            let at_goal = m.robots.iter().filter(|r| r.reached_goal == 1).count();
            let state = if s.phase == run_phase::FINISHED || m.finished() {
                "finished"
            } else {
                "running"
            };
            format!(
                "{state}  tick {}/{}  t {:.2} s  x{:.2}  {at_goal}/{n} at goal  {} collisions  {} lost",
                m.tick(),
                s.max_ticks,
                s.sim_time.max(m.snapshot.sim_time),
                s.realtime_factor,
                s.collisions_total,
                s.agents_lost
            )
        }
    };
    Line::from(vec![
        Span::styled(
            format!(" mrsim top  {} · {} · {mode}  ", m.run_id, m.scenario.name),
            Style::default().add_modifier(Modifier::BOLD),
        ),
        Span::raw(what),
    ])
}

fn draw_map(f: &mut Frame, area: Rect, m: &TopModel) {
    let (xb, yb) = m.map_bounds(area);
    let n = m.scenario.robots.len();
    let label_names = n <= 16;
    let canvas =
        Canvas::default()
            .block(Block::default().borders(Borders::ALL).title(" map "))
            .marker(Marker::Braille)
            .x_bounds(xb)
            .y_bounds(yb)
            .paint(|ctx| {
                let grey = Color::Gray;
                if let Some(a) = &m.scenario.world.arena {
                    let (lo, hi) = (a.min, a.max);
                    for (p, q) in [
                        (lo, [hi[0], lo[1]]),
                        ([hi[0], lo[1]], hi),
                        (hi, [lo[0], hi[1]]),
                        ([lo[0], hi[1]], lo),
                    ] {
                        ctx.draw(&Segment::new(p[0], p[1], q[0], q[1], grey));
                    }
                }
                for w in &m.scenario.walls {
                    let [p, q] = w.segment;
                    ctx.draw(&Segment::new(p[0], p[1], q[0], q[1], grey));
                }
                // Goals as small crosses in the robot's colour.
                let s = (xb[1] - xb[0]) / 120.0;
                for (i, r) in m.scenario.robots.iter().enumerate() {
                    let [gx, gy] = r.goal;
                    let c = robot_color(i);
                    ctx.draw(&Segment::new(gx - s, gy - s, gx + s, gy + s, c));
                    ctx.draw(&Segment::new(gx - s, gy + s, gx + s, gy - s, c));
                }
                ctx.layer();
                // Bodies: where the newest snapshot has them, else where they start.
                let starts: Vec<BodyState> =
                    if m.bodies.is_empty() {
                        m.scenario
                            .robots
                            .iter()
                            .enumerate()
                            .map(|(i, r)| BodyState {
                                id: i as u32,
                                kind: body_kind::ROBOT,
                                position: r.start,
                                radius: r.radius,
                                heading: r.start_heading(),
                                ..Default::default()
                            })
                            .chain(m.scenario.obstacles.iter().enumerate().map(|(k, o)| {
                                BodyState {
                                    id: (n + k) as u32,
                                    kind: body_kind::OBSTACLE,
                                    position: o.start,
                                    radius: o.radius,
                                    heading: o.heading,
                                    ..Default::default()
                                }
                            }))
                            .chain(
                                m.scenario
                                    .people
                                    .iter()
                                    .enumerate()
                                    .map(|(k, p)| BodyState {
                                        id: (n + m.scenario.obstacles.len() + k) as u32,
                                        kind: body_kind::PERSON,
                                        position: p.start,
                                        radius: p.radius,
                                        ..Default::default()
                                    }),
                            )
                            .collect()
                    } else {
                        Vec::new()
                    };
                let bodies = if m.bodies.is_empty() {
                    &starts
                } else {
                    &m.bodies
                };
                for b in bodies {
                    let color = if b.kind == body_kind::ROBOT {
                        robot_color(b.id as usize)
                    } else {
                        Color::DarkGray
                    };
                    let [x, y] = b.position;
                    let pose = mrsim_shape::Pose::new(b.position, b.heading);
                    let polygon = m.shapes.get(b.id as usize).and_then(|sh| sh.placed(pose));
                    match polygon {
                        // A polygon's outline, turned by the body's heading.
                        Some(poly) if b.radius > s => {
                            let pts = poly.points();
                            for (k, p) in pts.iter().enumerate() {
                                let q = pts[(k + 1) % pts.len()];
                                ctx.draw(&Segment::new(p[0], p[1], q[0], q[1], color));
                            }
                        }
                        Some(_) => {}
                        None if b.radius > s => ctx.draw(&Circle::new(x, y, b.radius, color)),
                        None => {}
                    }
                    ctx.draw(&Points::new(&[(x, y)], color));
                }
                if label_names {
                    ctx.layer();
                    for b in bodies.iter().filter(|b| b.kind == body_kind::ROBOT) {
                        if let Some(r) = m.scenario.robots.get(b.id as usize) {
                            let [x, y] = b.position;
                            ctx.print(
                                x + s * 2.0,
                                y,
                                Span::styled(r.name.clone(), Style::default().fg(color_of(b))),
                            );
                        }
                    }
                }
            });
    f.render_widget(canvas, area);
}

fn color_of(b: &BodyState) -> Color {
    robot_color(b.id as usize)
}

/// Draws the dashboard with the table at its start: a status line, the map,
/// the robots' table, and the keys. Side by side on a wide screen, map above
/// table on a narrow one.
pub fn draw(f: &mut Frame, m: &TopModel) {
    draw_with(f, m, &TableView::default());
}

/// [`draw`] with the table scrolled and ordered as `view` says.
pub fn draw_with(f: &mut Frame, m: &TopModel, view: &TableView) {
    let [status, body, keys] = Layout::default()
        .direction(Direction::Vertical)
        .constraints([
            Constraint::Length(1),
            Constraint::Min(4),
            Constraint::Length(1),
        ])
        .areas(f.area());
    f.render_widget(Paragraph::new(status_line(m)), status);
    let table_width = table_width(m);
    let [map, table] = if body.width >= table_width + 30 {
        Layout::default()
            .direction(Direction::Horizontal)
            .constraints([Constraint::Min(30), Constraint::Length(table_width)])
            .areas(body)
    } else {
        let rows = (m.scenario.robots.len() as u16 + 6).min(body.height / 2);
        Layout::default()
            .direction(Direction::Vertical)
            .constraints([Constraint::Min(4), Constraint::Length(rows)])
            .areas(body)
    };
    draw_map(f, map, m);
    table::draw_table(f, table, m, view);
    f.render_widget(
        Paragraph::new(Line::from(Span::styled(
            " q quit   PgUp/PgDn/↑/↓/Home/End scroll   s order   latency: snapshot published -> command received at the world",
            Style::default().fg(Color::DarkGray),
        ))),
        keys,
    );
}

/// Waits until the world's setup arrives over `obs`.
pub fn wait_for_setup(
    obs: &mut dyn ObserverTransport,
    timeout: Duration,
) -> Result<TopModel, TopError> {
    let start = Instant::now();
    loop {
        if let Some(setup) = obs.setup()? {
            return TopModel::from_setup(&setup);
        }
        if start.elapsed() >= timeout {
            return Err(TopError::NoSetup(timeout.as_secs_f64()));
        }
        if !obs.world_alive() {
            return Err(TopError::WorldGone);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A read-only observer of run `ns` (snapshots included) over iceoryx2, or
/// over Zenoh with `zenoh`, for the watcher `who` (`top`, `view`); waits
/// up to `timeout` for the world.
pub fn connect_observer(
    ns: &Namespace,
    who: &str,
    zenoh: Option<&ZenohOptions>,
    timeout: Duration,
) -> Result<Box<dyn ObserverTransport>, TopError> {
    let node = format!("mrsim-{who}-{}", std::process::id());
    let obs: Result<Box<dyn ObserverTransport>, _> = match zenoh {
        None => ShmObserver::connect(ns, &node, true, timeout).map(|o| Box::new(o) as _),
        Some(z) => ZenohObserver::connect(ns, z, true, timeout).map(|o| Box::new(o) as _),
    };
    let run_id = ns.run_id();
    obs.map_err(|cause| TopError::NoWorld {
        run_id: run_id.to_string(),
        cause,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;

    /// The rows and columns spanned by the cells drawn in dark grey (the
    /// obstacles) on a 100 x 50 screen of a run with one small robot and a
    /// rectangle obstacle 8 x 0.4 turned by `heading_deg`.
    fn obstacle_span(heading_deg: f64) -> (u16, u16) {
        let src = format!(
            "[world]\narena = {{ min = [-6.0, -6.0], max = [6.0, 6.0] }}\n\
             [[robot]]\nname = \"r\"\nstart = [-5.0, -5.0]\ngoal = [-5.0, -4.0]\n\
             [[obstacle]]\nname = \"board\"\nstart = [0.0, 0.0]\nheading_deg = {heading_deg}\n\
             shape = {{ kind = \"rectangle\", length = 8.0, width = 0.4 }}\n"
        );
        let loaded = mrsim_scenario::parse(&src, "board.toml").expect("scenario");
        let setup =
            serde_json::json!({"run_id": "t", "out_dir": "/tmp", "scenario": loaded.scenario});
        let m = TopModel::from_setup(setup.to_string().as_bytes()).expect("setup");
        let mut t = Terminal::new(TestBackend::new(100, 50)).expect("terminal");
        t.draw(|f| draw(f, &m)).expect("draw");
        let buf = t.backend().buffer();
        let (mut rows, mut cols) = ((u16::MAX, 0), (u16::MAX, 0));
        for y in 0..buf.area.height {
            for x in 0..buf.area.width {
                let cell = &buf[(x, y)];
                // Braille dots (the map's marker), not text.
                let dots = cell
                    .symbol()
                    .chars()
                    .any(|c| ('\u{2801}'..='\u{28ff}').contains(&c));
                if cell.fg == Color::DarkGray && dots {
                    rows = (rows.0.min(y), rows.1.max(y));
                    cols = (cols.0.min(x), cols.1.max(x));
                }
            }
        }
        assert!(rows.0 <= rows.1, "nothing drawn in dark grey");
        (rows.1 - rows.0 + 1, cols.1 - cols.0 + 1)
    }

    #[test]
    fn a_rectangle_obstacle_is_drawn_as_its_outline_turned_by_its_heading() {
        // A terminal cell is about twice as tall as wide: the map gives a
        // row two columns' worth of length. Its circumscribed disc would
        // span as many columns as twice its rows.
        let (rows, cols) = obstacle_span(90.0);
        assert!(2 * rows > 4 * cols, "upright: {rows} rows x {cols} columns");
        let (rows, cols) = obstacle_span(0.0);
        assert!(cols > 4 * 2 * rows, "lying: {rows} rows x {cols} columns");
    }
}
