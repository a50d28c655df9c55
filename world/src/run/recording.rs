//! Recording: what the tick loop hands to the recorder (events), the
//! timings thread and the live view, and what it counts on the way to
//! metrics.json.
//!
//! Events are written with the tick and simulated time they happened at.
//! Admission's verdicts and events come here to be counted and written;
//! the loop logs them and moves the robots.

use super::admission::{Agent, Event};
use crate::histogram::DurationHistogram;
use crate::live::LiveStats;
use crate::metrics::{Deadlock, RobotAccumulator, RobotMetrics, RunMetrics, TimingMetrics};
use crate::physics::{Contact, Owner};
use crate::record::Recorder;
use crate::timings::TimingRecorder;
use crate::tracking::Tracker;
use mrsim_proto::{StatsHeader, agent_state};
use mrsim_scenario::Scenario;
use mrsim_transport::WorldTransport;
use serde_json::json;
use std::time::Instant;

/// Tick and simulated time of what is recorded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamp {
    /// Tick.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
}

/// Run-wide counts of metrics.json.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Contacts started that involve a robot and no person.
    pub collisions_total: u64,
    /// Contacts started between a robot and a person.
    pub person_collisions_total: u64,
    /// Agents lost.
    pub agents_lost: u64,
    /// Commands rejected.
    pub rejected: u64,
    /// Commands rejected that named no robot.
    pub rejected_unknown: u64,
    /// Commands late.
    pub late: u64,
}

/// The tick loop's own costs, one sample per tick.
#[derive(Debug, Clone, Default)]
pub struct LoopCosts {
    /// Realtime: actual tick start minus scheduled.
    pub jitter: DurationHistogram,
    /// Published -> last command in, on ticks where every agent answered.
    pub allin: DurationHistogram,
    /// The loop's own work per tick.
    pub tick_cost: DurationHistogram,
    /// Rapier's step.
    pub physics: DurationHistogram,
}

/// Everything the loop records.
pub struct Recording {
    /// trajectory.csv and events.jsonl, on their thread.
    pub rec: Recorder,
    /// The commands' timings, on their thread.
    pub timings: TimingRecorder,
    live: LiveStats,
    /// Per robot.
    pub acc: Vec<RobotAccumulator>,
    /// Every body's name: the robots, the obstacles, the people.
    names: Vec<String>,
    /// How many of `names`, the last ones, are people.
    people: usize,
    /// Run-wide counts.
    pub counts: Counts,
    /// The loop's own costs.
    pub costs: LoopCosts,
    /// The deadlocks detected so far.
    pub deadlocks: Vec<Deadlock>,
    /// The run ended because every robot not at its goal was stuck.
    pub ended_stuck: bool,
}

/// A robot makes progress when its distance to its goal falls below its
/// distance at its last progress by this fraction of the way its
/// `max_speed` covers in `[world] stuck_after`: slower than 5 % of its top
/// speed on average towards its goal, it is stuck (the speed below which
/// it counts as not moving, `crate::interaction::NOT_MOVING`).
pub const PROGRESS: f64 = crate::interaction::NOT_MOVING;

impl Recording {
    /// Recording for `robots` robots among the bodies called `names`.
    pub fn new(rec: Recorder, timings: TimingRecorder, names: Vec<String>, robots: usize) -> Self {
        Self {
            rec,
            timings,
            live: LiveStats::new(robots),
            acc: vec![
                RobotAccumulator {
                    min_contact_gap: f64::INFINITY,
                    min_person_contact_gap: f64::INFINITY,
                    progress_distance: f64::INFINITY,
                    ..Default::default()
                };
                robots
            ],
            deadlocks: Vec::new(),
            ended_stuck: false,
            names,
            people: 0,
            counts: Counts::default(),
            costs: LoopCosts::default(),
        }
    }

    /// The last `people` of the names are people's.
    pub fn with_people(mut self, people: usize) -> Self {
        self.people = people.min(self.names.len());
        self
    }

    /// Body `i`'s name.
    pub fn name(&self, i: usize) -> &str {
        &self.names[i]
    }

    /// Writes one event, stamped.
    pub fn event(&mut self, at: Stamp, mut v: serde_json::Value) {
        if let Some(o) = v.as_object_mut() {
            o.insert("tick".into(), json!(at.tick));
            o.insert("time".into(), json!(at.time));
        }
        self.rec.event(&v);
    }

    /// Counts and writes what admission did.
    pub fn admitted(&mut self, at: Stamp, e: &Event) {
        match e {
            Event::Joined { robot, pid } => {
                self.acc[*robot].agent_pid = Some(*pid);
                let name = self.names[*robot].clone();
                self.event(
                    at,
                    json!({"type": "agent_joined", "robot": name, "pid": pid}),
                );
            }
            Event::Rejoined {
                robot,
                pid,
                by_command,
            } => {
                if !by_command {
                    self.acc[*robot].agent_pid = Some(*pid);
                }
                let name = self.names[*robot].clone();
                self.event(
                    at,
                    // `token`: "new" for a join (a new token), "kept" for
                    // an agent that answered again with its old one.
                    json!({"type": "agent_rejoined", "robot": name, "pid": pid,
                           "token": if *by_command { "kept" } else { "new" }}),
                );
            }
            Event::JoinRefused { robot, pid, reason } => self.event(
                at,
                json!({"type": "join_refused", "robot": robot, "pid": pid, "reason": reason}),
            ),
            Event::Lost { robot, pid, reason } => {
                self.counts.agents_lost += 1;
                self.acc[*robot].lost += 1;
                let name = self.names[*robot].clone();
                self.event(
                    at,
                    json!({"type": "agent_lost", "robot": name, "pid": pid, "reason": reason}),
                );
            }
        }
    }

    /// Counts and writes a rejected command (`robot`: the robot it named,
    /// `None` for an id `id` that names none).
    pub fn rejected(
        &mut self,
        at: Stamp,
        robot: Option<usize>,
        id: u32,
        reason: &str,
        for_tick: u64,
    ) {
        self.counts.rejected += 1;
        let robot = match robot {
            Some(i) => {
                self.acc[i].rejected += 1;
                self.names[i].clone()
            }
            None => {
                self.counts.rejected_unknown += 1;
                format!("#{id}")
            }
        };
        self.event(
            at,
            json!({"type": "command_rejected", "robot": robot, "reason": reason,
                          "for_tick": for_tick}),
        );
    }

    /// Writes a planner call's row of timing.csv and records its response
    /// time and CPU for metrics.json.
    pub fn call(&mut self, call: crate::record::Call) {
        self.timings
            .call(call.robot as usize, call.sent_ns, call.cpu_ns);
        self.rec.call(call);
    }

    /// Counts a command that came after its deadline.
    pub fn late(&mut self, robot: usize) {
        self.counts.late += 1;
        self.acc[robot].late += 1;
    }

    /// Counts and writes a tick robot `robot` did not answer in time.
    pub fn miss(&mut self, at: Stamp, robot: usize) {
        self.acc[robot].deadline_misses += 1;
        // The most frequent event of a run with misses: written without a
        // JSON map, the keys in the order every other event has them
        // (sorted), so the line is the one `event` would write.
        #[derive(serde::Serialize)]
        struct Miss<'a> {
            robot: &'a str,
            tick: u64,
            time: f64,
            #[serde(rename = "type")]
            kind: &'static str,
        }
        self.rec.event(&Miss {
            robot: &self.names[robot],
            tick: at.tick,
            time: at.time,
            kind: "deadline_miss",
        });
    }

    /// Counts and writes the contacts of a step that involve a robot: a
    /// robot's with a person apart from the others.
    pub fn contacts(&mut self, at: Stamp, contacts: &[Contact]) {
        let n = self.acc.len();
        for c in contacts {
            if !matches!(c.a, Owner::Robot(_)) && !matches!(c.b, Owner::Robot(_)) {
                continue;
            }
            let person = matches!(c.a, Owner::Person(_)) || matches!(c.b, Owner::Person(_));
            if person {
                self.counts.person_collisions_total += 1;
            } else {
                self.counts.collisions_total += 1;
            }
            for o in [c.a, c.b] {
                if let Owner::Robot(i) = o {
                    let a = &mut self.acc[i];
                    if person {
                        a.person_collisions += 1;
                        a.min_person_contact_gap = a.min_person_contact_gap.min(c.gap);
                    } else {
                        a.collisions += 1;
                        a.min_contact_gap = a.min_contact_gap.min(c.gap);
                    }
                }
            }
            let name = |o: Owner| match o {
                Owner::Robot(i) => self.names[i].clone(),
                Owner::Obstacle(k) => self.names[n + k].clone(),
                Owner::Person(k) => self.names[self.names.len() - self.people + k].clone(),
                Owner::Wall(w) => format!("wall{w}"),
            };
            self.event(
                at,
                json!({"type": "collision", "a": name(c.a), "b": name(c.b),
                              "x": c.at[0], "y": c.at[1], "gap": c.gap}),
            );
        }
    }

    /// The goal test after a step (Ko & Choi eq 22: within tolerance for
    /// `goal_hold_ticks` ticks running; with a `goal_heading`, the heading
    /// within its tolerance too, [`mrsim_scenario::RobotSpec::at_goal`]),
    /// for robots at `poses` (position, heading); writes and returns the
    /// robots that reached their goal just now. The other metrics of the
    /// robots' motion come from the recorded states, off this loop
    /// ([`crate::tracking`]).
    pub fn goals(
        &mut self,
        at: Stamp,
        scenario: &Scenario,
        poses: impl Iterator<Item = ([f64; 2], f64)>,
    ) -> Vec<usize> {
        let mut reached = Vec::new();
        let robots = poses.zip(&scenario.robots);
        for (i, (((p, heading), spec), acc)) in robots.zip(&mut self.acc).enumerate() {
            if spec.at_goal(p, heading) {
                if acc.hold == 0 {
                    acc.hold_start = at.time;
                }
                acc.hold += 1;
                if !acc.reached_goal && acc.hold >= spec.goal_hold_ticks.max(1) {
                    acc.reached_goal = true;
                    acc.time_to_goal = Some(acc.hold_start);
                    reached.push(i);
                }
            } else {
                acc.hold = 0;
            }
        }
        for &i in &reached {
            let name = self.names[i].clone();
            let t = self.acc[i].time_to_goal;
            self.event(
                at,
                json!({"type": "goal_reached", "robot": name, "time_to_goal": t}),
            );
        }
        reached
    }

    /// The stuck test after a step, for robots at `positions`: a robot not
    /// at its goal whose distance to its goal has not fallen [`PROGRESS`] x
    /// `max_speed` x `stuck_after` below its distance at its last progress
    /// for `[world] stuck_after` seconds is stuck (event `stuck`) until it makes progress again
    /// (event `unstuck`). Robots stuck within each other's sensing range
    /// (surface gap at most the smaller range), linked in a chain, are a
    /// deadlock (event `deadlock` naming them) when one of them has just
    /// become stuck. True when the run should end: `[world]
    /// end_when_stuck` and every robot not at its goal is stuck.
    pub fn stuck(&mut self, at: Stamp, scenario: &Scenario, positions: &[[f64; 2]]) -> bool {
        let after = scenario.world.stuck_after;
        let mut fresh = Vec::new();
        let mut freed = Vec::new();
        for (i, (spec, acc)) in scenario.robots.iter().zip(&mut self.acc).enumerate() {
            if acc.reached_goal {
                if let Some(since) = acc.stuck_since.take() {
                    acc.stuck_time += at.time - since;
                }
                continue;
            }
            let Some(p) = positions.get(i) else { continue };
            let d = (spec.goal[0] - p[0]).hypot(spec.goal[1] - p[1]);
            let progress = PROGRESS * spec.max_speed * after;
            if d <= spec.goal_tolerance || d < acc.progress_distance - progress {
                acc.progress_distance = d;
                acc.progress_time = at.time;
                if let Some(since) = acc.stuck_since.take() {
                    acc.stuck_time += at.time - since;
                    freed.push(i);
                }
            } else if acc.stuck_since.is_none() && at.time - acc.progress_time >= after - 1e-9 {
                acc.stuck_since = Some(at.time);
                fresh.push(i);
            }
        }
        for &i in &freed {
            let name = self.names[i].clone();
            self.event(at, json!({"type": "unstuck", "robot": name}));
        }
        for &i in &fresh {
            let name = self.names[i].clone();
            self.event(at, json!({"type": "stuck", "robot": name}));
        }
        self.deadlocks_of(at, scenario, positions, &fresh);
        let mut waiting = self.acc.iter().filter(|a| !a.reached_goal).peekable();
        let all = waiting.peek().is_some() && waiting.all(|a| a.stuck_since.is_some());
        if all && scenario.world.end_when_stuck && !self.ended_stuck {
            self.ended_stuck = true;
            self.event(at, json!({"type": "all_stuck"}));
        }
        self.ended_stuck
    }

    /// Writes the deadlocks that the robots `fresh`, just stuck, belong to.
    fn deadlocks_of(
        &mut self,
        at: Stamp,
        scenario: &Scenario,
        positions: &[[f64; 2]],
        fresh: &[usize],
    ) {
        if fresh.is_empty() {
            return;
        }
        let stuck: Vec<usize> = (0..self.acc.len())
            .filter(|&i| self.acc[i].stuck_since.is_some() && i < positions.len())
            .collect();
        let linked = |i: usize, j: usize| {
            let (a, b) = (&scenario.robots[i], &scenario.robots[j]);
            let (p, q) = (positions[i], positions[j]);
            let gap = (p[0] - q[0]).hypot(p[1] - q[1]) - a.radius - b.radius;
            gap <= a.sensing_range.min(b.sensing_range)
        };
        let mut grouped = vec![false; self.acc.len()];
        for &start in fresh {
            if grouped[start] {
                continue;
            }
            grouped[start] = true;
            let mut group = vec![start];
            let mut k = 0;
            while k < group.len() {
                let i = group[k];
                for &j in &stuck {
                    if !grouped[j] && linked(i, j) {
                        grouped[j] = true;
                        group.push(j);
                    }
                }
                k += 1;
            }
            if group.len() < 2 {
                continue;
            }
            group.sort_unstable();
            let robots: Vec<String> = group.iter().map(|&i| self.names[i].clone()).collect();
            self.event(at, json!({"type": "deadlock", "robots": robots}));
            self.deadlocks.push(Deadlock {
                tick: at.tick,
                time: at.time,
                robots,
            });
        }
    }

    /// Publishes the live statistics for observers when due (or now, with
    /// `force`): no allocation, and a failure never stops the run.
    /// `header` gives everything but the counts, which this fills in; it
    /// is asked only when the statistics are due.
    pub fn publish_stats(
        &mut self,
        link: &mut dyn WorldTransport,
        agents: &[Agent],
        header: impl FnOnce() -> StatsHeader,
        force: bool,
    ) {
        let now = Instant::now();
        if !force && !self.live.due(now) {
            return;
        }
        let mut header = header();
        let (acc, rows) = (&self.acc, self.live.robots_mut());
        self.timings.live(|latency| {
            for (i, row) in rows.iter_mut().enumerate() {
                let l = latency.get(i).copied().unwrap_or_default();
                row.latency_p50_us = l.p50_us;
                row.latency_p99_us = l.p99_us;
                row.commands = l.commands;
            }
        });
        for (i, row) in rows.iter_mut().enumerate() {
            let acc = &acc[i];
            row.state = match agents[i] {
                Agent::Waiting => agent_state::WAITING,
                Agent::Live { .. } => agent_state::LIVE,
                Agent::Lost { .. } => agent_state::LOST,
            };
            row.reached_goal = u32::from(acc.reached_goal);
            row.agent_pid = acc.agent_pid.unwrap_or(0);
            row.deadline_misses = acc.deadline_misses;
            // The live view counts every contact, with people too.
            row.collisions = acc.collisions + acc.person_collisions;
            row.commands_rejected = acc.rejected;
        }
        header.collisions_total =
            self.counts.collisions_total + self.counts.person_collisions_total;
        header.agents_lost = self.counts.agents_lost;
        let _ = self.live.publish(link, &header, now);
    }
}

/// metrics.json from what was recorded: the loop's `counts` and
/// accumulators, the commands' `robot_timings`, the motion metrics of
/// `tracker`, and the run-wide `timing`.
pub struct Summary<'a> {
    /// The scenario run.
    pub scenario: &'a Scenario,
    /// Ticks run.
    pub ticks: u64,
    /// Simulated time at the end, s.
    pub sim_time: f64,
    /// Wall-clock time of the tick loop, s.
    pub wall_s: f64,
    /// The run id.
    pub run_id: String,
    /// The transport's name.
    pub transport: String,
    /// Stopped by a signal.
    pub interrupted: bool,
    /// The run as a real-time system.
    pub timing: TimingMetrics,
    /// The deadlocks detected.
    pub deadlocks: Vec<Deadlock>,
    /// Ended because every robot not at its goal was stuck.
    pub ended_stuck: bool,
}

impl Summary<'_> {
    /// The metrics of a finished run.
    pub fn metrics(
        self,
        counts: Counts,
        acc: &[RobotAccumulator],
        robot_timings: &mut [crate::histogram::RobotTimings],
        tracker: &Tracker,
    ) -> RunMetrics {
        let n = self.scenario.robots.len();
        let robots = self
            .scenario
            .robots
            .iter()
            .zip(acc)
            .zip(robot_timings)
            .zip(tracker.robots())
            .zip(tracker.interaction().robots())
            .map(|((((spec, a), t), m), x)| {
                let calls = t
                    .calls()
                    .map(|[response, cpu]| (response.percentiles(), cpu.percentiles()));
                let [latency, wake, compute] = t.histograms();
                let min_clearance = m.min_clearance.min(a.min_contact_gap);
                let people = tracker.interaction().has_people();
                let person_min = x.person_min_gap.min(a.min_person_contact_gap);
                let spl = m.spl(a.reached_goal);
                let stuck_time = a.stuck_time + a.stuck_since.map_or(0.0, |s| self.sim_time - s);
                (
                    spec.name.clone(),
                    RobotMetrics {
                        planner: spec.planner.clone(),
                        reached_goal: a.reached_goal,
                        time_to_goal: a.time_to_goal,
                        path_length: m.path_length,
                        collisions: a.collisions,
                        min_clearance: min_clearance.is_finite().then_some(min_clearance),
                        max_speed: m.max_speed,
                        deadline_misses: a.deadline_misses,
                        latency_us: latency.percentiles(),
                        wake_us: wake.percentiles(),
                        compute_us: compute.percentiles(),
                        response_us: calls.map(|c| c.0),
                        cpu_us: calls.map(|c| c.1),
                        overruns: a.overruns,
                        agent_pid: a.agent_pid,
                        lost: a.lost,
                        commands_rejected: a.rejected,
                        commands_late: a.late,
                        path_deviation: m.path.as_ref().map(|p| p.deviation()),
                        boundary_violations: m.path.as_ref().and_then(|p| p.boundary_violations()),
                        spl: Some(spl),
                        time_not_moving: Some(x.time_not_moving),
                        ttc_min: Some(x.ttc_min.is_finite().then_some(x.ttc_min)),
                        time_intimate: Some(x.time_intimate),
                        time_personal: Some(x.time_personal),
                        time_social: Some(x.time_social),
                        jerk_mean: Some(x.jerk_mean()),
                        path_irregularity: Some(x.path_irregularity()),
                        heading_change: Some(x.heading_change),
                        stuck_time: Some(stuck_time),
                        outcome: None,
                        outcome_time: None,
                        collided_with: None,
                        person_collisions: people.then_some(a.person_collisions),
                        person_min_clearance: people
                            .then_some(person_min.is_finite().then_some(person_min)),
                        person_ttc_min: people
                            .then_some(x.person_ttc_min.is_finite().then_some(x.person_ttc_min)),
                        person_time_intimate: people.then_some(x.person_time_intimate),
                        person_time_personal: people.then_some(x.person_time_personal),
                        person_time_social: people.then_some(x.person_time_social),
                        discomfort_time: people.then_some(x.discomfort_time),
                    },
                )
            })
            .collect::<std::collections::BTreeMap<String, RobotMetrics>>();
        let people = tracker.interaction().has_people();
        let person_min_clearance = people.then(|| {
            let m = robots
                .values()
                .filter_map(|r| r.person_min_clearance.flatten())
                .fold(f64::INFINITY, f64::min);
            m.is_finite().then_some(m)
        });
        let discomfort_time =
            people.then(|| robots.values().filter_map(|r| r.discomfort_time).sum());
        let reached = acc.iter().filter(|a| a.reached_goal).count();
        let times: Option<Vec<f64>> = acc.iter().map(|a| a.time_to_goal).collect();
        let times = times.filter(|t| !t.is_empty());
        let travelled: f64 = tracker.robots().iter().map(|m| m.path_length).sum();
        let spl = (n > 0).then(|| robots.values().filter_map(|r| r.spl).sum::<f64>() / n as f64);
        RunMetrics {
            scenario: self.scenario.name.clone(),
            robots,
            collisions_total: counts.collisions_total,
            success_rate: if n > 0 {
                reached as f64 / n as f64
            } else {
                0.0
            },
            ticks: self.ticks,
            sim_time: self.sim_time,
            mode: self.scenario.world.mode.to_string(),
            realtime_factor: if self.wall_s > 0.0 {
                self.sim_time / self.wall_s
            } else {
                0.0
            },
            agents_lost: counts.agents_lost,
            commands_rejected: counts.rejected,
            commands_late: counts.late,
            commands_rejected_unknown: counts.rejected_unknown,
            world_pid: std::process::id(),
            run_id: self.run_id,
            transport: self.transport,
            interrupted: self.interrupted,
            timing: self.timing,
            spl,
            makespan: Some(
                times
                    .as_ref()
                    .map(|t| t.iter().copied().fold(0.0, f64::max)),
            ),
            flowtime: Some(times.as_ref().map(|t| t.iter().sum())),
            collisions_per_robot_km: Some(
                (travelled > 0.0).then(|| counts.collisions_total as f64 / (travelled / 1000.0)),
            ),
            deadlocks: self.deadlocks,
            ended_stuck: self.ended_stuck,
            person_collisions_total: people.then_some(counts.person_collisions_total),
            person_min_clearance,
            discomfort_time,
            ..RunMetrics::default()
        }
    }
}

/// Adds what a networked transport refused before the loop saw it
/// (Zenoh's counts) to `m`: commands that did not decode are rejected
/// commands that named no robot (as the loop counts them); the rest have
/// keys of their own, written only for such a transport.
pub(super) fn add_network_counts(m: &mut RunMetrics, c: mrsim_transport::NetworkCounts) {
    m.commands_rejected += c.commands_malformed;
    m.commands_rejected_unknown += c.commands_malformed;
    m.auth_refused = Some(c.auth_refused);
    m.messages_dropped = Some(c.dropped);
    m.joins_malformed = Some(c.joins_malformed);
}
