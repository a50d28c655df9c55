//! Scheduling: when ticks start and how long the world waits for their
//! answers.
//!
//! Lockstep publishes each tick as soon as the last one is stepped and
//! waits for every live agent, up to `stall_timeout`, after which the
//! silent agents are lost. Realtime publishes on the wall clock (tick `k`
//! at `start + k dt`) and waits until the deadline (`deadline` x `dt` after
//! publishing); what is not in by then is a miss. Time comes from a
//! [`Clock`], so the loop can be driven by a fake one in tests.

use super::admission::TickWindow;
use mrsim_scenario::{Mode, Scenario};
use mrsim_transport::{TransportError, WorldTransport};
use std::time::{Duration, Instant};

/// Where the loop reads the time.
pub trait Clock {
    /// Now.
    fn now(&self) -> Instant;
}

/// The monotonic clock of the system.
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemClock;

impl Clock for SystemClock {
    fn now(&self) -> Instant {
        Instant::now()
    }
}

/// What to do after a round of taking in commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Time is up for this tick (lockstep: the silent agents are lost).
    TimedOut,
    /// Wait for a wake-up at most this long (lockstep, in slices of 20 ms).
    For(Duration),
    /// Wait for a wake-up until this instant (realtime: the deadline).
    Until(Instant),
}

/// The run's timing rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// Realtime (else lockstep).
    pub realtime: bool,
    /// Tick length, s.
    pub dt: f64,
    /// Realtime: publish to deadline.
    pub deadline_after: Duration,
    /// Lockstep: how long an agent may stay silent before it is lost.
    pub stall: Duration,
}

impl Schedule {
    /// The rules of `scenario`.
    pub fn new(scenario: &Scenario) -> Self {
        let dt = scenario.world.dt;
        Self {
            realtime: scenario.world.mode == Mode::Realtime,
            dt,
            deadline_after: Duration::from_secs_f64(dt * scenario.world.deadline),
            stall: Duration::from_secs_f64(scenario.world.stall_timeout),
        }
    }

    /// The pause between everyone ready and tick 0: one tick in realtime
    /// (so tick 0 costs what any tick costs), none in lockstep.
    pub fn settle(&self) -> Duration {
        if self.realtime {
            Duration::from_secs_f64(self.dt)
        } else {
            Duration::ZERO
        }
    }

    /// Realtime: when tick `tick` is due, the clock having started at
    /// `start`; lockstep: `None` (at once).
    pub fn due(&self, start: Instant, tick: u64) -> Option<Instant> {
        self.realtime
            .then(|| start + Duration::from_secs_f64(tick as f64 * self.dt))
    }

    /// The window commands to tick `tick`, published at `published_ns`,
    /// are judged in.
    pub fn window(&self, tick: u64, published_ns: u64) -> TickWindow {
        TickWindow {
            tick,
            published_ns,
            deadline_ns: if self.realtime {
                published_ns + self.deadline_after.as_nanos() as u64
            } else {
                u64::MAX
            },
            realtime: self.realtime,
        }
    }

    /// After waiting `waited` since publishing at `published`: how to go on.
    pub fn next_wait(&self, published: Instant, waited: Duration) -> Wait {
        let limit = if self.realtime {
            self.deadline_after
        } else {
            self.stall
        };
        if waited >= limit {
            Wait::TimedOut
        } else if self.realtime {
            Wait::Until(published + limit)
        } else {
            Wait::For((limit - waited).min(Duration::from_millis(20)))
        }
    }

    /// Why a silent agent is lost in lockstep.
    pub fn stall_reason(&self) -> String {
        format!(
            "no command for {:.1} s (stall_timeout)",
            self.stall.as_secs_f64()
        )
    }
}

/// Waits for a wake-up from an agent or until `until`, whichever comes
/// first (the transports' waits are precise: iceoryx2's on a
/// high-resolution `ppoll`, in-process on a channel's timed receive).
pub fn wait_until(
    link: &mut dyn WorldTransport,
    clock: &dyn Clock,
    until: Instant,
) -> Result<(), TransportError> {
    let left = until.saturating_duration_since(clock.now());
    if left.is_zero() {
        return Ok(());
    }
    link.wait(left.min(Duration::from_millis(20)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn schedule(realtime: bool) -> Schedule {
        Schedule {
            realtime,
            dt: 0.1,
            deadline_after: Duration::from_millis(50),
            stall: Duration::from_secs(2),
        }
    }

    #[test]
    fn lockstep_waits_in_slices_until_the_stall_timeout() {
        let s = schedule(false);
        let t = Instant::now();
        assert_eq!(
            s.next_wait(t, Duration::ZERO),
            Wait::For(Duration::from_millis(20))
        );
        assert_eq!(
            s.next_wait(t, Duration::from_millis(1990)),
            Wait::For(Duration::from_millis(10))
        );
        assert_eq!(s.next_wait(t, Duration::from_secs(2)), Wait::TimedOut);
        assert_eq!(s.due(t, 5), None);
        assert_eq!(s.window(3, 100).deadline_ns, u64::MAX);
        assert_eq!(s.settle(), Duration::ZERO);
    }

    #[test]
    fn realtime_ticks_on_the_clock_and_waits_until_the_deadline() {
        let s = schedule(true);
        let t = Instant::now();
        assert_eq!(s.due(t, 3), Some(t + Duration::from_millis(300)));
        assert_eq!(
            s.next_wait(t, Duration::from_millis(10)),
            Wait::Until(t + Duration::from_millis(50))
        );
        assert_eq!(s.next_wait(t, Duration::from_millis(50)), Wait::TimedOut);
        let w = s.window(7, 1_000);
        assert_eq!(w.deadline_ns, 1_000 + 50_000_000);
        assert!(w.realtime);
        assert_eq!(s.settle(), Duration::from_millis(100));
    }
}
