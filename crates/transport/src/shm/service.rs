//! What every side of the shared-memory transport shares: the run's
//! iceoryx2 configuration and nodes, service names, the wait on an
//! iceoryx2 listener, the termination flag, and the subscribers an agent
//! and an observer both open.

use crate::{Namespace, TransportError};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use mrsim_proto::{BodyState, SnapshotHeader};
use std::os::unix::fs::PermissionsExt;
use std::time::Duration;

/// The iceoryx2 service kind of every port: between processes.
pub(super) type S = ipc::Service;

/// Name of the world's iceoryx2 node.
pub const WORLD_NODE: &str = "mrsim-world";

/// A setup error: `what` could not be made, for reason `e`.
pub(super) fn setup_err(what: impl Into<String>, e: impl std::fmt::Debug) -> TransportError {
    TransportError::Setup {
        what: what.into(),
        detail: format!("{e:?}"),
    }
}

/// The iceoryx2 name of service `name` (`mrsim/...`).
pub(super) fn service_name(name: &str) -> Result<ServiceName, TransportError> {
    ServiceName::new(name).map_err(|e| setup_err(format!("service name {name}"), e))
}

/// The iceoryx2 configuration of a run: its own prefix and root path. The
/// root path is created readable by the current user only.
///
/// Nodes do not look for dead nodes when they are created or dropped or
/// open a service (iceoryx2's defaults): each look reads the state of every
/// node of the run (or of the service), so with hundreds of agents starting
/// and ending together they cost O(agents²) file reads and TOML parses.
/// The world cleans up
/// instead, once at its start and whenever an agent process dies; the
/// launcher removes what is left at the end.
pub fn config(ns: &Namespace) -> Result<Config, TransportError> {
    let mut cfg = Config::default();
    cfg.global.node.cleanup_dead_nodes_on_creation = false;
    cfg.global.node.cleanup_dead_nodes_on_destruction = false;
    cfg.global.service.cleanup_dead_nodes_on_open = false;
    cfg.global.prefix =
        FileName::new(ns.prefix().as_bytes()).map_err(|e| setup_err("iceoryx2 prefix", e))?;
    let root = ns.root_path();
    std::fs::create_dir_all(&root)
        .map_err(|e| setup_err(format!("root path {}", root.display()), e))?;
    for dir in [root.as_path(), root.parent().unwrap_or(root.as_path())] {
        // Private by default: only the user who started the run may enter.
        // The shared parent (/tmp/mrsim) stays enterable for other users' runs.
        let mode = if dir == root.as_path() { 0o700 } else { 0o1777 };
        let _ = std::fs::set_permissions(dir, std::fs::Permissions::from_mode(mode));
    }
    let root_str = root.to_string_lossy();
    let path = Path::new(root_str.as_bytes()).map_err(|e| setup_err("iceoryx2 root path", e))?;
    cfg.global.set_root_path(&path);
    Ok(cfg)
}

/// Creates this process's iceoryx2 node `name` in the run of `cfg`.
pub(super) fn node(cfg: &Config, name: &str) -> Result<Node<S>, TransportError> {
    let node_name = NodeName::new(name).map_err(|e| setup_err(format!("node name {name}"), e))?;
    NodeBuilder::new()
        .name(&node_name)
        .config(cfg)
        .create::<S>()
        .map_err(|e| setup_err(format!("node {name}"), e))
}

/// Waits for events on `listener` until `timeout`; a signal interrupting
/// the wait (EINTR) is a spurious wake-up, not an error: callers check
/// termination and the clock themselves.
///
/// The wait is a `ppoll` on the listener's socket (it returns at once when
/// events are already pending), then the pending events are drained
/// without blocking. iceoryx2's own `timed_wait` times out
/// through a socket receive timeout, which the kernel rounds up to whole
/// jiffies (4 ms at HZ = 250), and sets it and the socket's flags again on
/// every call (three syscalls); `ppoll` sleeps on a high-resolution timer,
/// so the world can wait for commands right up to a tick's deadline
/// without polling.
pub(super) fn wait_on(listener: &Listener<S>, timeout: Duration) -> Result<(), TransportError> {
    use iceoryx2::port::listener::ListenerWaitError;
    let drain = || match listener.try_wait(|_| {}) {
        Ok(n) => Ok(n > 0),
        Err(ListenerWaitError::InterruptSignal) => Ok(true),
        Err(e) => Err(TransportError::Wait(format!("{e:?}"))),
    };
    if timeout.is_zero() {
        drain()?;
        return Ok(());
    }
    // SAFETY: the descriptor belongs to the listener, which outlives this
    // call; it is only polled here, never closed.
    let fd = unsafe { listener.file_descriptor().native_handle() };
    let mut pfd = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    let ts = libc::timespec {
        tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: one valid pollfd, a valid timespec, no signal mask change.
    let r = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
    if r < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(TransportError::Wait(format!("ppoll: {e}")));
        }
    }
    // Drained also after a timeout. A notifier sends its datagram only
    // while the listener's shared state is not yet "notified", and a
    // notifier that runs between the listener's reset of that state and
    // its emptying of the socket leaves it "notified" with the datagram
    // gone: no notifier sends again, and only a drain resets it. Without
    // this drain the world would then wake only at each deadline, for the
    // rest of the run.
    drain()?;
    Ok(())
}

/// True once SIGINT or SIGTERM arrived. iceoryx2 reports a termination
/// request only once (its signal handler's last signal is taken when read),
/// so the answer is kept in `seen`: asked twice, a loop must hear it twice.
///
/// Reads iceoryx2's signal flag directly: `Node::wait(Duration::ZERO)`,
/// which reads the same flag, also makes a `nanosleep(0)` system call, once
/// per agent per tick.
pub(super) fn terminated(seen: &std::cell::Cell<bool>) -> bool {
    if !seen.get() && iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        seen.set(true);
    }
    seen.get()
}

/// Subscribes to the run's setup.
pub(super) fn setup_subscriber(node: &Node<S>) -> Result<Subscriber<S, [u8], ()>, TransportError> {
    node.service_builder(&service_name("mrsim/setup")?)
        .publish_subscribe::<[u8]>()
        .open()
        .map_err(|e| {
            setup_err(
                "service mrsim/setup (is a world running with this run id?)",
                e,
            )
        })?
        .subscriber_builder()
        .create()
        .map_err(|e| setup_err("setup subscriber", e))
}

/// Subscribes to the run's snapshots.
pub(super) fn snapshot_subscriber(
    node: &Node<S>,
) -> Result<Subscriber<S, [BodyState], SnapshotHeader>, TransportError> {
    node.service_builder(&service_name("mrsim/snapshot")?)
        .publish_subscribe::<[BodyState]>()
        .user_header::<SnapshotHeader>()
        .open()
        .map_err(|e| setup_err("service mrsim/snapshot", e))?
        .subscriber_builder()
        .create()
        .map_err(|e| setup_err("snapshot subscriber", e))
}

/// The newest sample waiting on `sub`, the older ones received and
/// released on the way; `None` if none was waiting. Always to the empty
/// queue: one doorbell ring is not always one snapshot (a new subscriber
/// also gets the publisher's history, unrung), and taking the oldest of
/// two left an agent a tick behind for good.
pub(super) fn newest_sample<T, H>(
    sub: &Subscriber<S, [T], H>,
    what: &'static str,
) -> Result<Option<Sample<S, [T], H>>, TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + 'static,
    H: std::fmt::Debug + ZeroCopySend + 'static,
{
    let mut newest = None;
    loop {
        match sub.receive() {
            Ok(Some(s)) => newest = Some(s),
            Ok(None) => return Ok(newest),
            Err(e) => {
                return Err(TransportError::Receive {
                    what,
                    detail: format!("{e:?}"),
                });
            }
        }
    }
}

/// Copies the newest sample waiting on `sub` (header and slice) and
/// drops the older ones; false if none was waiting.
pub(super) fn receive_newest<T, H>(
    sub: &Subscriber<S, [T], H>,
    what: &'static str,
    header: &mut H,
    out: &mut Vec<T>,
) -> Result<bool, TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + Copy + 'static,
    H: std::fmt::Debug + ZeroCopySend + Copy + 'static,
{
    let Some(s) = newest_sample(sub, what)? else {
        return Ok(false);
    };
    *header = *s.user_header();
    out.clear();
    out.extend_from_slice(s.payload());
    Ok(true)
}
