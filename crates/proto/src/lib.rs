//! Wire types shared by the mrsim world and its agents.
//!
//! Everything that crosses a process boundary is defined here, once, so that
//! the world and every agent agree on layout and iceoryx2 type names: each
//! type is `#[repr(C)]`, fixed size, free of heap pointers and derives
//! `ZeroCopySend`. The crate has no logic beyond small constructors; the
//! transport decides how the types travel.
#![warn(missing_docs)]

use iceoryx2::prelude::ZeroCopySend;

/// Bumped whenever a wire type changes shape or meaning. An agent whose
/// version differs from the world's is refused at join time. What version 6
/// is: each snapshot rings the run's doorbell (a futex word in shared
/// memory); an agent says ready once it has read the setup and again once it
/// has taken up the tick's channels, and the world starts the clock when all
/// have; an agent counts its answer to a tick on the doorbell page and the
/// last answer wakes the world; the doorbell names the world that made it
/// (process id and start time) and an agent goes on only if that world is
/// running (ARCHITECTURE.md, "Channels" and "Ownership"; how each came
/// about is in the git log). Version 7: a [`BodyState`] carries the body's
/// heading and angular velocity, and a unicycle robot is driven by
/// [`command_kind::UNICYCLE`] commands (forward speed, turn rate). Version
/// 8: a robot under a timing model answers a lockstep tick it does not plan
/// on with [`command_kind::NONE`], and a command its model lost arrives as
/// [`command_kind::LOST`]. Version 9: over Zenoh, an accepted join reply
/// carries the key the world signs its snapshots with, and every snapshot
/// its tag (`mrsim_transport::zenoh::seal`). Version 10: a join request
/// says how many robots its process joins as ([`JoinRequest::group`]).
/// Version 11: a command carries the CPU time its call took
/// ([`CommandMsg::cpu_ns`]) and the agent's count of reservation overruns
/// ([`CommandMsg::overruns`]); in lockstep under `[world.cpus]` the world
/// marks the robots whose planner reads a snapshot with [`flags::PLANS`],
/// and such a robot plans only then. Version 12: a [`BodyState`] carries
/// a car's steering angle ([`BodyState::steering`]), and a car is driven by
/// [`command_kind::ACKERMANN`] commands (speed, steering). Version 13: a
/// snapshot carries people, bodies of kind [`body_kind::PERSON`] after the
/// obstacles.
pub const PROTOCOL_VERSION: u32 = 13;

/// Longest robot name, in bytes, that fits a [`JoinRequest`].
pub const MAX_NAME_LEN: usize = 64;

/// Longest human-readable reason in a [`JoinReply`].
pub const MAX_REASON_LEN: usize = 160;

/// Body kinds, the `kind` field of a [`BodyState`].
pub mod body_kind {
    /// A robot driven by an agent.
    pub const ROBOT: u32 = 0;
    /// A scripted obstacle moved by the world.
    pub const OBSTACLE: u32 = 1;
    /// A person (pedestrian) moved by the world's crowd models (since
    /// protocol 13).
    pub const PERSON: u32 = 2;

    /// A kind's name as the run folder writes it (trajectory.csv,
    /// encounters.csv): `robot`, `person`, and `obstacle` for any other.
    pub fn name(kind: u32) -> &'static str {
        match kind {
            ROBOT => "robot",
            PERSON => "person",
            _ => "obstacle",
        }
    }
}

/// Per-body flags in a snapshot.
pub mod flags {
    /// The robot's agent has been lost (died or stalled); the world brakes it.
    pub const LOST: u32 = 1;
    /// The robot has reached its goal and held it for `goal_hold_ticks`.
    pub const AT_GOAL: u32 = 2;
    /// Lockstep under `[world.cpus]`, a robot whose compute is CPU work
    /// (`cpu = true`): the cores' model has its planner read this
    /// snapshot. Unmarked, it answers [`super::command_kind::NONE`] (since
    /// protocol 11). Never set otherwise.
    pub const PLANS: u32 = 4;
}

/// The state of one body at the end of a tick, as published by the world.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct BodyState {
    /// Index of the body in the scenario: robots first, then obstacles,
    /// then people.
    pub id: u32,
    /// Robot, obstacle or person, one of [`body_kind`].
    pub kind: u32,
    /// Bit set of [`flags`].
    pub flags: u32,
    /// Explicit padding, always zero.
    pub _pad: u32,
    /// Position, scenario units.
    pub position: [f64; 2],
    /// Velocity, scenario units per second.
    pub velocity: [f64; 2],
    /// Disc radius (0 for a point robot).
    pub radius: f64,
    /// Heading, rad, counter-clockwise from +x: a unicycle's or a car's
    /// body orientation, an obstacle's fixed one; 0 for holonomic robots.
    pub heading: f64,
    /// Turn rate, rad/s (0 for holonomic robots and obstacles).
    pub angular_velocity: f64,
    /// A car's steering angle, rad, counter-clockwise (0 for every other
    /// body; since protocol 12).
    pub steering: f64,
}

/// Header of every snapshot: one per tick, followed by a slice of
/// [`BodyState`] for every body.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct SnapshotHeader {
    /// Tick number, starting at 0. A command must answer the current tick.
    pub tick: u64,
    /// Simulated time at this snapshot, s.
    pub sim_time: f64,
    /// The world's wall clock when it published this snapshot
    /// (CLOCK_MONOTONIC, ns): the start of every latency measurement.
    pub published_ns: u64,
    /// Deadline for commands answering this tick (CLOCK_MONOTONIC, ns);
    /// 0 in lockstep mode, where the world waits.
    pub deadline_ns: u64,
    /// 1 once the run is over: agents exit when they see it.
    pub finished: u32,
    /// Number of bodies in the slice that follows.
    pub body_count: u32,
}

/// Command kinds, the `kind` field of a [`CommandMsg`].
pub mod command_kind {
    /// Force, applied for the whole tick.
    pub const FORCE: u32 = 0;
    /// Velocity set-point, tracked by a first-order lag.
    pub const VELOCITY: u32 = 1;
    /// Not a command: the agent has read the setup and built its planner
    /// (sent once after joining; the world starts the clock only when every
    /// agent is ready, so the first ticks are not lost to start-up).
    pub const READY: u32 = 2;
    /// A unicycle robot's set-points: `value` is (forward speed v, turn
    /// rate omega in rad/s), tracked within the robot's speed and
    /// acceleration limits (since protocol 7).
    pub const UNICYCLE: u32 = 3;
    /// An answer without a command: the robot's timing model kept its
    /// planner from answering this tick (busy on an earlier snapshot, not a
    /// tick of its period, or its snapshot lost). Sent in lockstep only, so
    /// that the world need not wait (since protocol 8).
    pub const NONE: u32 = 4;
    /// A command the robot's timing model lost on its way (`command_loss`):
    /// counted and recorded as lost, never applied (since protocol 8).
    pub const LOST: u32 = 5;
    /// A car's set-points: `value` is (speed along the heading, steering
    /// angle in rad), tracked within the car's limits; on any other robot
    /// it brakes (since protocol 12).
    pub const ACKERMANN: u32 = 6;
}

/// One agent's answer to one tick.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct CommandMsg {
    /// The robot this command drives.
    pub robot_id: u32,
    /// Force or velocity, one of [`command_kind`].
    pub kind: u32,
    /// The token the world handed this agent when it joined; commands
    /// without the robot's current token are rejected.
    pub token: u64,
    /// The tick this command answers.
    pub tick: u64,
    /// Force (N in scenario units), velocity, (v, omega) for
    /// [`command_kind::UNICYCLE`], or (speed, steering) for
    /// [`command_kind::ACKERMANN`].
    pub value: [f64; 2],
    /// Time the agent spent on the answer, ns: the observation and the
    /// planner (an agent that plans as it wakes counts from its wake-up
    /// for the snapshot, or, for a robot after another of the same
    /// process, from the end of that one's).
    pub compute_ns: u64,
    /// When the agent woke for this tick (CLOCK_MONOTONIC, ns).
    pub woke_ns: u64,
    /// When the agent sent this command (CLOCK_MONOTONIC, ns).
    pub sent_ns: u64,
    /// The CPU time the call took, ns: in lockstep the modelled CPU work
    /// (`compute = { ..., cpu = true }`, 0 for a wait), in realtime the
    /// agent's thread's CPU clock over the call (since protocol 11).
    pub cpu_ns: u64,
    /// A realtime agent under SCHED_DEADLINE: how many times its
    /// reservation overran so far; 0 otherwise (since protocol 11).
    pub overruns: u32,
    /// Explicit padding, always zero.
    pub _pad: u32,
}

/// A fixed-size, NUL-padded UTF-8 string.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend)]
pub struct FixedStr<const N: usize> {
    len: u32,
    bytes: [u8; N],
}

impl<const N: usize> Default for FixedStr<N> {
    fn default() -> Self {
        Self {
            len: 0,
            bytes: [0; N],
        }
    }
}

impl<const N: usize> FixedStr<N> {
    /// Copies `s`, truncated at a character boundary to fit `N` bytes.
    pub fn new(s: &str) -> Self {
        let mut end = s.len().min(N);
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        let mut bytes = [0; N];
        bytes[..end].copy_from_slice(&s.as_bytes()[..end]);
        Self {
            len: end as u32,
            bytes,
        }
    }

    /// The string, or `""` if the bytes are not valid UTF-8.
    pub fn as_str(&self) -> &str {
        let len = (self.len as usize).min(N);
        std::str::from_utf8(&self.bytes[..len]).unwrap_or("")
    }
}

/// An agent asks to drive a robot.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct JoinRequest {
    /// The agent's [`PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// The agent's process id.
    pub pid: u32,
    /// Random number chosen by the agent to find its reply.
    pub nonce: u64,
    /// The robot's name from the scenario.
    pub robot: FixedStr<MAX_NAME_LEN>,
    /// How many robots the agent's process joins as, this one included (1
    /// for an agent of one robot; 0 where the transport does not carry
    /// it): the process sends that many commands at once, and the world's
    /// buffer for one process's commands must hold them all.
    pub group: u32,
}

/// The world's answer to a [`JoinRequest`].
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct JoinReply {
    /// The request's nonce.
    pub nonce: u64,
    /// 1 if accepted.
    pub accepted: u32,
    /// The robot's id when accepted.
    pub robot_id: u32,
    /// The token to put in every command when accepted.
    pub token: u64,
    /// The world's protocol version.
    pub protocol_version: u32,
    /// The world's process id (0 if unknown): an agent on the same machine
    /// watches it to notice a dead world cheaply.
    pub world_pid: u32,
    /// Why the request was refused, empty when accepted.
    pub reason: FixedStr<MAX_REASON_LEN>,
}

/// Event ids on the world's tick event service.
pub mod events {
    /// Not sent: a snapshot rings the run's doorbell instead. The id is
    /// kept so the others keep their values.
    pub const SNAPSHOT: usize = 1;
    /// A join reply is published.
    pub const JOIN_REPLY: usize = 2;
    /// An agent sent a command.
    pub const COMMAND: usize = 3;
    /// An agent sent a join request.
    pub const JOIN_REQUEST: usize = 4;
    /// A notifier's process died (iceoryx2 dead-notifier event).
    pub const NOTIFIER_DEAD: usize = 5;
    /// The largest id above (the event services are sized to it: a
    /// listener's wake-up drains a bit set this long).
    pub const MAX_ID: usize = 5;
}

/// A robot's agent as the world sees it, the `state` field of a
/// [`RobotStats`].
pub mod agent_state {
    /// No agent has joined for this robot yet.
    pub const WAITING: u32 = 0;
    /// An agent drives the robot.
    pub const LIVE: u32 = 1;
    /// The robot's agent died or stalled; the world brakes the robot.
    pub const LOST: u32 = 2;
}

/// Phases of a run, the `phase` field of a [`StatsHeader`].
pub mod run_phase {
    /// The world waits for every robot's agent to join.
    pub const JOINING: u32 = 0;
    /// The clock runs.
    pub const RUNNING: u32 = 1;
    /// The run is over (its outputs are being written).
    pub const FINISHED: u32 = 2;
}

/// One robot's live statistics, as the world last computed them. Published
/// a few times per second for observers (`mrsim top`, the launcher's
/// progress bar); never read by agents.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct RobotStats {
    /// The robot's index in the scenario.
    pub robot_id: u32,
    /// Its agent's state, one of [`agent_state`].
    pub state: u32,
    /// 1 once the robot has reached its goal (held for `goal_hold_ticks`).
    pub reached_goal: u32,
    /// Process id of the agent that last drove it (0 if none yet).
    pub agent_pid: u32,
    /// Median latency, snapshot published -> command received, µs.
    pub latency_p50_us: f64,
    /// 99th percentile of the same latency, µs.
    pub latency_p99_us: f64,
    /// Commands counted so far (the latency histogram's sample count).
    pub commands: u64,
    /// Ticks whose command came late or never (realtime).
    pub deadline_misses: u64,
    /// Contacts started with anything.
    pub collisions: u64,
    /// Commands rejected that named this robot.
    pub commands_rejected: u64,
}

/// Header of every stats message, followed by one [`RobotStats`] per robot.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Default)]
pub struct StatsHeader {
    /// Ticks simulated so far.
    pub tick: u64,
    /// The run's last tick (`duration / dt`): the run ends there at the latest.
    pub max_ticks: u64,
    /// Simulated time, s.
    pub sim_time: f64,
    /// Simulated seconds per wall-clock second since the clock started.
    pub realtime_factor: f64,
    /// The world's clock when it published this message (CLOCK_MONOTONIC, ns).
    pub published_ns: u64,
    /// Contacts started, all robots.
    pub collisions_total: u64,
    /// Agents lost so far.
    pub agents_lost: u64,
    /// One of [`run_phase`].
    pub phase: u32,
    /// 1 for realtime, 0 for lockstep.
    pub realtime: u32,
    /// Number of [`RobotStats`] that follow.
    pub robot_count: u32,
    /// The world's process id.
    pub world_pid: u32,
}

/// Monotonic clock in ns (CLOCK_MONOTONIC), comparable across processes
/// on one machine.
#[inline]
pub fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime only writes into the timespec we own; with
    // CLOCK_MONOTONIC it cannot fail on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_str_round_trips_and_truncates_on_char_boundary() {
        assert_eq!(FixedStr::<8>::new("r0").as_str(), "r0");
        assert_eq!(FixedStr::<4>::new("abcdef").as_str(), "abcd");
        assert_eq!(FixedStr::<3>::new("aé").as_str(), "aé");
        assert_eq!(FixedStr::<2>::new("aé").as_str(), "a");
    }

    #[test]
    fn monotonic_clock_does_not_go_back() {
        let a = now_ns();
        let b = now_ns();
        assert!(b >= a);
    }
}
