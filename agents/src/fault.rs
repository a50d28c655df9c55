//! Fault injection for tests: an agent that misbehaves on purpose, so the
//! world's defences can be proved with real processes (`mrsim agent
//! --fault MODE`, a hidden option).
//!
//! Bad commands ([`Fault::Nan`] .. [`Fault::Double`]) change what the agent
//! sends; process faults ([`Fault::HangAt`], [`Fault::DieAt`],
//! [`Fault::StopAt`], [`Fault::SlowMs`]) change how it behaves at a given
//! tick. `DieAt` and `StopAt` send the process a real SIGKILL or SIGSTOP
//! from inside, so the fault lands at a known tick; the world sees exactly
//! what it sees when the signal comes from outside.

use mrsim_proto::CommandMsg;
use std::str::FromStr;

/// One way of misbehaving.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// Every command's value is NaN.
    Nan,
    /// Every command's value is +infinity.
    Inf,
    /// Every command's value is scaled to an absurd magnitude (1e300).
    Huge,
    /// Every command names the next robot (by id) instead of this one.
    OtherRobot,
    /// Every command names the tick before the one it answers (tick 0 is
    /// not answered at all).
    PastTick,
    /// Every command names the tick after the one it answers.
    FutureTick,
    /// Every command is sent twice.
    Double,
    /// Every command says it was sent just after its tick's deadline
    /// (realtime; in lockstep there is no deadline and nothing changes), as
    /// from an agent that answered late while the world had not yet
    /// stopped waiting.
    SentLate,
    /// The join request is sent twice at once (as an agent whose first
    /// reply was slow re-asks).
    JoinTwice,
    /// From this tick on the planner never returns: the agent stops
    /// answering but stays alive (it still ends with the run or on SIGTERM,
    /// so tests leave nothing running).
    HangAt(u64),
    /// At this tick the agent sends itself SIGKILL.
    DieAt(u64),
    /// At this tick the agent sends itself SIGSTOP (SIGCONT resumes it).
    StopAt(u64),
    /// The planner takes this many milliseconds longer every tick.
    SlowMs(u64),
}

/// A `--fault` value that is not one of the modes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown fault `{0}` (nan, inf, huge, other-robot, past-tick, future-tick, double, \
     sent-late, join-twice, hang-at-tick=N, die-at-tick=N, stop-at-tick=N, slow-ms=N)"
)]
pub struct UnknownFault(pub String);

impl FromStr for Fault {
    type Err = UnknownFault;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || UnknownFault(s.to_string());
        let (mode, arg) = match s.split_once('=') {
            Some((m, a)) => (m, Some(a.trim().parse::<u64>().map_err(|_| bad())?)),
            None => (s, None),
        };
        Ok(match (mode.trim(), arg) {
            ("nan", None) => Fault::Nan,
            ("inf", None) => Fault::Inf,
            ("huge", None) => Fault::Huge,
            ("other-robot", None) => Fault::OtherRobot,
            ("past-tick", None) => Fault::PastTick,
            ("future-tick", None) => Fault::FutureTick,
            ("double", None) => Fault::Double,
            ("sent-late", None) => Fault::SentLate,
            ("join-twice", None) => Fault::JoinTwice,
            ("hang-at-tick", Some(n)) => Fault::HangAt(n),
            ("die-at-tick", Some(n)) => Fault::DieAt(n),
            ("stop-at-tick", Some(n)) => Fault::StopAt(n),
            ("slow-ms", Some(n)) => Fault::SlowMs(n),
            _ => return Err(bad()),
        })
    }
}

impl std::fmt::Display for Fault {
    /// The `--fault` value that parses back to this fault.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Nan => f.write_str("nan"),
            Fault::Inf => f.write_str("inf"),
            Fault::Huge => f.write_str("huge"),
            Fault::OtherRobot => f.write_str("other-robot"),
            Fault::PastTick => f.write_str("past-tick"),
            Fault::FutureTick => f.write_str("future-tick"),
            Fault::Double => f.write_str("double"),
            Fault::SentLate => f.write_str("sent-late"),
            Fault::JoinTwice => f.write_str("join-twice"),
            Fault::HangAt(n) => write!(f, "hang-at-tick={n}"),
            Fault::DieAt(n) => write!(f, "die-at-tick={n}"),
            Fault::StopAt(n) => write!(f, "stop-at-tick={n}"),
            Fault::SlowMs(n) => write!(f, "slow-ms={n}"),
        }
    }
}

/// What the agent loop must do at a tick before planning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Before {
    /// Plan and answer as usual.
    Go,
    /// Never answer again (a planner stuck in a loop).
    Hang,
}

/// The fault state of one agent (process faults fire once).
#[derive(Debug, Clone)]
pub struct Injector {
    fault: Fault,
    fired: bool,
}

impl Injector {
    /// Starts injecting `fault`.
    pub fn new(fault: Fault) -> Self {
        Self {
            fault,
            fired: false,
        }
    }

    /// Runs the process fault due at `tick`, if any.
    pub fn before_plan(&mut self, tick: u64) -> Before {
        match self.fault {
            Fault::HangAt(n) if tick >= n => return Before::Hang,
            Fault::DieAt(n) if tick >= n && !self.fired => {
                self.fired = true;
                mrsim_sys::process::kill(std::process::id(), mrsim_sys::signal::SIGKILL);
            }
            Fault::StopAt(n) if tick >= n && !self.fired => {
                self.fired = true;
                // Execution resumes here on SIGCONT.
                mrsim_sys::process::kill(std::process::id(), mrsim_sys::signal::SIGSTOP);
            }
            Fault::SlowMs(ms) => std::thread::sleep(std::time::Duration::from_millis(ms)),
            _ => {}
        }
        Before::Go
    }

    /// Turns the honest command `msg` into what this faulty agent sends
    /// (`robots` is the number of robots in the run, `deadline_ns` the
    /// tick's deadline, 0 in lockstep).
    pub fn corrupt(&self, msg: CommandMsg, robots: usize, deadline_ns: u64) -> Vec<CommandMsg> {
        let mut m = msg;
        match self.fault {
            Fault::Nan => m.value = [f64::NAN, f64::NAN],
            Fault::Inf => m.value = [f64::INFINITY, f64::INFINITY],
            Fault::Huge => {
                let n = m.value[0].hypot(m.value[1]);
                m.value = if n > 0.0 {
                    [m.value[0] / n * 1e300, m.value[1] / n * 1e300]
                } else {
                    [1e300, 0.0]
                };
            }
            Fault::OtherRobot => m.robot_id = ((m.robot_id as usize + 1) % robots.max(1)) as u32,
            Fault::PastTick => match m.tick.checked_sub(1) {
                Some(t) => m.tick = t,
                None => return Vec::new(),
            },
            Fault::FutureTick => m.tick += 1,
            Fault::Double => return vec![m, m],
            Fault::SentLate if deadline_ns > 0 => m.sent_ns = deadline_ns + 1,
            Fault::SentLate
            | Fault::JoinTwice
            | Fault::HangAt(_)
            | Fault::DieAt(_)
            | Fault::StopAt(_)
            | Fault::SlowMs(_) => {}
        }
        vec![m]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mode_parses_and_nonsense_is_refused() {
        for (s, f) in [
            ("nan", Fault::Nan),
            ("inf", Fault::Inf),
            ("huge", Fault::Huge),
            ("other-robot", Fault::OtherRobot),
            ("past-tick", Fault::PastTick),
            ("future-tick", Fault::FutureTick),
            ("double", Fault::Double),
            ("sent-late", Fault::SentLate),
            ("join-twice", Fault::JoinTwice),
            ("hang-at-tick=7", Fault::HangAt(7)),
            ("die-at-tick=3", Fault::DieAt(3)),
            ("stop-at-tick=0", Fault::StopAt(0)),
            ("slow-ms=5", Fault::SlowMs(5)),
        ] {
            assert_eq!(s.parse::<Fault>(), Ok(f));
        }
        for s in ["", "nan=1", "hang-at-tick", "hang-at-tick=x", "boom"] {
            assert!(s.parse::<Fault>().is_err(), "{s}");
        }
    }

    #[test]
    fn bad_commands_are_what_their_names_say() {
        let msg = CommandMsg {
            robot_id: 1,
            tick: 5,
            value: [3.0, 4.0],
            ..Default::default()
        };
        let one = |f| Injector::new(f).corrupt(msg, 2, 0);
        assert!(one(Fault::Nan)[0].value[0].is_nan());
        assert_eq!(one(Fault::Inf)[0].value[1], f64::INFINITY);
        let h = one(Fault::Huge)[0].value;
        assert!((h[0] - 0.6e300).abs() < 1e285 && (h[1] - 0.8e300).abs() < 1e285);
        assert_eq!(one(Fault::OtherRobot)[0].robot_id, 0);
        assert_eq!(one(Fault::PastTick)[0].tick, 4);
        assert_eq!(one(Fault::FutureTick)[0].tick, 6);
        assert_eq!(one(Fault::Double).len(), 2);
        let first = CommandMsg { tick: 0, ..msg };
        assert!(
            Injector::new(Fault::PastTick)
                .corrupt(first, 2, 0)
                .is_empty()
        );
        assert_eq!(one(Fault::SlowMs(1)), vec![msg]);
        // Late only where there is a deadline (realtime).
        assert_eq!(one(Fault::SentLate), vec![msg]);
        let late = Injector::new(Fault::SentLate).corrupt(msg, 2, 900);
        assert_eq!(late[0].sent_ns, 901);
    }
}
