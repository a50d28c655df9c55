//! The live page: a run shown in a browser while it ticks.
//!
//! Three parts, so that one page serves a run in this process (`mrsim run
//! --live`) and any run elsewhere (`mrsim view --run ID`, over iceoryx2 or
//! Zenoh):
//! - [`Feed`]: the newest frame of a run (bodies, statistics, scans) and
//!   its setup, shared between the one that fills it and the server;
//! - [`Pump`]: fills a feed from any [`ObserverTransport`], the read-only
//!   view that `mrsim top` uses: it never joins, sends or wakes the world,
//!   and the transport drops what an observer does not take in time, so a
//!   slow page can never slow the run;
//! - [`LiveServer`]: a small synchronous HTTP server (tiny_http, two
//!   threads, no async code) that serves the page, `/setup` and `/frame`.
//!   The page polls `/frame?after=SEQ` about ten times a second and gets
//!   the newest frame or nothing new, so a viewer that falls behind skips
//!   frames and costs the run nothing. Several viewers may watch at once.
//!
//! There is no authentication: the server listens on loopback unless the
//! user gives another address.
#![warn(missing_docs)]

use mrsim_lidar::{Scanner, Walls};
use mrsim_planners::lidar::LaserScan;
use mrsim_proto::{BodyState, RobotStats, SnapshotHeader, StatsHeader, run_phase};
use mrsim_scenario::Scenario;
use mrsim_transport::{ObserverTransport, TransportError};
use serde_json::{Value, json};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The page, self-contained (no file or network access of its own).
const PAGE: &str = include_str!("live.html");

/// The people's colour (the report's palette: sandy brown).
const PERSON_COLOR: &str = "#f4a460";

/// Colours of the robots, as in the plots and the replay page.
const PALETTE: [&str; 16] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#bcbd22", "#17becf",
    "#393b79", "#637939", "#8c6d31", "#7b4173", "#3182bd", "#e6550d", "#31a354", "#756bb1",
];

/// Why the live server could not start.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The address could not be bound (in use, not local, no permission).
    #[error("cannot serve the live page on {addr}: {reason}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// The system's reason.
        reason: String,
    },
}

#[derive(Default)]
struct FeedState {
    setup: Option<Arc<String>>,
    frame: Option<Arc<String>>,
    seq: u64,
    end: Option<String>,
}

/// The newest frame of a run and its setup, shared between a [`Pump`] and
/// a [`LiveServer`]. Cloning shares it.
#[derive(Clone, Default)]
pub struct Feed(Arc<Mutex<FeedState>>);

impl Feed {
    /// An empty feed (the page says it waits for the run).
    pub fn new() -> Self {
        Self::default()
    }

    fn with<T>(&self, f: impl FnOnce(&mut FeedState) -> T) -> T {
        // A poisoned lock only means a thread panicked while holding it;
        // the state is still a whole frame.
        let mut g = self.0.lock().unwrap_or_else(|p| p.into_inner());
        f(&mut g)
    }

    /// Sets the run's setup (JSON: run id, scenario, colours, walls).
    pub fn set_setup(&self, setup: String) {
        self.with(|s| s.setup = Some(Arc::new(setup)));
    }

    /// Publishes a frame (JSON); it replaces the one before.
    pub fn publish(&self, frame: String) {
        self.with(|s| {
            s.seq += 1;
            s.frame = Some(Arc::new(frame));
        });
    }

    /// Says how the run ended (`finished`, or why the world is gone); the
    /// page shows it.
    /// The first ending said stays.
    pub fn end(&self, how: impl Into<String>) {
        let how = how.into();
        self.with(|s| {
            if s.end.is_none() {
                s.seq += 1;
                s.end = Some(how);
            }
        });
    }

    /// Has the feed been told how the run ended?
    pub fn ended(&self) -> bool {
        self.with(|s| s.end.is_some())
    }

    /// How many frames (and endings) have been published.
    pub fn seq(&self) -> u64 {
        self.with(|s| s.seq)
    }

    /// The `/frame` answer for a page that has seen `after`: None if
    /// nothing is newer.
    fn frame_after(&self, after: u64) -> Option<String> {
        self.with(|s| {
            (s.seq > after).then(|| {
                format!(
                    "{{\"seq\":{},\"end\":{},\"frame\":{}}}",
                    s.seq,
                    s.end
                        .as_ref()
                        .map_or("null".to_string(), |e| json!(e).to_string()),
                    s.frame.as_ref().map_or("null", |f| f.as_str())
                )
            })
        })
    }
}

/// The HTTP server of the live page.
pub struct LiveServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl LiveServer {
    /// How many threads answer requests.
    const THREADS: usize = 2;

    /// Serves `feed` on `addr` (port 0: a free port, see
    /// [`LiveServer::url`]).
    pub fn start(addr: SocketAddr, feed: Feed) -> Result<Self, LiveError> {
        let server = tiny_http::Server::http(addr).map_err(|e| LiveError::Bind {
            addr: addr.to_string(),
            reason: e.to_string(),
        })?;
        let bound = server.server_addr().to_ip().unwrap_or(addr);
        let server = Arc::new(server);
        let stop = Arc::new(AtomicBool::new(false));
        let threads = (0..Self::THREADS)
            .map(|_| {
                let (server, stop, feed) = (server.clone(), stop.clone(), feed.clone());
                std::thread::spawn(move || {
                    while !stop.load(Ordering::Relaxed) {
                        match server.recv_timeout(Duration::from_millis(200)) {
                            Ok(Some(request)) => answer(request, &feed),
                            Ok(None) => {}
                            Err(_) => break,
                        }
                    }
                })
            })
            .collect();
        Ok(Self {
            addr: bound,
            stop,
            threads,
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's address, to open in a browser.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

type Response = tiny_http::Response<std::io::Cursor<Vec<u8>>>;

/// `response` with the header `name: value` (both constant and valid).
fn with_header(response: Response, name: &str, value: &str) -> Response {
    match tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()) {
        Ok(h) => response.with_header(h),
        Err(()) => response,
    }
}

/// What the page asked for, answered: the status, the content type and the
/// body for a request of `method` on `url` (whatever a browser, or anyone
/// who reaches the port, sends).
fn route(get: bool, url: &str, feed: &Feed) -> (u16, &'static str, String) {
    let (path, query) = url.split_once('?').unwrap_or((url, ""));
    const JSON: &str = "application/json";
    match (get, path) {
        (true, "/") => (200, "text/html; charset=utf-8", PAGE.to_string()),
        (true, "/setup") => match feed.with(|s| s.setup.clone()) {
            Some(setup) => (200, JSON, setup.as_str().to_string()),
            // Not yet: the world has not published its setup.
            None => (503, JSON, "{}".to_string()),
        },
        (true, "/frame") => {
            let after = query
                .split('&')
                .find_map(|kv| kv.strip_prefix("after="))
                .and_then(|v| v.parse::<u64>().ok())
                .unwrap_or(0);
            match feed.frame_after(after) {
                Some(body) => (200, JSON, body),
                None => (204, "text/plain", String::new()),
            }
        }
        _ => (404, "text/plain", "not found".to_string()),
    }
}

fn answer(request: tiny_http::Request, feed: &Feed) {
    let get = *request.method() == tiny_http::Method::Get;
    let (status, kind, body) = route(get, request.url(), feed);
    let mut response = Response::from_string(body).with_status_code(status);
    if kind != "text/plain" {
        response = with_header(response, "Content-Type", kind);
    }
    // A viewer that closed its tab mid-answer is no error of the run's.
    let _ = request.respond(with_header(response, "Cache-Control", "no-store"));
}

/// Fills a [`Feed`] from an observer of a run: its setup once, then each
/// time it is called the newest snapshot and statistics as one frame (at
/// most [`Pump::MAX_RATE`] frames a second, and only when something is
/// new), with the scans of the robots that record theirs, computed by the
/// function the agents and scan.csv use.
pub struct Pump {
    feed: Feed,
    scenario: Option<Scenario>,
    header: SnapshotHeader,
    bodies: Vec<BodyState>,
    stats: StatsHeader,
    robots: Vec<RobotStats>,
    /// The scanner and every body's shape (empty: all discs).
    scanner: Option<(Scanner, Vec<mrsim_planners::Shape>)>,
    scan: LaserScan,
    started: Option<Instant>,
    last: Option<Instant>,
    published_tick: Option<u64>,
    ended: bool,
}

impl Pump {
    /// Frames a second at most (the page polls ten times a second).
    pub const MAX_RATE: f64 = 20.0;

    /// A pump into `feed`.
    pub fn new(feed: Feed) -> Self {
        Self {
            feed,
            scenario: None,
            header: SnapshotHeader::default(),
            bodies: Vec::new(),
            stats: StatsHeader::default(),
            robots: Vec::new(),
            scanner: None,
            scan: LaserScan::default(),
            started: None,
            last: None,
            published_tick: None,
            ended: false,
        }
    }

    /// True once the run has finished or its world is gone (the feed says
    /// which).
    pub fn ended(&self) -> bool {
        self.ended
    }

    /// The newest statistics read (default until the first arrive).
    pub fn stats(&self) -> (&StatsHeader, &[RobotStats]) {
        (&self.stats, &self.robots)
    }

    /// Reads what `obs` has new and publishes it; true if new statistics
    /// arrived (see [`Pump::stats`]). Call it often (every 20-100 ms); it
    /// returns at once.
    pub fn pump(&mut self, obs: &mut dyn ObserverTransport) -> Result<bool, TransportError> {
        if self.ended {
            return Ok(false);
        }
        if self.scenario.is_none() {
            if let Some(setup) = obs.setup()? {
                self.take_setup(&setup);
            }
            if self.scenario.is_none() {
                let stats = obs.latest_stats(&mut self.stats, &mut self.robots)?;
                if !obs.world_alive() {
                    self.finish("the world is gone before the run started");
                }
                return Ok(stats);
            }
        }
        let now = Instant::now();
        let snap = obs.latest_snapshot(&mut self.header, &mut self.bodies)?;
        let stats = obs.latest_stats(&mut self.stats, &mut self.robots)?;
        if (snap || stats) && self.stats.phase != run_phase::JOINING && self.started.is_none() {
            self.started = Some(now);
        }
        let due = self
            .last
            .is_none_or(|t| now.duration_since(t).as_secs_f64() >= 1.0 / Self::MAX_RATE);
        let new_tick = self.published_tick != Some(self.header.tick) && !self.bodies.is_empty();
        if (snap || stats) && due && (new_tick || stats) {
            self.last = Some(now);
            self.published_tick = Some(self.header.tick);
            let frame = self.frame(now);
            self.feed.publish(frame);
        }
        if self.stats.phase == run_phase::FINISHED {
            let frame = self.frame(now);
            self.feed.publish(frame);
            self.finish("finished");
        } else if !obs.world_alive() {
            self.finish("the world is gone: the run ended without finishing");
        }
        Ok(stats)
    }

    fn finish(&mut self, how: &str) {
        self.ended = true;
        self.feed.end(how);
    }

    /// Takes the world's setup message (JSON with `run_id` and `scenario`)
    /// and publishes the page's setup; a setup it cannot read leaves the
    /// page waiting.
    fn take_setup(&mut self, setup: &[u8]) {
        let Ok(v) = serde_json::from_slice::<Value>(setup) else {
            return;
        };
        let Ok(scenario) = serde_json::from_value::<Scenario>(v["scenario"].clone()) else {
            return;
        };
        self.feed
            .set_setup(page_setup(&v["run_id"], &scenario).to_string());
        if scenario
            .robots
            .iter()
            .any(|r| r.sensor.is_some_and(|s| s.record))
        {
            let shapes = if scenario.has_shapes() {
                scenario.body_shapes()
            } else {
                Vec::new()
            };
            self.scanner = Some((Scanner::new(Walls::new(scenario.all_walls())), shapes));
        }
        self.scenario = Some(scenario);
    }

    fn frame(&mut self, now: Instant) -> String {
        let wall = self
            .started
            .map_or(0.0, |t| now.duration_since(t).as_secs_f64());
        let misses: u64 = self.robots.iter().map(|r| r.deadline_misses).sum();
        let p99 = self
            .robots
            .iter()
            .map(|r| r.latency_p99_us)
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let round = |v: f64| (v * 1000.0).round() / 1000.0;
        let bodies: Vec<Value> = self
            .bodies
            .iter()
            .map(|b| {
                json!([
                    b.id,
                    round(b.position[0]),
                    round(b.position[1]),
                    round(b.velocity[0]),
                    round(b.velocity[1]),
                    round(b.heading)
                ])
            })
            .collect();
        let robots: Vec<Value> = self
            .robots
            .iter()
            .map(|r| {
                json!([
                    r.robot_id,
                    r.state,
                    r.reached_goal,
                    r.deadline_misses,
                    round(r.latency_p50_us),
                    round(r.latency_p99_us),
                    r.collisions,
                    r.commands,
                    r.agent_pid
                ])
            })
            .collect();
        let mut scans = serde_json::Map::new();
        if let (Some((scanner, shapes)), Some(scenario)) = (&mut self.scanner, &self.scenario) {
            for (i, r) in scenario.robots.iter().enumerate() {
                if !r.sensor.is_some_and(|s| s.record) {
                    continue;
                }
                if scanner.scan_robot(
                    &mut self.scan,
                    scenario.world.seed,
                    self.header.tick,
                    i,
                    r,
                    &self.bodies,
                    shapes,
                ) {
                    let ranges: Vec<Value> = self
                        .scan
                        .ranges
                        .iter()
                        .map(|&d| {
                            if d.is_finite() {
                                json!(round(d))
                            } else {
                                Value::Null
                            }
                        })
                        .collect();
                    scans.insert(
                        i.to_string(),
                        json!([self.scan.angle_min, self.scan.angle_increment, ranges]),
                    );
                }
            }
        }
        json!({
            "tick": self.header.tick,
            "time": round(self.header.sim_time),
            "wall": round(wall),
            "phase": self.stats.phase,
            "realtime": self.stats.realtime == 1,
            "rtf": round(self.stats.realtime_factor),
            "maxTicks": self.stats.max_ticks,
            "collisions": self.stats.collisions_total,
            "lost": self.stats.agents_lost,
            "misses": misses,
            "p99": round(p99),
            "bodies": bodies,
            "robots": robots,
            "scans": scans,
        })
        .to_string()
    }
}

/// What the page needs once: names, colours, radii, goals, planners,
/// walls, and the view's extent.
fn page_setup(run_id: &Value, s: &Scenario) -> Value {
    let walls: Vec<Value> = s
        .all_walls()
        .iter()
        .map(|[a, b]| json!([a[0], a[1], b[0], b[1]]))
        .collect();
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut grow = |p: [f64; 2], r: f64| {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - r);
            hi[k] = hi[k].max(p[k] + r);
        }
    };
    match &s.world.arena {
        Some(a) => {
            grow(a.min, 0.0);
            grow(a.max, 0.0);
        }
        None => {
            for r in &s.robots {
                grow(r.start, r.radius);
                grow(r.goal, r.radius);
            }
            for o in &s.obstacles {
                grow(o.start, o.radius);
            }
            for p in &s.people {
                grow(p.start, p.radius);
                for &w in &p.waypoints {
                    grow(w, p.radius);
                }
            }
        }
    }
    for w in &s.walls {
        grow(w.segment[0], 0.0);
        grow(w.segment[1], 0.0);
    }
    if !lo[0].is_finite() {
        (lo, hi) = ([-1.0, -1.0], [1.0, 1.0]);
    }
    json!({
        "runId": run_id,
        "name": s.name,
        "description": s.description,
        "dt": s.world.dt,
        "extent": [lo[0], lo[1], hi[0], hi[1]],
        "walls": walls,
        "robots": s.robots.iter().enumerate().map(|(i, r)| with_shape(json!({
            "name": r.name,
            "planner": r.planner,
            "radius": r.radius,
            "goal": r.goal,
            "color": PALETTE[i % PALETTE.len()],
            "unicycle": r.kinematics == mrsim_scenario::Kinematics::Unicycle,
        }), r.body_shape())).collect::<Vec<_>>(),
        "obstacles": s.obstacles.iter().map(|o| {
            with_shape(json!({ "name": o.name, "radius": o.radius }), o.body_shape())
        }).collect::<Vec<_>>(),
        // People: discs, their ids after the obstacles', in the colour the
        // plots and the replay page give them.
        "people": s.people.iter().map(|p| json!({ "name": p.name, "radius": p.radius }))
            .collect::<Vec<_>>(),
        "personColor": PERSON_COLOR,
    })
}

/// `body` with its `shape` added when it is a polygon: the vertices in its
/// body frame (x along its heading), counter-clockwise. The page turns
/// them by each frame's heading; a disc has none.
fn with_shape(mut body: Value, shape: mrsim_shape::Shape) -> Value {
    if let mrsim_shape::Shape::Polygon(p) = shape {
        body["shape"] = json!(p.points());
    }
    body
}

#[cfg(test)]
mod fuzz;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_that_has_seen_the_newest_frame_gets_nothing_new() {
        let feed = Feed::new();
        assert_eq!(feed.frame_after(0), None);
        feed.publish("{\"tick\":1}".into());
        let first = feed.frame_after(0).expect("a frame");
        assert!(
            first.contains("\"tick\":1") && first.contains("\"seq\":1"),
            "{first}"
        );
        assert_eq!(feed.frame_after(1), None);
        feed.publish("{\"tick\":2}".into());
        feed.publish("{\"tick\":3}".into());
        // A viewer behind by two frames gets the newest only.
        let newest = feed.frame_after(1).expect("a frame");
        assert!(
            newest.contains("\"tick\":3") && newest.contains("\"seq\":3"),
            "{newest}"
        );
        feed.end("finished");
        assert!(
            feed.frame_after(3)
                .expect("the end")
                .contains("\"end\":\"finished\"")
        );
    }
}
