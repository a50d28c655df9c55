//! `mrsim view --run ID`: the live page of a running world, and the
//! server `mrsim run --live` starts for its own run.
//!
//! The page is served by [`mrsim_live`] (a small synchronous HTTP server)
//! and fed by a read-only observer of the run, as `mrsim top` reads it:
//! over iceoryx2, or over Zenoh for a world elsewhere.

use anyhow::{Result, anyhow};
use mrsim_live::{Feed, LiveServer, Pump};
use mrsim_transport::Namespace;
use mrsim_transport::zenoh::ZenohOptions;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// How long the page is still served once the run has ended, so that every
/// open page shows the end.
pub const LINGER: Duration = Duration::from_secs(2);

/// Starts the live page's server on `addr` (e.g. `127.0.0.1:0`) and says
/// where on stderr; a refused address is bad input.
pub fn serve(addr: &str, feed: Feed) -> Result<LiveServer> {
    let parsed: SocketAddr = addr.parse().map_err(|e| {
        crate::exit::invalid(format!(
            "--live {addr}: not an address (IP:PORT, e.g. 127.0.0.1:8080): {e}"
        ))
    })?;
    let server =
        LiveServer::start(parsed, feed).map_err(|e| crate::exit::invalid(e.to_string()))?;
    if !parsed.ip().is_loopback() {
        eprintln!(
            "warning: the live page is served on {} and has no authentication: anyone who \
             can reach this address can watch the run",
            server.addr()
        );
    }
    eprintln!("live page: {}", server.url());
    Ok(server)
}

/// `mrsim view`: attaches to run `run_id` (over Zenoh with `zenoh`) and
/// serves its live page until the run ends or Ctrl-C. Returns the exit
/// status.
pub fn run(run_id: &str, timeout: f64, zenoh: Option<ZenohOptions>, addr: &str) -> Result<i32> {
    let ns = Namespace::new(run_id).map_err(|e| crate::exit::invalid(e.to_string()))?;
    let feed = Feed::new();
    let server = serve(addr, feed.clone())?;
    let timeout = Duration::from_secs_f64(timeout.max(0.0));
    let mut obs = mrsim_top::connect_observer(&ns, "view", zenoh.as_ref(), timeout)?;
    mrsim_sys::signal::catch_termination();
    let mut pump = Pump::new(feed.clone());
    let started = Instant::now();
    while !pump.ended() {
        pump.pump(obs.as_mut())
            .map_err(|e| anyhow!("run `{run_id}`: {e}"))?;
        if mrsim_sys::signal::received().is_some() {
            feed.end("the viewer was stopped");
            break;
        }
        if feed.seq() == 0 && started.elapsed() > timeout && !obs.world_alive() {
            feed.end("the world is gone");
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(LINGER);
    drop(server);
    Ok(0)
}
