//! Joining a run: one join request (with its own nonce) per robot, re-asked
//! until the world answers, then the run's setup read and parsed once and a
//! [`Seat`] built for each robot. One robot joins as a group of one.
//!
//! Each robot's request carries this process's pid, so the world gives each
//! robot its own token and judges its commands on their own, and loses
//! every robot this process joined when the process dies.

use crate::seat::{self, Seat, SetupView};
use crate::{AgentError, AgentOptions, fault};
use mrsim_proto::{FixedStr, JoinReply, JoinRequest, now_ns};
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

/// Joins the run as `opts.robot` and reads the run's setup: [`join_seats`]
/// for one robot. `None` if the process was asked to stop meanwhile.
pub(crate) fn join_seat(
    link: &mut dyn AgentTransport,
    opts: &AgentOptions,
) -> Result<Option<Seat>, AgentError> {
    Ok(join_seats(link, std::slice::from_ref(opts))?.and_then(|mut s| s.pop()))
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
            group: u32::try_from(opts.len()).unwrap_or(u32::MAX),
        })
        .collect();
    let mut replies: Vec<Option<JoinReply>> = vec![None; opts.len()];
    let mut waiting: Vec<usize> = (0..opts.len()).collect();
    let start = Instant::now();
    let mut last_ask: Option<Instant> = None;
    // Unanswered requests are asked again after half a second, then after
    // twice as long each time (up to 8 s): a world busy answering 100,000
    // robots' requests is not sent every one of them again twice a second.
    let mut ask_every = Duration::from_millis(500);
    loop {
        if link.termination_requested() {
            return Ok(None);
        }
        if last_ask.is_none_or(|t| t.elapsed() > ask_every) {
            if last_ask.is_some() {
                ask_every = (ask_every * 2).min(Duration::from_secs(8));
            }
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
    let walls = seat::walls(&view);
    let shapes = seat::shapes(&view)?;
    replies
        .iter()
        .zip(opts)
        .map(|(r, o)| match r {
            Some(r) => seat::seat_of(&view, &walls, &shapes, r, o),
            None => Err(AgentError::BadSetup("a join without its reply".to_string())),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}
