//! The Zenoh transport: the world and its agents on different machines.
//!
//! The world opens a Zenoh session in peer mode and listens (by default on
//! loopback only, `tcp/127.0.0.1:7447`); agents and observers open client
//! sessions that connect to it (or to the routers of a user's config). All
//! keys are under the run id ([`keys`]):
//!
//! | key | what | from -> to |
//! | --- | --- | --- |
//! | `mrsim/<run>/setup` | queryable: the resolved scenario as JSON | world -> agents, observers |
//! | `mrsim/<run>/snapshot` | `SnapshotHeader` + `[BodyState]` + tag ([`seal`]), one per tick | world -> agents |
//! | `mrsim/<run>/join` | `JoinRequest` | agents -> world |
//! | `mrsim/<run>/join-reply` | `JoinReply` (+ the run's snapshot key if accepted; each agent keeps its nonce's) | world -> agents |
//! | `mrsim/<run>/command` | `CommandMsg` (and ready messages) | agents -> world |
//! | `mrsim/<run>/stats` | `StatsHeader` + `[RobotStats]` | world -> observers |
//! | `mrsim/<run>/alive/world` | liveliness token of the world | |
//! | `mrsim/<run>/alive/agent/<pid>` | liveliness token of an agent process | |
//!
//! The protocol is the one of shared memory (join with a token, version
//! check, refusals with a reason, commands only for the current tick),
//! judged by the same world loop; only the bytes differ ([`wire`]: fields in
//! order, little endian, length checked before anything is read).
//!
//! **Liveness** comes from Zenoh's liveliness tokens, not process ids: the
//! world's is what an agent watches, an agent's is what the world asks
//! about in [`WorldTransport::agent_alive`](crate::WorldTransport::agent_alive).
//! A token disappears when its process ends or when its session's lease
//! runs out (a vanished host, a cut link).
//!
//! **Time**: every latency the world records is measured on the world's
//! own clock (publish to receipt, the receipt stamped when the message is
//! taken off the network); two hosts' clocks are never compared. An
//! agent's `woke_ns`/`sent_ns` are its own clock's and are meaningful
//! only when it runs on the world's host.
//!
//! All calls are blocking (Zenoh's `Wait`); Zenoh runs its own I/O threads
//! and hands received messages to callbacks that fill a small inbox per
//! side ([`inbox`]), which the world's and agents' loops drain.
//!
//! **Refusals** are counted by the world ([`NetworkCounts`], for
//! metrics.json): messages that do not decode, a flood beyond the inbox
//! (commands with a token the world gave have a share of their own, which
//! forged ones cannot fill), and connections Zenoh refused for failed
//! authentication (which only Zenoh's log tells of: `auth` listens to it).
//! Snapshots are signed with a key of the run ([`seal`]); an agent counts
//! and drops those whose tag does not check.
//!
//! One module per side: `world` ([`ZenohWorld`]), `agent`
//! ([`ZenohAgent`]), `observer` ([`ZenohObserver`]); they share `keys`,
//! `wire`, `inbox` and the session configuration here.

mod agent;
mod auth;
#[cfg(test)]
mod fuzz;
mod inbox;
pub mod keys;
mod observer;
pub mod seal;
#[cfg(test)]
mod tests;
pub mod wire;
mod world;

pub use crate::NetworkCounts;
pub use agent::ZenohAgent;
pub use observer::ZenohObserver;
pub use world::ZenohWorld;

use crate::TransportError;
use std::path::PathBuf;

/// Where the world listens unless told otherwise: loopback only.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// The environment variable Zenoh's runtime takes its threads from, read
/// once, when the process opens its first session.
pub const RUNTIME_ENV: &str = "ZENOH_RUNTIME";

/// Threads for Zenoh's runtime that [`default_runtime`] sets, and that
/// every `mrsim agent` process takes unless [`RUNTIME_ENV`] is set: links
/// are read, and connections accepted, on the application runtime's
/// thread instead of runtimes of their own. A link's socket is registered
/// with the runtime that opened or accepted it (the application's for a
/// client, the acceptor's for a listener), so by default every message
/// wakes that runtime's thread, which wakes a receiving thread, and
/// Zenoh's default two receiving threads wake each other: on one runtime,
/// the thread that sees the socket ready reads it and runs the callback.
/// An agent reads one link, its world's.
pub const RUNTIME: &str = "(rx: (handover: app), acc: (handover: app))";

/// Threads for Zenoh's runtime that [`world_runtime`] sets, and that
/// every `mrsim world` process takes unless [`RUNTIME_ENV`] is set:
/// connections are accepted on the receiving runtime (Zenoh's two threads
/// by default), so an agent's socket is watched by the threads that read
/// it, and a message no longer wakes the acceptor's thread first.
///
/// The world does not read its links on one thread ([`RUNTIME`], or one
/// receiving thread): it reads every agent's link, and with all of them
/// on one thread, once Zenoh closed the transport of an agent whose lease
/// ran out (a cut link), no other link was read again: the other agents'
/// commands stopped arriving, the other agents behind the cut were never
/// counted lost (nor rejoined), and the world's next snapshot blocked in
/// Zenoh's send to a dead link whose socket had filled. With Zenoh's two
/// receiving threads they are lost and rejoin.
pub const WORLD_RUNTIME: &str = "(acc: (handover: rx))";

/// Gives Zenoh's runtime [`RUNTIME`] (an agent's threads) unless the
/// environment already says what it is to be.
///
/// # Safety
///
/// Sets an environment variable: call it before the process has started
/// any other thread (first thing in `main`).
pub unsafe fn default_runtime() {
    // SAFETY: the caller's promise.
    unsafe { runtime_unless_set(RUNTIME) };
}

/// Gives Zenoh's runtime [`WORLD_RUNTIME`] (the world's threads) unless
/// the environment already says what it is to be.
///
/// # Safety
///
/// As [`default_runtime`]: before the process has started any other thread.
pub unsafe fn world_runtime() {
    // SAFETY: the caller's promise.
    unsafe { runtime_unless_set(WORLD_RUNTIME) };
}

/// Sets [`RUNTIME_ENV`] to `threads` unless it is set.
///
/// # Safety
///
/// As [`default_runtime`].
unsafe fn runtime_unless_set(threads: &str) {
    if std::env::var_os(RUNTIME_ENV).is_none() {
        // SAFETY: no other thread reads the environment (the caller's
        // promise).
        unsafe { std::env::set_var(RUNTIME_ENV, threads) };
    }
}

/// How to reach the other side.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ZenohOptions {
    /// The world: the endpoint to listen on; an agent or observer: the
    /// endpoint to connect to (`tcp/HOST:PORT`, or `tls/HOST:PORT` with a
    /// TLS config). `None`: the config file's endpoints if one is given,
    /// else [`DEFAULT_ENDPOINT`].
    pub endpoint: Option<String>,
    /// A Zenoh JSON5 config (TLS, user/password auth, routers, lease).
    pub config_file: Option<PathBuf>,
}

/// The side a session is opened for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// The world, whose largest message (snapshot, statistics or setup)
    /// is this many bytes.
    World { largest_message: usize },
    /// An agent, observer or other client.
    Client,
}

/// Largest message that Zenoh's low-latency transport carries (it does
/// not fragment: a message must fit one batch, 65535 bytes by default,
/// with room for Zenoh's own framing).
const LOW_LATENCY_MAX: usize = 60_000;

/// How long a session may be silent before the other side counts it gone
/// (when no config file says otherwise): a vanished agent's token goes
/// this long after its last message.
const LEASE_MS: u64 = 3000;

/// Builds the session config of `role` from `opts`.
fn config(opts: &ZenohOptions, role: Role) -> Result<zenoh::Config, TransportError> {
    let err = |detail: String| TransportError::Setup {
        what: "zenoh config".to_string(),
        detail,
    };
    let mut cfg = match &opts.config_file {
        Some(path) => {
            zenoh::Config::from_file(path).map_err(|e| err(format!("{}: {e}", path.display())))?
        }
        None => zenoh::Config::default(),
    };
    let set = |cfg: &mut zenoh::Config, key: &str, value: &str| {
        cfg.insert_json5(key, value)
            .map_err(|e| err(format!("{key} = {value}: {e}")))
    };
    let mode = match role {
        Role::World { .. } => r#""peer""#,
        Role::Client => r#""client""#,
    };
    set(&mut cfg, "mode", mode)?;
    // Zenoh's low-latency transport writes each message from the sending
    // thread (no hand-over to a transmit task, no batching, no priority
    // lanes): used when both sides ask for it, so clients always ask and
    // the world only when every message of its run fits one batch. A
    // config file decides for itself.
    let low_latency = match role {
        Role::World { largest_message } => largest_message <= LOW_LATENCY_MAX,
        Role::Client => true,
    };
    if opts.config_file.is_none() && low_latency {
        set(&mut cfg, "transport/unicast/qos/enabled", "false")?;
        set(&mut cfg, "transport/unicast/lowlatency", "true")?;
    }
    // A run is found by its address, never by multicast: two runs on one
    // network, or a lab's other Zenoh programs, must not meet by chance.
    set(&mut cfg, "scouting/multicast/enabled", "false")?;
    if opts.config_file.is_none() {
        set(&mut cfg, "transport/link/tx/lease", &LEASE_MS.to_string())?;
    }
    let endpoint = match (&opts.endpoint, &opts.config_file) {
        (Some(e), _) => Some(e.clone()),
        (None, None) => Some(DEFAULT_ENDPOINT.to_string()),
        (None, Some(_)) => None,
    };
    if let Some(e) = endpoint {
        let list = serde_json_list(&e);
        match role {
            Role::World { .. } => set(&mut cfg, "listen/endpoints", &list)?,
            Role::Client => set(&mut cfg, "connect/endpoints", &list)?,
        }
    }
    if matches!(role, Role::World { .. }) {
        // The world is nobody's client: no connecting out unless a config
        // file asks for routers.
        if opts.config_file.is_none() {
            set(&mut cfg, "connect/endpoints", "[]")?;
        }
    }
    Ok(cfg)
}

/// `["ENDPOINT"]` with the endpoint's quotes and backslashes escaped.
fn serde_json_list(endpoint: &str) -> String {
    let escaped: String = endpoint
        .chars()
        .flat_map(|c| match c {
            '"' | '\\' => vec!['\\', c],
            c => vec![c],
        })
        .collect();
    format!(r#"["{escaped}"]"#)
}

/// Opens a session of `role`.
fn open(opts: &ZenohOptions, role: Role) -> Result<zenoh::Session, TransportError> {
    use zenoh::Wait;
    let cfg = config(opts, role)?;
    zenoh::open(cfg).wait().map_err(|e| TransportError::Setup {
        what: match role {
            Role::World { .. } => format!(
                "zenoh session listening on {}",
                opts.endpoint.as_deref().unwrap_or(DEFAULT_ENDPOINT)
            ),
            Role::Client => format!(
                "zenoh session to {}",
                opts.endpoint.as_deref().unwrap_or(DEFAULT_ENDPOINT)
            ),
        },
        detail: e.to_string(),
    })
}

/// Publishes each of `payloads` on `key` as any Zenoh client on the
/// network could (garbage, another run's messages, a flood), then asks the
/// world of run `ns` for its setup over the same connection, so that
/// everything sent has reached it on return. For tests and for probing a
/// world; mrsim itself never calls it.
pub fn publish_raw(
    opts: &ZenohOptions,
    ns: &crate::Namespace,
    key: &str,
    payloads: &[Vec<u8>],
) -> Result<(), TransportError> {
    use zenoh::Wait;
    let session = open(opts, Role::Client)?;
    let publisher = session
        .declare_publisher(key.to_string())
        .congestion_control(zenoh::qos::CongestionControl::Block)
        .wait()
        .map_err(|e| declare_err("raw publisher", e))?;
    for p in payloads {
        publisher
            .put(p.clone())
            .wait()
            .map_err(|e| send_err("raw message", e))?;
    }
    agent::query_setup(&session, &keys::Keys::new(ns))?;
    Ok(())
}

/// A declaration failed.
fn declare_err(what: &str, e: impl std::fmt::Display) -> TransportError {
    TransportError::Setup {
        what: format!("zenoh {what}"),
        detail: e.to_string(),
    }
}

/// A send failed.
fn send_err(what: &'static str, e: impl std::fmt::Display) -> TransportError {
    TransportError::Send {
        what,
        detail: e.to_string(),
    }
}

/// True once SIGINT or SIGTERM came (as the shared-memory sides ask).
fn terminated(seen: &std::cell::Cell<bool>) -> bool {
    if !seen.get() && iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        seen.set(true);
    }
    seen.get()
}

#[cfg(test)]
mod config_tests {
    use super::*;

    const WORLD: Role = Role::World {
        largest_message: 1000,
    };

    #[test]
    fn a_world_whose_messages_fit_a_batch_asks_for_low_latency_a_larger_one_not() {
        let small = config(&ZenohOptions::default(), WORLD).unwrap();
        assert_eq!(
            small.get_json("transport/unicast/lowlatency").unwrap(),
            "true"
        );
        let large = Role::World {
            largest_message: 1 << 20,
        };
        let large = config(&ZenohOptions::default(), large).unwrap();
        assert_eq!(
            large.get_json("transport/unicast/lowlatency").unwrap(),
            "false"
        );
        let client = config(&ZenohOptions::default(), Role::Client).unwrap();
        assert_eq!(
            client.get_json("transport/unicast/lowlatency").unwrap(),
            "true"
        );
    }

    #[test]
    fn the_world_listens_on_loopback_unless_told() {
        let cfg = config(&ZenohOptions::default(), WORLD).unwrap();
        let listen = cfg.get_json("listen/endpoints").unwrap();
        assert!(listen.contains("127.0.0.1:7447"), "{listen}");
    }

    #[test]
    fn an_agent_connects_where_it_is_told_as_a_client() {
        let opts = ZenohOptions {
            endpoint: Some("tcp/10.0.0.2:9000".to_string()),
            config_file: None,
        };
        let cfg = config(&opts, Role::Client).unwrap();
        assert!(
            cfg.get_json("connect/endpoints")
                .unwrap()
                .contains("10.0.0.2:9000")
        );
        assert!(cfg.get_json("mode").unwrap().contains("client"));
    }

    #[test]
    fn a_missing_config_file_is_an_error_naming_it() {
        let opts = ZenohOptions {
            endpoint: None,
            config_file: Some("/nonexistent/zenoh.json5".into()),
        };
        let e = config(&opts, WORLD).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/zenoh.json5"), "{e}");
    }
}
