//! Several robots driven by one agent (`mrsim agent --robots a0,a1,...`,
//! and the in-process pool's joins): one transport, one copy of the setup
//! read once, one wait per snapshot, and per robot its own join token,
//! observation and planner, exactly as if each had a process of its own.
//!
//! Each robot joins with a request of its own (`join.rs`), so the
//! world gives each its own token and judges each robot's commands on their
//! own; the group only shares the process. When the process dies, the world
//! loses every robot it drove (each one's join carried the process's pid),
//! and a restarted process joins them all again. The loop that drives them
//! is [`crate::Live`]'s, the same as for one robot.

use crate::join::join_seats;
use crate::live::{Live, drive_each};
use crate::{AgentError, AgentExit, AgentOptions, Driver};
use mrsim_planners::Planner;
use mrsim_transport::AgentTransport;
use std::time::Duration;

/// Joins the run as every robot of `opts` (one join request each, the
/// setup read once) and returns their [`Driver`]s, each with the planner
/// its scenario entry names (from its options' registry), in the order of
/// `opts`, ready for the first snapshot. `None` if the process was asked to
/// stop meanwhile. The first robot refused fails the whole group; the join
/// timeout is the first robot's.
pub fn join_group(
    link: &mut dyn AgentTransport,
    opts: &[AgentOptions],
) -> Result<Option<Vec<Driver>>, AgentError> {
    let Some(seats) = join_seats(link, opts)? else {
        return Ok(None);
    };
    seats
        .into_iter()
        .zip(opts)
        .map(|(seat, o)| {
            let planner = seat.build_planner(&o.registry)?;
            Ok(Driver { seat, planner })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}

/// Joins the run as every robot of `opts` (one join request each, the
/// setup read once) and tells the world they are ready: a [`Live`] whose
/// ticks the caller answers ([`Live::next`], [`Live::reply`]) with commands
/// of its own (the ROS 2 agent's: what a ROS 2 node sent). `None` if the
/// process was asked to stop meanwhile.
pub fn join_live(
    link: &mut dyn AgentTransport,
    opts: &[AgentOptions],
) -> Result<Option<Live>, AgentError> {
    let Some(seats) = join_seats(link, opts)? else {
        return Ok(None);
    };
    let world_check_after = opts
        .first()
        .map_or(Duration::from_millis(300), |o| o.world_check_after);
    Live::start(link, seats, world_check_after).map(Some)
}

/// Joins the run as every robot of `opts` and drives them until the world
/// ends the run, the process is asked to stop, or something fails (the
/// first robot's failure ends the group: its process is one agent).
pub fn run_group(
    link: &mut dyn AgentTransport,
    opts: &[AgentOptions],
) -> Result<AgentExit, AgentError> {
    let Some(seats) = join_seats(link, opts)? else {
        return Ok(AgentExit::Interrupted);
    };
    take_policy(&seats)?;
    let mut planners = seats
        .iter()
        .zip(opts)
        .map(|(seat, o)| seat.build_planner(&o.registry))
        .collect::<Result<Vec<_>, _>>()?;
    let world_check_after = opts
        .first()
        .map_or(Duration::from_millis(300), |o| o.world_check_after);
    let mut live = Live::start(link, seats, world_check_after)?;
    let mut each: Vec<&mut dyn Planner> = planners.iter_mut().map(|p| &mut **p as _).collect();
    let exit = drive_each(link, &mut live, &mut each)?;
    live.finish(exit)
}

/// Realtime under `[world.cpus]`: the calling thread, which plans, takes
/// its robot's scheduling policy ([`crate::cores`]), SIGXCPU counted first
/// under SCHED_DEADLINE. One robot per process: a thread has one policy.
fn take_policy(seats: &[crate::seat::Seat]) -> Result<(), AgentError> {
    let Some(first) = seats.iter().find(|s| s.policy.is_some()) else {
        return Ok(());
    };
    let robot = first.spec.name.clone();
    let scheduling = |why: String| AgentError::Scheduling {
        robot: robot.clone(),
        why,
    };
    if seats.len() > 1 {
        return Err(scheduling(format!(
            "realtime under [world.cpus] each robot's agent takes its own scheduling \
             policy, and this process drives {} robots: start one agent per robot",
            seats.len()
        )));
    }
    let Some(policy) = first.policy else {
        return Ok(());
    };
    if matches!(policy, mrsim_sys::policy::Policy::Deadline { .. }) {
        mrsim_sys::policy::count_overruns()
            .map_err(|e| scheduling(format!("cannot count overruns (SIGXCPU): {e}")))?;
    }
    mrsim_sys::policy::set_policy(policy).map_err(|e| scheduling(e.to_string()))
}
