//! The real cores: which Linux scheduling policy each robot's agent
//! process takes in a realtime run under `[world.cpus]`, the same mapping
//! for the launcher (which asks the kernel before the run) and for the
//! agent (which takes it after it starts: a SCHED_DEADLINE task cannot
//! start the processes and threads an agent needs before it runs).
//!
//! - `fair` -> SCHED_OTHER (nice 0).
//! - `fifo` -> SCHED_FIFO one level below the robot's level in the model
//!   ([`mrsim_scenario::cores::fifo_levels`]: its `timing.priority`, or
//!   rate-monotonic, 99 for the shortest `period_ticks`, one below for the
//!   next robot by period and then name, ...): 99 is the world's, which
//!   runs above every agent. The order is the model's, but for levels 1
//!   and 2, which both run at 1. Equal levels given by hand run in the
//!   order they became runnable (Linux), where the model orders them by
//!   name.
//! - `deadline` -> SCHED_DEADLINE with the robot's `timing.reservation`
//!   (runtime, deadline = period, period); a robot without one (its
//!   compute takes no core, `cpu = false`) runs SCHED_OTHER.
//!
//! The world runs at SCHED_FIFO [`WORLD_PRIORITY`], above every agent's
//! SCHED_FIFO level; SCHED_DEADLINE tasks run
//! before any SCHED_FIFO task, so under `deadline` the world runs where
//! the reservations leave a core free.

use mrsim_scenario::cores::{Task, fifo_levels};
use mrsim_scenario::timing::Timing;
use mrsim_scenario::{Mode, Scheduler, WorldConfig};
use mrsim_sys::policy::Policy;

pub use mrsim_sys::sched::WORLD_PRIORITY;

/// True if a run of `world` sets the agents' policies for real: realtime
/// under `[world.cpus]`.
pub fn real(world: &WorldConfig) -> bool {
    world.mode == Mode::Realtime && world.cpus.is_some()
}

/// The policy of each robot's agent under `scheduler`, the robots given
/// by name and timing, in the scenario's order.
pub fn policies(scheduler: Scheduler, robots: &[(&str, Option<&Timing>)]) -> Vec<Policy> {
    match scheduler {
        Scheduler::Fair => vec![Policy::Other; robots.len()],
        Scheduler::Deadline => robots
            .iter()
            .map(|(_, t)| match t.and_then(|t| t.reservation) {
                Some(r) => Policy::Deadline {
                    runtime_ns: r.runtime_ns(),
                    period_ns: r.period_ns(),
                },
                None => Policy::Other,
            })
            .collect(),
        Scheduler::Fifo => {
            let tasks: Vec<Task> = robots
                .iter()
                .map(|(name, t)| Task {
                    name: name.to_string(),
                    period_ticks: t.map_or(1, |t| t.period_ticks),
                    priority: t.and_then(|t| t.priority),
                    reservation: None,
                })
                .collect();
            fifo_levels(&tasks)
                .into_iter()
                .map(|level| Policy::Fifo {
                    priority: level.min(WORLD_PRIORITY).saturating_sub(1).max(1),
                })
                .collect()
        }
    }
}

/// The world's own policy in a realtime run under `[world.cpus]`.
pub fn world_policy() -> Policy {
    Policy::Fifo {
        priority: WORLD_PRIORITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_scenario::timing::{Priority, Reservation};

    fn timing(period_ticks: u32, priority: Option<Priority>) -> Timing {
        Timing {
            period_ticks,
            priority,
            ..Timing::default()
        }
    }

    #[test]
    fn fifo_takes_the_model_s_levels_below_the_world() {
        let (a, b, c, d) = (
            timing(2, None),
            timing(1, Some(Priority::RateMonotonic)),
            timing(1, None),
            timing(5, Some(Priority::Level(40))),
        );
        let robots = [
            ("a", Some(&a)),
            ("c", Some(&b)),
            ("b", Some(&c)),
            ("d", Some(&d)),
            ("e", None),
        ];
        let p = policies(Scheduler::Fifo, &robots);
        let level = |i: usize| match p[i] {
            Policy::Fifo { priority } => priority,
            other => panic!("{other}"),
        };
        // Period 1 comes first in rate-monotonic order (99 in the model, 98
        // for real: the world is at 99), its robots a level each by name
        // ("b", "c", "e"), then period 2 ("a"); "d" keeps the order of its
        // own level.
        assert_eq!([level(2), level(1), level(4)], [98, 97, 96]);
        assert_eq!(level(0), 95);
        assert_eq!(level(3), 39);
        let first = timing(1, Some(Priority::Level(1)));
        let second = timing(1, Some(Priority::Level(2)));
        let p = policies(
            Scheduler::Fifo,
            &[("x", Some(&first)), ("y", Some(&second))],
        );
        assert_eq!(
            p,
            vec![Policy::Fifo { priority: 1 }, Policy::Fifo { priority: 1 }]
        );
    }

    #[test]
    fn deadline_gives_each_reservation_and_sched_other_to_a_robot_without_one() {
        let with = Timing {
            cpu: true,
            reservation: Some(Reservation {
                runtime_ms: 20.0,
                period_ms: 100.0,
            }),
            ..Timing::default()
        };
        let p = policies(Scheduler::Deadline, &[("a", Some(&with)), ("b", None)]);
        assert_eq!(
            p,
            vec![
                Policy::Deadline {
                    runtime_ns: 20_000_000,
                    period_ns: 100_000_000
                },
                Policy::Other
            ]
        );
        assert_eq!(
            policies(Scheduler::Fair, &[("a", Some(&with))]),
            vec![Policy::Other]
        );
    }
}
