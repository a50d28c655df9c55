//! Several robots driven by one agent (`mrsim agent --robots a0,a1,...`,
//! and the in-process pool's joins): one transport, one copy of the setup
//! read once, one wait per snapshot, and per robot its own join token,
//! observation and planner, exactly as if each had a process of its own.
//!
//! Each robot joins with a request of its own (its own nonce), so the world
//! gives each its own token and judges each robot's commands on their own;
//! the group only shares the process. When the process dies, the world
//! loses every robot it drove (each one's join carried the process's pid),
//! and a restarted process joins them all again.
//!
//! The observations of a group of more than one robot look only at the
//! bodies a neighbour grid (`mrsim-spatial`, one built per snapshot) puts
//! near each robot: the same bodies in the same order as a full scan, so
//! the commands are those of one process per robot.

use crate::live::STOP_CHECK_EVERY_NS;
use crate::seat::{Seat, SetupView};
use crate::{AgentError, AgentExit, AgentOptions, Driver, fault};
use mrsim_proto::{BodyState, FixedStr, JoinReply, JoinRequest, SnapshotHeader, now_ns};
use mrsim_spatial::NeighbourGrid;
use mrsim_transport::AgentTransport;
use std::time::{Duration, Instant};

/// A join nonce for robot `name`: the clock, the process and the name
/// mixed, so that robots joining at once from one process (or from threads
/// of one process) ask with different nonces.
fn nonce(name: &str, i: usize) -> u64 {
    let mut x = now_ns() ^ ((std::process::id() as u64) << 20) ^ 0x6d72_7369_6d00_0000;
    for b in name.bytes().chain((i as u64).to_le_bytes()) {
        x = (x ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
    }
    // splitmix64's finaliser: nearby inputs give unrelated nonces.
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Joins the run as every robot of `opts` (see [`join_seats`]) and returns
/// their [`Driver`]s, each with the planner its scenario entry names (from
/// its options' registry), in the order of `opts`, ready for the first
/// snapshot. `None` if the process was asked to stop meanwhile.
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

/// Joins the run as every robot of `opts` (one request each, re-asked
/// until the world answers), reads the run's setup once, and returns their
/// seats in the order of `opts`. `None` if the process was asked to stop
/// meanwhile. The first robot refused fails the whole group; the join
/// timeout is the first robot's.
pub(crate) fn join_seats(
    link: &mut dyn AgentTransport,
    opts: &[AgentOptions],
) -> Result<Option<Vec<Seat>>, AgentError> {
    let Some(first) = opts.first() else {
        return Ok(Some(Vec::new()));
    };
    let timeout = first.join_timeout;
    let reqs: Vec<JoinRequest> = opts
        .iter()
        .enumerate()
        .map(|(i, o)| JoinRequest {
            protocol_version: o.protocol_version,
            pid: std::process::id(),
            nonce: nonce(&o.robot, i),
            robot: FixedStr::new(&o.robot),
        })
        .collect();
    let mut replies: Vec<Option<JoinReply>> = vec![None; opts.len()];
    let mut waiting: Vec<usize> = (0..opts.len()).collect();
    let start = Instant::now();
    let mut last_ask: Option<Instant> = None;
    loop {
        if link.termination_requested() {
            return Ok(None);
        }
        if last_ask.is_none_or(|t| t.elapsed() > Duration::from_millis(500)) {
            for &i in &waiting {
                if last_ask.is_none() && opts[i].fault == Some(fault::Fault::JoinTwice) {
                    link.request_join(&reqs[i])?;
                }
                link.request_join(&reqs[i])?;
            }
            last_ask = Some(Instant::now());
        }
        let mut failed = None;
        waiting.retain(|&i| match link.poll_join_reply(reqs[i].nonce) {
            Ok(Some(r)) => {
                replies[i] = Some(r);
                false
            }
            Ok(None) => true,
            Err(e) => {
                failed.get_or_insert(e);
                true
            }
        });
        if let Some(e) = failed {
            return Err(e.into());
        }
        if let Some((i, r)) = replies
            .iter()
            .enumerate()
            .find_map(|(i, r)| r.filter(|r| r.accepted == 0).map(|r| (i, r)))
        {
            return Err(AgentError::Refused {
                robot: opts[i].robot.clone(),
                reason: r.reason.as_str().to_string(),
            });
        }
        if waiting.is_empty() {
            break;
        }
        if start.elapsed() > timeout {
            return Err(AgentError::Timeout {
                what: "join reply",
                secs: timeout.as_secs_f64(),
            });
        }
        link.wait(Duration::from_millis(50))?;
    }

    // Setup: the resolved scenario, from the world; read and parsed once.
    let setup = loop {
        if let Some(s) = link.setup()? {
            break s;
        }
        if start.elapsed() > timeout {
            return Err(AgentError::Timeout {
                what: "setup",
                secs: timeout.as_secs_f64(),
            });
        }
        link.wait(Duration::from_millis(20))?;
    };
    let view: SetupView =
        serde_json::from_slice(&setup).map_err(|e| AgentError::BadSetup(e.to_string()))?;
    let walls = crate::seat::walls(&view);
    replies
        .iter()
        .zip(opts)
        .map(|(r, o)| match r {
            Some(r) => crate::seat::seat_of(&view, &walls, r, o),
            None => Err(AgentError::BadSetup("a join without its reply".to_string())),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}

/// Joins the run as every robot of `opts` and drives them until the world
/// ends the run, the process is asked to stop, or something fails (the
/// first robot's failure ends the group: its process is one agent).
pub fn run_group(
    link: &mut dyn AgentTransport,
    opts: &[AgentOptions],
) -> Result<AgentExit, AgentError> {
    let Some(mut drivers) = join_group(link, opts)? else {
        return Ok(AgentExit::Interrupted);
    };
    let world_check_after = opts
        .first()
        .map_or(Duration::from_millis(300), |o| o.world_check_after);
    for d in &drivers {
        link.send_command(&d.ready())?;
    }
    link.joined();
    let finish = |drivers: Vec<Driver>, exit| {
        let mut result = Ok(exit);
        for d in drivers {
            let r = d.finish(exit);
            if result.is_ok() {
                result = r;
            }
        }
        result
    };
    // The grid is built (once per snapshot) only for a group of robots
    // that all sense within a finite reach.
    let reach = drivers
        .iter()
        .map(Driver::reach)
        .try_fold(0.0_f64, |m, r| r.map(|r| m.max(r)))
        .filter(|_| drivers.len() > 1);
    let mut grid = NeighbourGrid::default();
    let mut near = Vec::new();
    // Where a transport that cannot lend its snapshot copies it.
    let capacity = drivers.first().map_or(0, Driver::capacity);
    let mut scratch = (
        SnapshotHeader::default(),
        Vec::<BodyState>::with_capacity(capacity),
    );
    // When the last snapshot came (the clock read as the agent woke for
    // it: one clock read a tick fewer).
    let mut last_heard = now_ns();
    // A snapshot has come (after it, a wake-up without one is spurious).
    let mut heard_one = false;
    let check_after = u64::try_from(world_check_after.as_nanos()).unwrap_or(u64::MAX);
    // When the agent last asked whether it is to stop (over iceoryx2 the
    // question takes a process-wide lock: asked every few ticks, not
    // every tick).
    let mut asked_to_stop_at = 0;
    let mut woke = last_heard;
    loop {
        if woke.saturating_sub(asked_to_stop_at) >= STOP_CHECK_EVERY_NS {
            asked_to_stop_at = woke;
            if link.termination_requested() {
                return finish(drivers, AgentExit::Interrupted);
            }
        }
        link.wait(Duration::from_millis(100))?;
        woke = now_ns();
        let (mut finished, mut failed) = (false, None);
        let got = link.with_latest_snapshot(&mut scratch, &mut |header, bodies, send| {
            heard_one = true;
            if header.finished != 0 {
                finished = true;
                return;
            }
            let gridded = reach.is_some_and(|r| {
                grid.build(
                    bodies
                        .iter()
                        .map(|b| [b.position[0], b.position[1], b.radius]),
                    r,
                )
            });
            for d in &mut drivers {
                let among = gridded
                    && match (d.reach(), d.position(bodies)) {
                        (Some(r), Some(p)) => grid.near(p, r, &mut near),
                        _ => false,
                    };
                let near = among.then_some(near.as_slice());
                if let Err(e) = d.on_snapshot_among(header, bodies, near, woke, None, send) {
                    failed = Some(e);
                    return;
                }
            }
        })?;
        if !got {
            if woke.saturating_sub(last_heard) > check_after && !link.world_alive() {
                return Err(AgentError::WorldGone);
            }
            if !heard_one {
                // Before the first snapshot a wake-up is the world's
                // call to take up the tick's channels (this receive just
                // did): say ready again, and the world starts the clock
                // once every agent has (`WorldTransport::prepare_ticks`).
                for d in &drivers {
                    link.send_command(&d.ready())?;
                }
            }
            continue;
        }
        last_heard = woke;
        if let Some(e) = failed {
            return Err(e);
        }
        if finished {
            return finish(drivers, AgentExit::Finished);
        }
    }
}
