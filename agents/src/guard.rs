//! The one check at every plan call: a planner that panics or returns a
//! non-finite command fails its robot at that tick, with an error naming
//! both, instead of taking down the thread (and with it an in-process
//! world) or sending the world a command it can only refuse.
//!
//! The release profile unwinds on panic (the workspace sets no
//! `panic = "abort"`), so the panic is caught at the call; the planner's
//! state after it is not trusted again (the robot answers no more in
//! lockstep).

use mrsim_planners::{Command, Observation, Planner};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

/// How a planner failed at one tick.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanFault {
    /// `plan` panicked; the panic's message.
    #[error("the planner panicked: {0}")]
    Panicked(String),
    /// `plan` returned a command with a NaN or infinite component.
    #[error("the planner returned a non-finite command {0:?}")]
    NonFinite(Command),
    /// `plan` had not returned after the run's limit (in-process runs with
    /// a plan timeout: the run's watchdog stops the run without it).
    #[error("the planner did not return within the limit of {:.3} s", .0.as_secs_f64())]
    TimedOut(std::time::Duration),
}

/// A planner's failure: which robot, which tick, how.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("robot `{robot}` at tick {tick}: {what}")]
pub struct PlanFailure {
    /// The robot's name.
    pub robot: String,
    /// The tick whose observation it failed on.
    pub tick: u64,
    /// How.
    pub what: PlanFault,
}

/// Calls `planner.plan(obs)`, catching a panic and refusing a non-finite
/// command.
pub fn plan_checked(planner: &mut dyn Planner, obs: &Observation) -> Result<Command, PlanFault> {
    let cmd = std::panic::catch_unwind(AssertUnwindSafe(|| planner.plan(obs))).map_err(|p| {
        let msg = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "(no message)".to_string());
        PlanFault::Panicked(msg)
    })?;
    let v = cmd.vector();
    if v.x.is_finite() && v.y.is_finite() {
        Ok(cmd)
    } else {
        Err(PlanFault::NonFinite(cmd))
    }
}

/// How an in-process lockstep run hears that a planner failed: the run's
/// stop flag (what its world reads as a termination request) is raised and
/// the first failure kept, so the run ends with the outputs so far written
/// and its caller can name the robot and the tick.
#[derive(Debug, Clone)]
pub struct Halt {
    stop: Arc<AtomicBool>,
    first: Arc<Mutex<Option<PlanFailure>>>,
}

impl Halt {
    /// A halt that raises `stop`.
    pub fn new(stop: Arc<AtomicBool>) -> Self {
        Self {
            stop,
            first: Arc::default(),
        }
    }

    /// Notes `failure` (the first one is kept) and stops the run.
    pub fn raise(&self, failure: &PlanFailure) {
        self.first
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get_or_insert_with(|| failure.clone());
        self.stop.store(true, Ordering::SeqCst);
    }

    /// The first failure raised, if any.
    pub fn failure(&self) -> Option<PlanFailure> {
        self.first
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_planners::{SelfState, Vec2};

    struct Fixed(Option<Command>);
    impl Planner for Fixed {
        fn plan(&mut self, _obs: &Observation) -> Command {
            self.0.expect("no command planned")
        }
    }

    fn obs() -> Observation<'static> {
        Observation {
            tick: 3,
            time: 0.3,
            dt: 0.1,
            me: SelfState {
                id: 0,
                position: Vec2::zeros(),
                velocity: Vec2::zeros(),
                radius: 0.0,
                shape: mrsim_planners::Shape::disc(0.0),
                mass: 1.0,
                damping: 0.0,
                max_speed: 1.0,
                max_accel: 1.0,
                heading: 0.0,
                angular_velocity: 0.0,
                steering: 0.0,
                kinematics: mrsim_planners::Kinematics::Holonomic,
            },
            goal: Vec2::new(1.0, 0.0),
            goal_tolerance: 0.1,
            goal_hold_ticks: 1,
            others: &[],
            walls: &[],
            path: None,
            scan: None,
        }
    }

    #[test]
    fn a_finite_command_passes_and_a_nan_or_a_panic_is_a_fault() {
        let ok = Command::Force(Vec2::new(1.0, 2.0));
        assert_eq!(plan_checked(&mut Fixed(Some(ok)), &obs()), Ok(ok));
        let nan = Command::Velocity(Vec2::new(f64::NAN, 0.0));
        assert!(matches!(
            plan_checked(&mut Fixed(Some(nan)), &obs()),
            Err(PlanFault::NonFinite(_))
        ));
        let inf = Command::Force(Vec2::new(0.0, f64::INFINITY));
        assert!(plan_checked(&mut Fixed(Some(inf)), &obs()).is_err());
        match plan_checked(&mut Fixed(None), &obs()) {
            Err(PlanFault::Panicked(m)) => assert!(m.contains("no command planned"), "{m}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_halt_keeps_the_first_failure_and_raises_the_stop_flag() {
        let stop = Arc::new(AtomicBool::new(false));
        let halt = Halt::new(stop.clone());
        assert_eq!(halt.failure(), None);
        let f = |robot: &str| PlanFailure {
            robot: robot.into(),
            tick: 4,
            what: PlanFault::Panicked("boom".into()),
        };
        halt.raise(&f("a"));
        halt.clone().raise(&f("b"));
        assert!(stop.load(Ordering::SeqCst));
        assert_eq!(halt.failure(), Some(f("a")));
        assert_eq!(
            f("a").to_string(),
            "robot `a` at tick 4: the planner panicked: boom"
        );
    }
}
