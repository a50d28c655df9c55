//! Timing as a variable of the experiment: a robot's planner compute time,
//! the age of what it is shown, the delay of its commands, its rate, and
//! lost snapshots and commands (`[defaults.timing]`, `[robot.timing]`).
//!
//! The semantics exist here once, for both modes. Every draw is a pure
//! function of (`world.seed`, robot, tick of the snapshot read, stream), so
//! neither thread nor process scheduling changes it:
//!
//! - after reading a snapshot the planner is busy for its compute time; the
//!   command is sent then, and answers the tick of that snapshot: sent after
//!   that tick's deadline it is late (a miss, never applied);
//! - once free the planner reads the newest snapshot it has not seen (one
//!   published while it was busy at once, else it waits for the next);
//! - `period_ticks = k`: only snapshots of ticks 0, k, 2k, ... are read;
//!   in between the command holds, and those ticks are no misses;
//! - `snapshot_loss`, `command_loss`: a snapshot (per robot and tick) or a
//!   command is lost with that probability; a lost command is a miss;
//! - `observation_delay_ms`: the planner reading tick t's snapshot is shown
//!   the state of tick t - round(delay / dt) (states exist only at ticks);
//! - `actuation_delay_ms`: a command takes effect that long after it was
//!   sent, from the first physics substep that starts at or after then.
//!
//! In lockstep [`Clerk`] decides all of this from the model (the world
//! judges the modelled send times); in realtime the agent spends the drawn
//! compute time for real and the world judges the real send times.

use crate::rng::Rng;
use serde::{Deserialize, Serialize};

/// A robot's timing model, all defaults applied.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The planner's compute time per snapshot read.
    pub compute: Compute,
    /// Age of the state the planner is shown, ms, >= 0.
    pub observation_delay_ms: f64,
    /// Time from sending a command to its taking effect, ms, >= 0.
    pub actuation_delay_ms: f64,
    /// The planner reads every k-th tick's snapshot, >= 1.
    pub period_ticks: u32,
    /// Probability that the robot's snapshot of a tick is lost, in [0, 1].
    pub snapshot_loss: f64,
    /// Probability that a command is lost on its way, in [0, 1].
    pub command_loss: f64,
    /// The compute time is CPU work that contends for the cores
    /// (`compute = { ..., cpu = true }`); false (the default): a wait that
    /// takes no core (I/O, a GPU, a remote service). Left out of the
    /// resolved scenario when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub cpu: bool,
    /// The planner's priority under `[world.cpus] scheduler = "fifo"`
    /// (`priority = 1..99 | "rate-monotonic"`); `None`: rate-monotonic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub priority: Option<Priority>,
    /// The planner's CPU reservation under `[world.cpus] scheduler =
    /// "deadline"` (`reservation = { runtime_ms, period_ms }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reservation: Option<Reservation>,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            compute: Compute::None,
            observation_delay_ms: 0.0,
            actuation_delay_ms: 0.0,
            period_ticks: 1,
            snapshot_loss: 0.0,
            command_loss: 0.0,
            cpu: false,
            priority: None,
            reservation: None,
        }
    }
}

/// A planner's fixed priority (`timing.priority`), as SCHED_FIFO's: the
/// higher level runs first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Priority {
    /// A level in 1..=99 (`priority = 50`).
    Level(u8),
    /// From the robot's rate (`priority = "rate-monotonic"`): the shorter
    /// `period_ticks`, the higher; equal periods by robot name.
    RateMonotonic,
}

impl Serialize for Priority {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Priority::Level(l) => s.serialize_u8(*l),
            Priority::RateMonotonic => s.serialize_str("rate-monotonic"),
        }
    }
}

impl<'de> Deserialize<'de> for Priority {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Written {
            Level(i64),
            Name(String),
        }
        match Written::deserialize(d)? {
            Written::Level(l) if (1..=99).contains(&l) => Ok(Priority::Level(l as u8)),
            Written::Name(n) if n == "rate-monotonic" => Ok(Priority::RateMonotonic),
            _ => Err(serde::de::Error::custom(
                "a priority is 1..99 or \"rate-monotonic\"",
            )),
        }
    }
}

/// A constant-bandwidth CPU reservation (`timing.reservation`), as
/// SCHED_DEADLINE's: `runtime_ms` of CPU in every `period_ms`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reservation {
    /// CPU time granted per period, ms, in (0, `period_ms`].
    pub runtime_ms: f64,
    /// The reservation's period (and relative deadline), ms, > 0.
    pub period_ms: f64,
}

impl Reservation {
    /// The runtime, ns.
    pub fn runtime_ns(&self) -> u64 {
        ms_to_ns(self.runtime_ms)
    }

    /// The period, ns.
    pub fn period_ns(&self) -> u64 {
        ms_to_ns(self.period_ms)
    }

    /// The share of one core it grants, runtime / period.
    pub fn bandwidth(&self) -> f64 {
        self.runtime_ms / self.period_ms
    }
}

/// The planner's compute time per snapshot read (`compute = { model, ... }`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum Compute {
    /// None modelled: in lockstep the command is sent as the snapshot is
    /// published; in realtime the planner's own time.
    None,
    /// Always `ms`.
    Fixed {
        /// Compute time, ms, >= 0.
        ms: f64,
    },
    /// Uniform in [`min_ms`, `max_ms`].
    Uniform {
        /// Least compute time, ms, >= 0.
        min_ms: f64,
        /// Largest compute time, ms, >= `min_ms`.
        max_ms: f64,
    },
    /// Log-normal: `median_ms` times e^(`sigma` Z), Z standard normal (mean
    /// `median_ms` e^(`sigma`²/2)).
    Lognormal {
        /// Median compute time, ms, > 0.
        median_ms: f64,
        /// Standard deviation of the logarithm, >= 0.
        sigma: f64,
    },
    /// `base_ms` plus `per_body_ms` for every body the planner senses
    /// (robots and obstacles within its sensing range and field of view):
    /// perception that grows with what is seen.
    PerBody {
        /// Time with nothing in view, ms, >= 0.
        base_ms: f64,
        /// Time per body in view, ms, >= 0.
        per_body_ms: f64,
    },
}

/// One stream of draws of a robot's timing.
#[derive(Debug, Clone, Copy)]
enum Stream {
    Compute,
    SnapshotLoss,
    CommandLoss,
}

impl Stream {
    fn tag(self) -> &'static str {
        match self {
            Stream::Compute => "timing-compute",
            Stream::SnapshotLoss => "timing-snapshot-loss",
            Stream::CommandLoss => "timing-command-loss",
        }
    }
}

/// The draw of `stream` for robot `robot` at tick `tick`: a fresh stream
/// per robot and tick (as [`Rng::lidar`]), whatever else was drawn.
fn rng(seed: u64, robot: u64, tick: u64, stream: Stream) -> Rng {
    Rng::stream(seed, stream.tag(), (robot << 40) ^ tick)
}

/// Milliseconds as whole nanoseconds (negative as 0).
pub fn ms_to_ns(ms: f64) -> u64 {
    (ms * 1e6).round().max(0.0) as u64
}

/// Seconds as whole nanoseconds (negative as 0).
pub fn s_to_ns(s: f64) -> u64 {
    (s * 1e9).round().max(0.0) as u64
}

impl Timing {
    /// The compute time of robot `robot`'s planner on the snapshot of
    /// `tick`, sensing `sensed` bodies, ns.
    pub fn compute_ns(&self, seed: u64, robot: u64, tick: u64, sensed: usize) -> u64 {
        let ms = match self.compute {
            Compute::None => 0.0,
            Compute::Fixed { ms } => ms,
            Compute::Uniform { min_ms, max_ms } => {
                let u = rng(seed, robot, tick, Stream::Compute).unit();
                min_ms + (max_ms - min_ms) * u
            }
            Compute::Lognormal { median_ms, sigma } => {
                let z = rng(seed, robot, tick, Stream::Compute).gaussian();
                median_ms * (sigma * z).exp()
            }
            Compute::PerBody {
                base_ms,
                per_body_ms,
            } => base_ms + per_body_ms * sensed as f64,
        };
        ms_to_ns(ms)
    }

    /// Whether robot `robot`'s snapshot of `tick` is lost.
    pub fn snapshot_lost(&self, seed: u64, robot: u64, tick: u64) -> bool {
        self.snapshot_loss > 0.0
            && rng(seed, robot, tick, Stream::SnapshotLoss).unit() < self.snapshot_loss
    }

    /// Whether the command robot `robot` sends on the snapshot of `tick` is
    /// lost on its way.
    pub fn command_lost(&self, seed: u64, robot: u64, tick: u64) -> bool {
        self.command_loss > 0.0
            && rng(seed, robot, tick, Stream::CommandLoss).unit() < self.command_loss
    }

    /// True if the planner runs on `tick`'s snapshot at all (`period_ticks`):
    /// a tick it does not is no miss.
    pub fn plans_at(&self, tick: u64) -> bool {
        tick.is_multiple_of(u64::from(self.period_ticks.max(1)))
    }

    /// Why robot `robot`'s planner does not read `tick`'s snapshot, whatever
    /// it is busy with: not a tick of its period, or the snapshot is lost.
    pub fn skips(&self, seed: u64, robot: u64, tick: u64) -> Option<Turn> {
        if !self.plans_at(tick) {
            Some(Turn::Off)
        } else if self.snapshot_lost(seed, robot, tick) {
            Some(Turn::SnapshotLost)
        } else {
            None
        }
    }

    /// The age of the state shown, in ticks of `dt` seconds.
    pub fn observation_delay_ticks(&self, dt: f64) -> u64 {
        if self.observation_delay_ms <= 0.0 || dt <= 0.0 {
            return 0;
        }
        (self.observation_delay_ms / 1000.0 / dt).round() as u64
    }

    /// The physics substep, counted from the start of the run, from which a
    /// command sent `sent_ns` after the publication of `tick` takes effect:
    /// the first that starts at or after it is sent plus the actuation
    /// delay (`dt_ns` per tick, `substeps` per tick).
    pub fn effect_substep(&self, tick: u64, sent_ns: u64, dt_ns: u64, substeps: u32) -> u64 {
        effect_substep(
            tick,
            sent_ns + ms_to_ns(self.actuation_delay_ms),
            dt_ns,
            substeps,
        )
    }
}

/// The first physics substep (counted from the start of the run) that
/// starts at or after `after_ns` past the publication of `tick`.
pub fn effect_substep(tick: u64, after_ns: u64, dt_ns: u64, substeps: u32) -> u64 {
    let sub = u64::from(substeps.max(1));
    let dt_ns = dt_ns.max(1);
    let into = (u128::from(after_ns) * u128::from(sub)).div_ceil(u128::from(dt_ns));
    tick * sub + u64::try_from(into).unwrap_or(u64::MAX / 2)
}

/// What a robot's planner does at one tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Turn {
    /// It reads this tick's snapshot `start_ns` after its publication.
    Plan {
        /// When it reads the snapshot, ns after its publication.
        start_ns: u64,
    },
    /// Not a tick of its period: the command holds, no miss.
    Off,
    /// The snapshot was lost on its way to the planner.
    SnapshotLost,
    /// Still computing on an earlier snapshot.
    Busy,
}

/// A planner's command as timing sends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sent {
    /// When it is sent, ns after the publication of the tick it answers.
    pub sent_ns: u64,
    /// Lost on its way (`command_loss`).
    pub lost: bool,
    /// The CPU the call took in the model: its compute time if that is CPU
    /// work (`cpu = true`), else 0 (a wait).
    pub cpu_ns: u64,
}

/// One robot's planner in modelled time (lockstep): when it reads which
/// snapshot and when its command is sent, from its [`Timing`] alone.
#[derive(Debug, Clone)]
pub struct Clerk {
    timing: Timing,
    seed: u64,
    robot: u64,
    dt_ns: u64,
    /// When the planner is free again, ns from the run's start.
    free_at_ns: u64,
}

impl Clerk {
    /// Robot `robot`'s clerk in a run of seed `seed` and tick `dt` s.
    pub fn new(timing: Timing, seed: u64, robot: u64, dt: f64) -> Self {
        Self {
            timing,
            seed,
            robot,
            dt_ns: s_to_ns(dt).max(1),
            free_at_ns: 0,
        }
    }

    /// The model this clerk follows.
    pub fn timing(&self) -> &Timing {
        &self.timing
    }

    /// What the planner does at `tick` (ticks asked in increasing order).
    pub fn turn(&self, tick: u64) -> Turn {
        if let Some(skip) = self.timing.skips(self.seed, self.robot, tick) {
            return skip;
        }
        let start = tick * self.dt_ns;
        if self.free_at_ns >= start + self.dt_ns {
            return Turn::Busy;
        }
        Turn::Plan {
            start_ns: self.free_at_ns.saturating_sub(start),
        }
    }

    /// The planner read `tick`'s snapshot `start_ns` after its publication
    /// and sensed `sensed` bodies: its command's send time; it is busy
    /// until then.
    pub fn planned(&mut self, tick: u64, start_ns: u64, sensed: usize) -> Sent {
        let compute = self.timing.compute_ns(self.seed, self.robot, tick, sensed);
        let sent_ns = start_ns + compute;
        self.free_at_ns = tick * self.dt_ns + sent_ns;
        Sent {
            sent_ns,
            lost: self.timing.command_lost(self.seed, self.robot, tick),
            cpu_ns: if self.timing.cpu { compute } else { 0 },
        }
    }
}

/// What became of one planner call's command, as recorded in a realtime
/// run's timing.csv and replayed by `mrsim rerun`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CallStatus {
    /// In by its tick's deadline, applied.
    Accepted,
    /// After its tick's deadline: a miss, not applied.
    Late,
    /// Lost on its way (`command_loss`): a miss.
    Lost,
}

/// One planner call of a recorded run: the snapshot it read and when its
/// command was sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordedCall {
    /// The tick of the snapshot read (the tick the command answers).
    pub tick: u64,
    /// When the command was sent, ns after that snapshot's publication.
    pub sent_ns: u64,
    /// What became of it.
    pub status: CallStatus,
    /// The CPU it took, ns (0 in a record without it).
    #[serde(default)]
    pub cpu_ns: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(compute: Compute) -> Timing {
        Timing {
            compute,
            ..Timing::default()
        }
    }

    /// Mean and standard deviation of robot 3's compute draws (ms) over
    /// `n` ticks.
    fn stats(t: &Timing, n: u64) -> (f64, f64) {
        let xs: Vec<f64> = (0..n)
            .map(|k| t.compute_ns(9, 3, k, 4) as f64 / 1e6)
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, var.sqrt())
    }

    #[test]
    fn draws_are_a_function_of_seed_robot_and_tick_only() {
        let t = with(Compute::Lognormal {
            median_ms: 20.0,
            sigma: 0.5,
        });
        let a: Vec<u64> = (0..100).map(|k| t.compute_ns(1, 2, k, 0)).collect();
        let b: Vec<u64> = (0..100).rev().map(|k| t.compute_ns(1, 2, k, 0)).collect();
        assert!(
            a.iter().eq(b.iter().rev()),
            "order of asking changed a draw"
        );
        assert_ne!(
            a,
            (0..100)
                .map(|k| t.compute_ns(2, 2, k, 0))
                .collect::<Vec<_>>()
        );
        assert_ne!(
            a,
            (0..100)
                .map(|k| t.compute_ns(1, 3, k, 0))
                .collect::<Vec<_>>()
        );
    }

    #[test]
    fn fixed_compute_is_always_its_value_and_none_is_zero() {
        let (mean, sd) = stats(&with(Compute::Fixed { ms: 30.0 }), 1000);
        assert_eq!((mean, sd), (30.0, 0.0));
        assert_eq!(stats(&with(Compute::None), 100), (0.0, 0.0));
    }

    #[test]
    fn uniform_compute_has_the_mean_and_spread_of_its_interval() {
        let n = 100_000;
        let (mean, sd) = stats(
            &with(Compute::Uniform {
                min_ms: 10.0,
                max_ms: 50.0,
            }),
            n,
        );
        let true_sd = 40.0 / 12f64.sqrt();
        // Four standard errors.
        assert!(
            (mean - 30.0).abs() < 4.0 * true_sd / (n as f64).sqrt(),
            "{mean}"
        );
        assert!((sd - true_sd).abs() < 0.02 * true_sd, "{sd}");
        let t = with(Compute::Uniform {
            min_ms: 10.0,
            max_ms: 50.0,
        });
        assert!((0..10_000).all(|k| (10_000_000..=50_000_000).contains(&t.compute_ns(1, 0, k, 0))));
    }

    #[test]
    fn lognormal_compute_has_its_median_mean_and_spread() {
        let n = 200_000u64;
        let t = with(Compute::Lognormal {
            median_ms: 20.0,
            sigma: 0.5,
        });
        let (mean, sd) = stats(&t, n);
        let true_mean = 20.0 * (0.125f64).exp();
        let true_sd = true_mean * ((0.25f64).exp() - 1.0).sqrt();
        assert!(
            (mean - true_mean).abs() < 4.0 * true_sd / (n as f64).sqrt(),
            "{mean}"
        );
        assert!((sd - true_sd).abs() < 0.03 * true_sd, "{sd}");
        let below = (0..n)
            .filter(|&k| t.compute_ns(9, 3, k, 0) < 20_000_000)
            .count();
        let half = below as f64 / n as f64;
        assert!((half - 0.5).abs() < 4.0 * 0.5 / (n as f64).sqrt(), "{half}");
    }

    #[test]
    fn per_body_compute_grows_by_its_step_with_every_body_sensed() {
        let t = with(Compute::PerBody {
            base_ms: 5.0,
            per_body_ms: 2.5,
        });
        assert_eq!(t.compute_ns(1, 0, 0, 0), 5_000_000);
        assert_eq!(t.compute_ns(1, 0, 7, 4), 15_000_000);
    }

    #[test]
    fn losses_at_rate_p_lose_about_p() {
        let t = Timing {
            snapshot_loss: 0.2,
            command_loss: 0.05,
            ..Timing::default()
        };
        let n = 100_000u64;
        for (p, lost) in [
            (0.2, (0..n).filter(|&k| t.snapshot_lost(4, 1, k)).count()),
            (0.05, (0..n).filter(|&k| t.command_lost(4, 1, k)).count()),
        ] {
            let rate = lost as f64 / n as f64;
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!((rate - p).abs() < 4.0 * se, "{rate} against {p}");
        }
        let none = Timing::default();
        assert!((0..1000).all(|k| !none.snapshot_lost(1, 0, k) && !none.command_lost(1, 0, k)));
    }

    #[test]
    fn compute_longer_than_a_tick_keeps_the_planner_busy_into_the_next() {
        // dt 0.1 s, 150 ms of compute: reads 0 at 0, sends at 150 ms; at
        // tick 1 it is free at 50 ms into the tick and reads 1 then.
        let mut c = Clerk::new(with(Compute::Fixed { ms: 150.0 }), 1, 0, 0.1);
        assert_eq!(c.turn(0), Turn::Plan { start_ns: 0 });
        assert_eq!(c.planned(0, 0, 0).sent_ns, 150_000_000);
        assert_eq!(
            c.turn(1),
            Turn::Plan {
                start_ns: 50_000_000
            }
        );
        assert_eq!(c.planned(1, 50_000_000, 0).sent_ns, 200_000_000);
        // Free exactly at tick 3's start.
        assert_eq!(c.turn(2), Turn::Busy);
        assert_eq!(c.turn(3), Turn::Plan { start_ns: 0 });
    }

    #[test]
    fn period_two_reads_every_other_snapshot() {
        let c = Clerk::new(
            Timing {
                period_ticks: 2,
                ..Timing::default()
            },
            1,
            0,
            0.1,
        );
        let turns: Vec<Turn> = (0..4).map(|k| c.turn(k)).collect();
        assert_eq!(
            turns,
            [
                Turn::Plan { start_ns: 0 },
                Turn::Off,
                Turn::Plan { start_ns: 0 },
                Turn::Off
            ]
        );
    }

    #[test]
    fn a_command_takes_effect_from_the_first_substep_after_it_is_sent_plus_the_delay() {
        let t = Timing {
            actuation_delay_ms: 20.0,
            ..Timing::default()
        };
        // dt 100 ms, 10 substeps of 10 ms: sent at 0 -> substep 2 of tick 5.
        assert_eq!(t.effect_substep(5, 0, 100_000_000, 10), 52);
        // Sent at 31 ms -> 51 ms: the substep starting at 60 ms.
        assert_eq!(t.effect_substep(5, 31_000_000, 100_000_000, 10), 56);
        assert_eq!(Timing::default().effect_substep(5, 0, 100_000_000, 10), 50);
    }
}
