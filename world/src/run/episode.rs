//! The run counted as an episode of the crowd-navigation benchmarks
//! (`[world] end_on`): CrowdNav's `CrowdSim.step` (Chen et al., "Crowd-Robot
//! Interaction", ICRA 2019) ends an episode at the robot's first contact
//! (`Collision`), at its goal (`ReachGoal`) or at the time limit
//! (`Timeout`), the contact taking precedence over the goal within a step.
//!
//! Per robot, in that order of precedence:
//! - **collision**: its first contact (with a robot, a person, an obstacle
//!   or a wall) started before it reached its goal. With `"collision"` in
//!   `end_on` that contact ends the run at the tick it starts; contacts
//!   among bodies that are not robots never count. A robot already at its
//!   goal has ended its episode: a contact after it changes nothing.
//! - **success**: at its goal (the world's goal test) within the time limit.
//! - **timeout**: not at its goal when the run's duration, its time limit,
//!   ended it, with `"timeout"` in `end_on`.
//! - **unfinished**: not at its goal when the run ended otherwise (another
//!   robot's contact, everyone stuck, a signal), or at its duration when
//!   `end_on` does not name `"timeout"`.
//!
//! The run's outcome is the worst of its robots' (collision, then timeout,
//! then unfinished, then success): with one robot, that robot's.

use crate::metrics::{EndedBy, Episode as EpisodeMetrics, Outcome, RunMetrics};
use crate::physics::{Contact, Owner};
use mrsim_scenario::{EndOn, Scenario};

/// A robot's first contact before its goal.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FirstContact {
    /// Simulated time after the step it started in, s.
    time: f64,
    /// The other side.
    with: Owner,
}

/// What the tick loop keeps of the episode.
#[derive(Debug, Clone)]
pub struct Episode {
    end_on: EndOn,
    /// Per robot, its first contact before its goal, if any.
    first: Vec<Option<FirstContact>>,
    /// The run ended at a contact.
    ended_on_contact: bool,
}

impl Episode {
    /// The episode of a run of `scenario` (counted only with `end_on`).
    pub fn new(scenario: &Scenario) -> Self {
        Self {
            end_on: scenario.world.end_on,
            first: vec![None; scenario.robots.len()],
            ended_on_contact: false,
        }
    }

    /// True if the run is counted as an episode.
    pub fn counted(&self) -> bool {
        !self.end_on.is_empty()
    }

    /// Notes the first contacts among the contacts started in a step, of
    /// the robots not at their goals before it (`reached`); true if one
    /// ends the run (`end_on` names `"collision"`).
    pub fn contacts(
        &mut self,
        time: f64,
        contacts: &[Contact],
        reached: impl Fn(usize) -> bool,
    ) -> bool {
        if !self.counted() {
            return false;
        }
        let mut fresh = false;
        for c in contacts {
            for (me, other) in [(c.a, c.b), (c.b, c.a)] {
                let Owner::Robot(i) = me else { continue };
                if i >= self.first.len() || reached(i) || self.first[i].is_some() {
                    continue;
                }
                self.first[i] = Some(FirstContact { time, with: other });
                fresh = true;
            }
        }
        if fresh && self.end_on.collision {
            self.ended_on_contact = true;
        }
        self.ended_on_contact
    }

    /// Fills in each robot's outcome and the run's `episode` in `m`, for a
    /// run of `scenario` over bodies named `names` (robots, then
    /// obstacles, then people) that ran `ticks` ticks to simulated time `time`.
    pub fn fill(
        &self,
        m: &mut RunMetrics,
        scenario: &Scenario,
        names: &[String],
        ticks: u64,
        time: f64,
    ) {
        if !self.counted() {
            return;
        }
        let at_limit = ticks >= scenario.max_ticks();
        let ended_by = if self.ended_on_contact {
            EndedBy::Collision
        } else if m.interrupted {
            EndedBy::Interrupted
        } else if m.ended_stuck {
            EndedBy::Stuck
        } else if at_limit {
            EndedBy::TimeLimit
        } else {
            EndedBy::Goals
        };
        let n = scenario.robots.len();
        let name = |o: Owner| match o {
            Owner::Robot(i) => names[i].clone(),
            Owner::Obstacle(k) => names[n + k].clone(),
            Owner::Person(k) => names[n + scenario.obstacles.len() + k].clone(),
            Owner::Wall(w) => format!("wall{w}"),
        };
        let mut counts = [0u32; 4];
        let mut arrivals = Vec::new();
        for (spec, first) in scenario.robots.iter().zip(&self.first) {
            let Some(r) = m.robots.get_mut(&spec.name) else {
                continue;
            };
            let (outcome, at) = match (first, r.time_to_goal) {
                (Some(c), _) => {
                    r.collided_with = Some(name(c.with));
                    (Outcome::Collision, c.time)
                }
                (None, Some(t)) if r.reached_goal => {
                    arrivals.push(t);
                    (Outcome::Success, t)
                }
                _ if at_limit && self.end_on.timeout && ended_by == EndedBy::TimeLimit => {
                    (Outcome::Timeout, time)
                }
                _ => (Outcome::Unfinished, time),
            };
            counts[rank(outcome)] += 1;
            r.outcome = Some(outcome);
            r.outcome_time = Some(at);
        }
        let worst = [
            Outcome::Collision,
            Outcome::Timeout,
            Outcome::Unfinished,
            Outcome::Success,
        ]
        .into_iter()
        .find(|o| counts[rank(*o)] > 0)
        .unwrap_or(Outcome::Unfinished);
        m.episode = Some(EpisodeMetrics {
            end_on: self.end_on.names().iter().map(|s| s.to_string()).collect(),
            outcome: worst,
            ended_by,
            time,
            success: counts[rank(Outcome::Success)],
            collision: counts[rank(Outcome::Collision)],
            timeout: counts[rank(Outcome::Timeout)],
            unfinished: counts[rank(Outcome::Unfinished)],
            time_to_goal: (!arrivals.is_empty())
                .then(|| arrivals.iter().sum::<f64>() / arrivals.len() as f64),
        });
    }
}

/// The slot of an outcome in the counts.
fn rank(o: Outcome) -> usize {
    match o {
        Outcome::Collision => 0,
        Outcome::Timeout => 1,
        Outcome::Unfinished => 2,
        Outcome::Success => 3,
    }
}
