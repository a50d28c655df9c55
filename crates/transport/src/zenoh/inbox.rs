//! What Zenoh's callbacks hand over to the world's and agents' loops: a
//! mutex-guarded inbox and a condition variable to wake the one waiter.
//!
//! Callbacks run on Zenoh's own threads and must neither block nor
//! allocate without bound: each inbox has a limit, past which messages
//! are dropped and counted (a flood of commands cannot grow the world's
//! memory), and a message that does not decode is refused and counted.

use super::seal::{self, KEY_LEN, RunKey};
use super::wire::{self, Wire};
use mrsim_proto::{CommandMsg, JoinReply, JoinRequest, command_kind, now_ns};
use std::collections::{HashMap, HashSet};
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
    /// Most commands of strangers, and as many of agents, held at once
    /// (and, a quarter of it, joins).
    limit: usize,
    /// Commands held that carry no token the world gave (a flood of
    /// forged commands fills only their share of the inbox).
    strangers: usize,
    /// Every token the world has given in an accepted join reply.
    issued: HashSet<u64>,
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
        // A command with a token the world gave goes in whatever strangers
        // sent: a flood of forged commands cannot crowd out the agents'.
        let given = s.issued.contains(&cmd.token);
        let held = if given {
            s.commands.len() - s.strangers
        } else {
            s.strangers
        };
        if held >= s.limit {
            s.dropped += 1;
            return;
        }
        s.strangers += usize::from(!given);
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

    /// The world gave `token` to an agent it accepted.
    pub(super) fn issued(&self, token: u64) {
        lock(&self.state).issued.insert(token);
    }

    /// Every command received since the last call, in order of receipt.
    pub(super) fn take_commands(&self) -> Vec<(CommandMsg, u64)> {
        let mut s = lock(&self.state);
        s.strangers = 0;
        std::mem::take(&mut s.commands)
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
    /// The newest snapshot's bytes (older ones are overwritten): checked
    /// and without its tag once the run's key is known, else as received.
    pub(super) snapshot: Vec<u8>,
    pub(super) fresh_snapshot: bool,
    /// Whether `snapshot` still carries its tag, unchecked (it came before
    /// the run's key).
    pub(super) snapshot_sealed: bool,
    /// The newest statistics' bytes (observers only).
    pub(super) stats: Vec<u8>,
    pub(super) fresh_stats: bool,
    /// Join replies not yet looked at (bounded: the newest are kept), each
    /// with the run's key if it carried one.
    pub(super) replies: Vec<(JoinReply, Option<RunKey>)>,
    pub(super) woken: bool,
    /// The world's token: seen at least once, and present now.
    pub(super) world_seen: bool,
    pub(super) world_present: bool,
    /// Messages that did not decode.
    pub(super) refused: u64,
    /// The nonce of this agent's join request, whose accepted reply
    /// brings the run's key.
    pub(super) nonce: Option<u64>,
    /// The key the run's world signs its snapshots with, once joined.
    pub(super) key: Option<RunKey>,
    /// The tick of the newest snapshot kept since the key came.
    newest_tick: Option<u64>,
    /// Snapshots whose tag did not check (forged, or of another world).
    pub(super) forged: u64,
    /// Signed snapshots of a tick older than one already kept (replayed).
    pub(super) replayed: u64,
}

/// The agent's side of the inbox.
#[derive(Default)]
pub(super) struct AgentInbox {
    pub(super) state: Mutex<AgentState>,
    pub(super) waker: Waker,
}

impl AgentState {
    /// Checks sealed snapshot bytes against the run's key: the message
    /// inside if it is the world's and not older than one kept already;
    /// else `None`, counted.
    fn admit<'a>(&mut self, key: &RunKey, sealed: &'a [u8]) -> Option<&'a [u8]> {
        let Some(message) = key.open(sealed) else {
            self.forged += 1;
            return None;
        };
        let tick = seal::tick_of(message)?;
        if self.newest_tick.is_some_and(|t| tick < t) {
            self.replayed += 1;
            return None;
        }
        self.newest_tick = Some(tick);
        Some(message)
    }

    /// Reads the newest snapshot's message with `read` if one came since
    /// the last call: checked against the run's key if it came before it
    /// (an observer, which has no key and only watches, reads it
    /// unchecked); `None` if none came or it does not check.
    pub(super) fn take_snapshot<R>(&mut self, read: impl FnOnce(&[u8]) -> R) -> Option<R> {
        if !std::mem::take(&mut self.fresh_snapshot) {
            return None;
        }
        if !self.snapshot_sealed {
            return Some(read(&self.snapshot));
        }
        let bytes = std::mem::take(&mut self.snapshot);
        let key = self.key.take();
        let out = match &key {
            Some(key) => self.admit(key, &bytes).map(read),
            None => seal::unchecked(&bytes).map(read),
        };
        self.key = key;
        self.snapshot = bytes;
        out
    }
}

/// Join replies an agent keeps while joining (hundreds of agents joining
/// at once see each other's replies).
const REPLY_MAX: usize = 256;

impl AgentInbox {
    /// A snapshot arrived: once the run's key is known, it replaces the
    /// last one if its tag checks (a forged one is counted and dropped and
    /// wakes nobody); before, it is kept as received, checked when taken.
    pub(super) fn snapshot(&self, bytes: &[u8]) {
        let mut guard = lock(&self.state);
        let s = &mut *guard;
        if let Some(key) = s.key.take() {
            let admitted = s.admit(&key, bytes);
            s.key = Some(key);
            let Some(message) = admitted else {
                return;
            };
            s.snapshot.clear();
            s.snapshot.extend_from_slice(message);
            s.snapshot_sealed = false;
        } else {
            s.snapshot.clear();
            s.snapshot.extend_from_slice(bytes);
            s.snapshot_sealed = true;
        }
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

    /// A join reply arrived (an accepted one followed by the run's key).
    /// The accepted reply to this agent's own request gives the inbox the
    /// key, before any snapshot that follows it on the link is looked at.
    pub(super) fn reply(&self, bytes: &[u8]) {
        let mut s = lock(&self.state);
        let Some((r, key)) = decode_reply(bytes) else {
            s.refused += 1;
            return;
        };
        if let Some(key) = &key
            && r.accepted == 1
            && Some(r.nonce) == s.nonce
        {
            s.key = Some(key.clone());
            s.newest_tick = None;
        }
        if s.replies.len() >= REPLY_MAX {
            s.replies.remove(0);
        }
        s.replies.push((r, key));
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

/// A join reply's bytes as the world sends them over Zenoh: the reply,
/// then the run's key if accepted.
pub(super) fn encode_reply(reply: &JoinReply, key: &RunKey) -> Vec<u8> {
    let mut out = wire::encode(reply);
    if reply.accepted == 1 {
        out.extend_from_slice(key.bytes());
    }
    out
}

/// A join reply and the key after it, if any; `None` if the bytes are
/// neither.
pub(super) fn decode_reply(bytes: &[u8]) -> Option<(JoinReply, Option<RunKey>)> {
    if bytes.len() == JoinReply::LEN + KEY_LEN {
        let (reply, key) = bytes.split_at(JoinReply::LEN);
        let key: [u8; KEY_LEN] = key.try_into().ok()?;
        Some((wire::decode(reply)?, Some(RunKey::from_bytes(key))))
    } else {
        Some((wire::decode(bytes)?, None))
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
    fn a_flood_of_forged_commands_leaves_room_for_the_agents() {
        let inbox = WorldInbox::new(4);
        inbox.issued(77);
        for _ in 0..100 {
            inbox.command(&cmd(1, 0));
        }
        let honest = CommandMsg {
            tick: 1,
            token: 77,
            ..Default::default()
        };
        inbox.command(&wire::encode(&honest));
        assert_eq!(lock(&inbox.state).dropped, 96);
        let taken = inbox.take_commands();
        assert_eq!(taken.len(), 5);
        assert_eq!(taken[4].0.token, 77, "the agent's command is in");
        // Each drain gives the strangers their share again.
        inbox.command(&cmd(2, 0));
        assert_eq!(inbox.take_commands().len(), 1);
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

    /// A sealed snapshot message of `tick` under `key`.
    fn sealed(key: &RunKey, tick: u64) -> Vec<u8> {
        let mut m = tick.to_le_bytes().to_vec();
        m.extend_from_slice(b"bodies");
        key.seal(&mut m);
        m
    }

    fn accepted(nonce: u64) -> JoinReply {
        JoinReply {
            nonce,
            accepted: 1,
            ..Default::default()
        }
    }

    /// An agent inbox that asked to join with nonce 7 and was accepted.
    fn joined(key: &RunKey) -> AgentInbox {
        let inbox = AgentInbox::default();
        lock(&inbox.state).nonce = Some(7);
        inbox.reply(&encode_reply(&accepted(7), key));
        assert!(lock(&inbox.state).key.is_some());
        inbox
    }

    fn take(inbox: &AgentInbox) -> Option<u64> {
        lock(&inbox.state).take_snapshot(|m| seal::tick_of(m).unwrap_or(u64::MAX))
    }

    #[test]
    fn a_forged_snapshot_is_counted_and_never_displaces_the_worlds() {
        let key = RunKey::generate().expect("key");
        let inbox = joined(&key);
        inbox.snapshot(&sealed(&key, 3));
        lock(&inbox.state).woken = false;
        let forger = RunKey::generate().expect("key");
        inbox.snapshot(&sealed(&forger, 4));
        inbox.snapshot(b"no tag at all");
        let s = lock(&inbox.state);
        assert_eq!((s.forged, s.replayed), (2, 0));
        assert!(!s.woken, "a forged snapshot wakes nobody");
        drop(s);
        assert_eq!(take(&inbox), Some(3), "the world's snapshot is kept");
        assert_eq!(take(&inbox), None);
    }

    #[test]
    fn a_signed_snapshot_older_than_one_kept_is_refused_as_a_replay() {
        let key = RunKey::generate().expect("key");
        let inbox = joined(&key);
        inbox.snapshot(&sealed(&key, 5));
        inbox.snapshot(&sealed(&key, 5));
        inbox.snapshot(&sealed(&key, 4));
        let s = lock(&inbox.state);
        assert_eq!(
            (s.forged, s.replayed),
            (0, 1),
            "the same tick again is not a replay"
        );
        drop(s);
        assert_eq!(take(&inbox), Some(5));
    }

    #[test]
    fn a_snapshot_before_the_key_is_checked_when_taken() {
        let key = RunKey::generate().expect("key");
        let forger = RunKey::generate().expect("key");
        let inbox = AgentInbox::default();
        lock(&inbox.state).nonce = Some(7);
        inbox.snapshot(&sealed(&forger, 2));
        inbox.reply(&encode_reply(&accepted(7), &key));
        assert_eq!(take(&inbox), None);
        assert_eq!(lock(&inbox.state).forged, 1);
        inbox.snapshot(&sealed(&key, 2));
        assert_eq!(take(&inbox), Some(2));
    }

    #[test]
    fn only_the_accepted_reply_to_the_agents_own_request_gives_it_the_key() {
        let key = RunKey::generate().expect("key");
        let inbox = AgentInbox::default();
        lock(&inbox.state).nonce = Some(7);
        // Another agent's reply, and a refusal of this one's: no key.
        inbox.reply(&encode_reply(&accepted(8), &key));
        let refused = JoinReply {
            nonce: 7,
            ..Default::default()
        };
        assert_eq!(encode_reply(&refused, &key).len(), JoinReply::LEN);
        inbox.reply(&encode_reply(&refused, &key));
        assert!(lock(&inbox.state).key.is_none());
        inbox.reply(&encode_reply(&accepted(7), &key));
        assert!(lock(&inbox.state).key.is_some());
        assert_eq!(lock(&inbox.state).replies.len(), 3);
    }

    #[test]
    fn an_observer_reads_a_snapshot_without_a_key() {
        let key = RunKey::generate().expect("key");
        let inbox = AgentInbox::default();
        inbox.snapshot(&sealed(&key, 9));
        assert_eq!(take(&inbox), Some(9));
    }
}
