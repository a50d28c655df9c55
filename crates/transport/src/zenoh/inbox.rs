//! What Zenoh's callbacks hand over to the world's and agents' loops: a
//! mutex-guarded inbox and a condition variable to wake the one waiter.
//!
//! Callbacks run on Zenoh's own threads and must neither block nor
//! allocate without bound: each inbox has a limit, past which messages
//! are dropped and counted (a flood of commands cannot grow the world's
//! memory), and a message that does not decode is refused and counted.

use super::wire;
use mrsim_proto::{CommandMsg, JoinReply, JoinRequest, command_kind, now_ns};
use std::collections::HashMap;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

/// Locks `m`, whatever a panicking holder left (the data stays usable: a
/// poisoned inbox holds only plain values).
pub(super) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// A wake-up flag and its condition variable.
#[derive(Default)]
pub(super) struct Waker {
    cv: Condvar,
}

impl Waker {
    /// Waits until `*woken` or `timeout`, then clears it.
    pub(super) fn wait<'a, T>(
        &self,
        mut guard: MutexGuard<'a, T>,
        woken: impl Fn(&mut T) -> &mut bool,
        timeout: Duration,
    ) -> MutexGuard<'a, T> {
        if !*woken(&mut guard) && !timeout.is_zero() {
            guard = match self.cv.wait_timeout(guard, timeout) {
                Ok((g, _)) => g,
                Err(p) => p.into_inner().0,
            };
        }
        *woken(&mut guard) = false;
        guard
    }

    pub(super) fn ring(&self) {
        self.cv.notify_one();
    }
}

/// What the world has received and not yet taken.
pub(super) struct WorldInbox {
    pub(super) state: Mutex<WorldState>,
    pub(super) waker: Waker,
}

/// The world's inbox.
#[derive(Default)]
pub(super) struct WorldState {
    /// Commands with the world's clock at receipt.
    pub(super) commands: Vec<(CommandMsg, u64)>,
    pub(super) joins: Vec<JoinRequest>,
    pub(super) woken: bool,
    /// The tick whose answers are counted, and how many wake the world.
    expect: Option<(u64, usize)>,
    answered: usize,
    /// Most commands (and, a quarter of it, joins) held at once.
    limit: usize,
    /// Commands that did not decode.
    pub(super) refused_commands: u64,
    /// Join requests that did not decode.
    pub(super) refused_joins: u64,
    /// Messages dropped because the inbox was full (a flood).
    pub(super) dropped: u64,
    /// Live liveliness tokens per agent process id.
    tokens: HashMap<u32, usize>,
}

impl WorldInbox {
    /// An inbox holding at most `limit` commands at once.
    pub(super) fn new(limit: usize) -> Self {
        Self {
            state: Mutex::new(WorldState {
                limit,
                ..Default::default()
            }),
            waker: Waker::default(),
        }
    }

    /// A command's bytes arrived.
    pub(super) fn command(&self, bytes: &[u8]) {
        let received = now_ns();
        let mut s = lock(&self.state);
        let Some(mut cmd) = wire::decode::<CommandMsg>(bytes) else {
            s.refused_commands += 1;
            return;
        };
        // An agent's clock may be another host's: the world never compares
        // it with its own. A command is late by when it arrived, and its
        // wake-up is estimated as arrival less the agent's compute time (a
        // duration, the same on any clock).
        cmd.sent_ns = received;
        cmd.woke_ns = received.saturating_sub(cmd.compute_ns);
        if s.commands.len() >= s.limit {
            s.dropped += 1;
            return;
        }
        s.commands.push((cmd, received));
        // Answers to the counted tick wake the world once, at the last;
        // anything else wakes it at once.
        let wake = match s.expect {
            Some((tick, count)) if cmd.tick == tick && cmd.kind != command_kind::READY => {
                s.answered += 1;
                s.answered >= count
            }
            _ => true,
        };
        if wake {
            s.woken = true;
            self.waker.ring();
        }
    }

    /// A join request's bytes arrived.
    pub(super) fn join(&self, bytes: &[u8]) {
        let mut s = lock(&self.state);
        let Some(req) = wire::decode::<JoinRequest>(bytes) else {
            s.refused_joins += 1;
            return;
        };
        if s.joins.len() >= s.limit / 4 + 16 {
            s.dropped += 1;
            return;
        }
        s.joins.push(req);
        s.woken = true;
        self.waker.ring();
    }

    /// An agent's liveliness token appeared (`up`) or went.
    pub(super) fn token(&self, pid: u32, up: bool) {
        let mut s = lock(&self.state);
        let n = s.tokens.entry(pid).or_default();
        if up {
            *n += 1;
        } else {
            *n = n.saturating_sub(1);
            s.woken = true;
            self.waker.ring();
        }
    }

    /// False only for a process whose token was seen and is gone: an agent
    /// the world has heard nothing of yet (its token still on the way) is
    /// not declared dead; if it never answers, the stall timeout decides.
    pub(super) fn alive(&self, pid: u32) -> bool {
        lock(&self.state).tokens.get(&pid).is_none_or(|&n| n > 0)
    }

    /// From now on answers to `tick` are counted; `count` of them wake.
    pub(super) fn expect(&self, tick: u64, count: usize) {
        let mut s = lock(&self.state);
        let already = s
            .commands
            .iter()
            .filter(|(c, _)| c.tick == tick && c.kind != command_kind::READY)
            .count();
        s.expect = Some((tick, count));
        s.answered = already;
    }
}

/// What an agent (or observer) has received and not yet taken.
#[derive(Default)]
pub(super) struct AgentState {
    /// The newest snapshot's bytes (older ones are overwritten).
    pub(super) snapshot: Vec<u8>,
    pub(super) fresh_snapshot: bool,
    /// The newest statistics' bytes (observers only).
    pub(super) stats: Vec<u8>,
    pub(super) fresh_stats: bool,
    /// Join replies not yet looked at (bounded: the newest are kept).
    pub(super) replies: Vec<JoinReply>,
    pub(super) woken: bool,
    /// The world's token: seen at least once, and present now.
    pub(super) world_seen: bool,
    pub(super) world_present: bool,
    /// Messages that did not decode.
    pub(super) refused: u64,
}

/// The agent's side of the inbox.
#[derive(Default)]
pub(super) struct AgentInbox {
    pub(super) state: Mutex<AgentState>,
    pub(super) waker: Waker,
}

/// Join replies an agent keeps while joining (hundreds of agents joining
/// at once see each other's replies).
const REPLY_MAX: usize = 256;

impl AgentInbox {
    /// A snapshot arrived: it replaces the last one.
    pub(super) fn snapshot(&self, bytes: &[u8]) {
        let mut s = lock(&self.state);
        s.snapshot.clear();
        s.snapshot.extend_from_slice(bytes);
        s.fresh_snapshot = true;
        s.woken = true;
        self.waker.ring();
    }

    /// Statistics arrived: they replace the last ones.
    pub(super) fn stats(&self, bytes: &[u8]) {
        let mut s = lock(&self.state);
        s.stats.clear();
        s.stats.extend_from_slice(bytes);
        s.fresh_stats = true;
    }

    /// A join reply arrived.
    pub(super) fn reply(&self, bytes: &[u8]) {
        let mut s = lock(&self.state);
        let Some(r) = wire::decode::<JoinReply>(bytes) else {
            s.refused += 1;
            return;
        };
        if s.replies.len() >= REPLY_MAX {
            s.replies.remove(0);
        }
        s.replies.push(r);
        s.woken = true;
        self.waker.ring();
    }

    /// The world's token appeared (`up`) or went.
    pub(super) fn world(&self, up: bool) {
        let mut s = lock(&self.state);
        s.world_present = up;
        s.world_seen |= up;
        s.woken = true;
        self.waker.ring();
    }

    /// Waits until something arrives or `timeout` passes.
    pub(super) fn wait(&self, timeout: Duration) {
        let g = lock(&self.state);
        drop(self.waker.wait(g, |s| &mut s.woken, timeout));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd(tick: u64, kind: u32) -> Vec<u8> {
        wire::encode(&CommandMsg {
            tick,
            kind,
            ..Default::default()
        })
    }

    #[test]
    fn garbage_is_refused_and_counted() {
        let inbox = WorldInbox::new(8);
        inbox.command(b"not a command");
        inbox.join(&[0xff; 3]);
        let s = lock(&inbox.state);
        assert_eq!(
            (s.refused_commands, s.refused_joins, s.commands.len()),
            (1, 1, 0)
        );
    }

    #[test]
    fn an_agents_clock_never_reaches_the_world() {
        let inbox = WorldInbox::new(8);
        let before = now_ns();
        inbox.command(&wire::encode(&CommandMsg {
            tick: 1,
            compute_ns: 1000,
            woke_ns: u64::MAX / 2,
            sent_ns: u64::MAX / 2,
            ..Default::default()
        }));
        let s = lock(&inbox.state);
        let (c, received) = s.commands[0];
        assert!(received >= before);
        assert_eq!((c.sent_ns, c.woke_ns), (received, received - 1000));
    }

    #[test]
    fn a_flood_is_dropped_past_the_limit() {
        let inbox = WorldInbox::new(4);
        for _ in 0..100 {
            inbox.command(&cmd(1, 0));
        }
        let s = lock(&inbox.state);
        assert_eq!((s.commands.len(), s.dropped), (4, 96));
    }

    #[test]
    fn counted_answers_wake_the_world_only_at_the_last() {
        let inbox = WorldInbox::new(64);
        inbox.expect(7, 3);
        inbox.command(&cmd(7, 0));
        inbox.command(&cmd(7, 0));
        assert!(!lock(&inbox.state).woken);
        inbox.command(&cmd(6, 0));
        assert!(lock(&inbox.state).woken, "a stale command wakes at once");
        lock(&inbox.state).woken = false;
        inbox.command(&cmd(7, 0));
        assert!(lock(&inbox.state).woken);
    }

    #[test]
    fn an_agent_is_dead_only_once_its_token_went() {
        let inbox = WorldInbox::new(8);
        assert!(inbox.alive(10), "not heard of yet");
        inbox.token(10, true);
        assert!(inbox.alive(10));
        inbox.token(10, false);
        assert!(!inbox.alive(10));
        inbox.token(10, true);
        assert!(inbox.alive(10), "came back");
    }
}
