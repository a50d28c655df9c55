//! Zenoh between a world and agents started here: where the world listens
//! and where the agents connect.

use super::LaunchError;
use crate::error::Invalid;
use mrsim_transport::zenoh::ZenohOptions;

/// A loopback endpoint on a port free a moment ago.
pub(super) fn free_loopback_endpoint() -> Result<String, LaunchError> {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map_err(|e| Invalid(format!("cannot find a free loopback port for zenoh: {e}")))?
        .port();
    Ok(format!("tcp/127.0.0.1:{port}"))
}

/// Where a process on this machine connects to reach a world listening on
/// `listen` (loopback when it listens on every address).
pub(super) fn loopback_of(listen: &str) -> String {
    listen
        .replace("0.0.0.0", "127.0.0.1")
        .replace("[::]", "[::1]")
}

/// Where the world of a Zenoh run started here listens (a free loopback
/// port unless given) and where its agents connect (the same place,
/// loopback when the world listens on every address), both with the
/// config file.
pub(super) fn zenoh_sides(
    opts: &ZenohOptions,
) -> Result<(ZenohOptions, ZenohOptions), LaunchError> {
    let listen = match &opts.endpoint {
        Some(e) => e.clone(),
        None => free_loopback_endpoint()?,
    };
    let connect = loopback_of(&listen);
    let side = |endpoint: String| ZenohOptions {
        endpoint: Some(endpoint),
        config_file: opts.config_file.clone(),
    };
    Ok((side(listen), side(connect)))
}
