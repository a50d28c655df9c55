//! Connections the world's Zenoh session refused for failed
//! authentication.
//!
//! Zenoh checks user/password credentials inside its handshake and closes
//! a link that fails it without telling the application: the only trace
//! is a `debug` event of its accept code
//! (`zenoh_transport::unicast::establishment::accept`) whose message names
//! the `UsrPwd` (or `Auth`) extension. So the world's process installs a
//! `tracing` subscriber that listens to that one module and nothing else
//! (every other call site is disabled once, when first met, and costs
//! nothing afterwards). The refused peer's address is in the trace event
//! the same task emitted just before on the same thread
//! (`Establishment Accept InitSyn: LOCAL => REMOTE`); it is remembered per
//! thread and paired with the failure.
//!
//! The subscriber is process-wide: every live [`AuthWatch`] hears every
//! refusal (a world process has one). If the process already has another
//! global `tracing` subscriber, none is installed and refusals go uncounted
//! ([`AuthWatch::new`] says so).

use std::cell::RefCell;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex, OnceLock, Weak};
use tracing::field::{Field, Visit};
use tracing::span::{Attributes, Id, Record};
use tracing::subscriber::Interest;
use tracing::{Event, Level, Metadata, Subscriber};

/// The module of Zenoh whose events tell of refused handshakes.
const ACCEPT_TARGET: &str = "zenoh_transport::unicast::establishment::accept";

/// Refusals heard by one world, not yet taken.
#[derive(Default)]
struct Heard {
    /// The refused peers' addresses (`None`: not known), oldest first.
    pending: Vec<Option<String>>,
    total: u64,
}

/// One world's ear on refused handshakes.
pub(super) struct AuthWatch {
    heard: Arc<Mutex<Heard>>,
}

/// Every live watch.
fn watches() -> &'static Mutex<Vec<Weak<Mutex<Heard>>>> {
    static W: OnceLock<Mutex<Vec<Weak<Mutex<Heard>>>>> = OnceLock::new();
    W.get_or_init(Default::default)
}

/// Whether the subscriber is this process's (installed once).
fn installed() -> bool {
    static I: OnceLock<bool> = OnceLock::new();
    *I.get_or_init(|| tracing::subscriber::set_global_default(Refusals).is_ok())
}

impl AuthWatch {
    /// Starts listening (installing the subscriber on first use). `None` if
    /// another `tracing` subscriber owns the process.
    pub(super) fn new() -> Option<Self> {
        if !installed() {
            return None;
        }
        let heard = Arc::new(Mutex::new(Heard::default()));
        let mut w = super::inbox::lock(watches());
        w.retain(|h| h.strong_count() > 0);
        w.push(Arc::downgrade(&heard));
        Some(Self { heard })
    }

    /// The refusals since the last call (their peers' addresses where
    /// known), and how many there were in all.
    pub(super) fn take(&self) -> (Vec<Option<String>>, u64) {
        let mut h = super::inbox::lock(&self.heard);
        (std::mem::take(&mut h.pending), h.total)
    }

    /// Refusals so far.
    pub(super) fn total(&self) -> u64 {
        super::inbox::lock(&self.heard).total
    }
}

thread_local! {
    /// The remote end of the link this thread last saw a handshake step of.
    static LAST_PEER: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Tells every watch of a refusal.
fn refused(peer: Option<String>) {
    for h in super::inbox::lock(watches()).iter() {
        if let Some(h) = h.upgrade() {
            let mut h = super::inbox::lock(&h);
            h.total += 1;
            // A flood of failed attempts keeps a bounded list; the count
            // stays exact.
            if h.pending.len() < 1024 {
                h.pending.push(peer.clone());
            }
        }
    }
}

/// What an event says, in text.
#[derive(Default)]
struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.0, "{value:?}");
        }
    }
}

/// The remote address in `Establishment Accept ...: LOCAL => REMOTE. ...`.
fn peer_of(message: &str) -> Option<String> {
    let (_, rest) = message.split_once(" => ")?;
    let end = rest.find(". ").unwrap_or(rest.len());
    let peer = rest[..end].trim();
    (!peer.is_empty()).then(|| peer.to_string())
}

/// A refusal for failed authentication (as opposed to a link that broke
/// or spoke another protocol version).
fn is_auth_failure(message: &str) -> bool {
    message.contains("UsrPwd extension") || message.contains("Auth extension")
}

/// The subscriber: enabled for Zenoh's accept module only.
struct Refusals;

impl Subscriber for Refusals {
    fn register_callsite(&self, metadata: &'static Metadata<'static>) -> Interest {
        if self.enabled(metadata) {
            Interest::always()
        } else {
            Interest::never()
        }
    }

    fn enabled(&self, metadata: &Metadata<'_>) -> bool {
        metadata.is_event() && metadata.target() == ACCEPT_TARGET
    }

    fn max_level_hint(&self) -> Option<tracing::level_filters::LevelFilter> {
        Some(tracing::level_filters::LevelFilter::TRACE)
    }

    fn new_span(&self, _: &Attributes<'_>) -> Id {
        Id::from_u64(1)
    }

    fn record(&self, _: &Id, _: &Record<'_>) {}

    fn record_follows_from(&self, _: &Id, _: &Id) {}

    fn event(&self, event: &Event<'_>) {
        let mut m = Message::default();
        event.record(&mut m);
        let level = *event.metadata().level();
        if level == Level::TRACE && m.0.starts_with("Establishment Accept") {
            LAST_PEER.with(|p| *p.borrow_mut() = peer_of(&m.0));
        } else if level <= Level::DEBUG && is_auth_failure(&m.0) {
            refused(LAST_PEER.with(|p| p.borrow_mut().take()));
        }
    }

    fn enter(&self, _: &Id) {}

    fn exit(&self, _: &Id) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_remote_end_of_a_handshake_step_is_its_peer() {
        let m = "Establishment Accept InitSyn: tcp/10.1.2.1:7447 => tcp/10.1.2.2:51234. Received: InitSyn { .. }";
        assert_eq!(peer_of(m).as_deref(), Some("tcp/10.1.2.2:51234"));
        assert_eq!(peer_of("nothing here"), None);
    }

    #[test]
    fn only_the_authentication_extensions_failures_count() {
        assert!(is_auth_failure(
            "UsrPwd extension - Recv OpenSyn. Invalid password. at src/x.rs:1."
        ));
        assert!(is_auth_failure(
            "Auth extension - Recv InitSyn. Invalid UsrPwd configuration."
        ));
        assert!(!is_auth_failure("Rejecting OpenSyn on: x. Unknown cookie."));
    }
}
