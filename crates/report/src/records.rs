//! What a run folder's files hold, in memory: the trajectory grouped by
//! body, the events and the planners' diagnostics.

use serde::{Deserialize, Serialize};

/// What a body in `trajectory.csv` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Driven by an agent.
    Robot,
    /// Moved by the world.
    Obstacle,
    /// A person, moved by the world's crowd models.
    Person,
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
    /// Heading, rad: the `theta` column, present when the run records
    /// headings (a unicycle robot or a body that is not a disc).
    pub theta: Option<f64>,
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
