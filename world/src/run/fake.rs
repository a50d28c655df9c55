//! An in-memory [`WorldTransport`] and a clock it moves, for the tick
//! loop's unit tests: joins and commands are queued by the test, replies
//! and snapshots kept for it to look at, and every wait moves the clock on
//! by the time asked for (no test sleeps or reads the wall clock).

use super::schedule::Clock;
use mrsim_proto::{
    BodyState, CommandMsg, FixedStr, JoinReply, JoinRequest, PROTOCOL_VERSION, RobotStats,
    SnapshotHeader, StatsHeader, command_kind,
};
use mrsim_transport::{TransportError, WorldTransport};
use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::{Duration, Instant};

/// A clock that moves only when the fake transport waits.
#[derive(Debug, Clone)]
pub struct FakeClock {
    base: Instant,
    elapsed: Rc<Cell<Duration>>,
}

impl Clock for FakeClock {
    fn now(&self) -> Instant {
        self.base + self.elapsed.get()
    }
}

/// An agent the fake answers for on every snapshot.
#[derive(Debug, Clone, Copy)]
pub struct Responder {
    /// Its robot.
    pub robot: u32,
    /// Its token.
    pub token: u64,
    /// The velocity it asks for.
    pub value: [f64; 2],
}

/// What the fake transport holds: the test's side of the channels.
#[derive(Default)]
pub struct State {
    /// Join requests not yet drained.
    pub joins: VecDeque<JoinRequest>,
    /// Commands not yet drained, with their receive time.
    pub commands: VecDeque<(CommandMsg, u64)>,
    /// Every join reply sent.
    pub replies: Vec<JoinReply>,
    /// Every snapshot header published.
    pub snapshots: Vec<SnapshotHeader>,
    /// Agents that answer each snapshot at once (a command for its tick,
    /// sent when it was published).
    pub responders: Vec<Responder>,
    /// Times `cleanup_dead` was called.
    pub cleanups: usize,
    /// Ask the loop to stop.
    pub terminate: bool,
}

/// The world's side of channels that live in memory; clones share them,
/// so the test keeps one while the loop drives another.
#[derive(Clone, Default)]
pub struct FakeTransport {
    state: Rc<RefCell<State>>,
    elapsed: Rc<Cell<Duration>>,
}

impl FakeTransport {
    /// The clock this transport moves.
    pub fn clock(&self) -> FakeClock {
        FakeClock {
            base: Instant::now(),
            elapsed: self.elapsed.clone(),
        }
    }

    /// The channels' contents.
    pub fn state(&self) -> std::cell::RefMut<'_, State> {
        self.state.borrow_mut()
    }

    /// Time the world has waited on this transport so far.
    pub fn waited(&self) -> Duration {
        self.elapsed.get()
    }

    /// Queues a join request for `robot` from process `pid`.
    pub fn join(&self, robot: &str, pid: u32, nonce: u64) {
        self.state()
            .joins
            .push_back(join_request(robot, pid, nonce));
    }

    /// The reply to the request with `nonce`.
    pub fn reply(&self, nonce: u64) -> Option<JoinReply> {
        self.state()
            .replies
            .iter()
            .rev()
            .find(|r| r.nonce == nonce)
            .copied()
    }

    /// Queues a command, received when it was sent.
    pub fn send(&self, cmd: CommandMsg) {
        self.state().commands.push_back((cmd, cmd.sent_ns));
    }
}

/// A join request of this protocol for `robot` from process `pid`.
pub fn join_request(robot: &str, pid: u32, nonce: u64) -> JoinRequest {
    JoinRequest {
        protocol_version: PROTOCOL_VERSION,
        pid,
        nonce,
        robot: FixedStr::new(robot),
        group: 1,
    }
}

/// A velocity command of `robot` with `token` for `tick`, sent at `sent_ns`.
pub fn velocity(robot: u32, token: u64, tick: u64, sent_ns: u64) -> CommandMsg {
    CommandMsg {
        robot_id: robot,
        kind: command_kind::VELOCITY,
        token,
        tick,
        value: [0.1, 0.0],
        compute_ns: 0,
        woke_ns: sent_ns,
        sent_ns,
        ..CommandMsg::default()
    }
}

impl WorldTransport for FakeTransport {
    fn publish_setup(&mut self, _setup: &[u8]) -> Result<(), TransportError> {
        Ok(())
    }

    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        _bodies: &[BodyState],
    ) -> Result<(), TransportError> {
        let mut st = self.state();
        st.snapshots.push(*header);
        if header.finished == 0 {
            for r in st.responders.clone() {
                let mut c = velocity(r.robot, r.token, header.tick, header.published_ns);
                c.value = r.value;
                st.commands.push_back((c, c.sent_ns));
            }
        }
        Ok(())
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        self.elapsed.set(self.elapsed.get() + timeout);
        Ok(())
    }

    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError> {
        let commands: Vec<_> = self.state().commands.drain(..).collect();
        for (c, t) in commands {
            f(c, t);
        }
        Ok(())
    }

    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError> {
        let joins: Vec<_> = self.state().joins.drain(..).collect();
        for j in joins {
            f(j);
        }
        Ok(())
    }

    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError> {
        self.state().replies.push(*reply);
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        self.state.borrow().terminate
    }

    fn cleanup_dead(&mut self) {
        self.state().cleanups += 1;
    }

    /// Nothing to count: commands are queued in `publish_snapshot`.
    fn expect_answers(&mut self, _tick: u64, _count: usize) {}

    /// Nothing to do: replies are kept in `replies` as they come.
    fn joins_answered(&mut self) -> Result<(), TransportError> {
        Ok(())
    }

    /// Nothing to connect.
    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        Ok(false)
    }

    /// No observers.
    fn publish_stats(
        &mut self,
        _header: &StatsHeader,
        _robots: &[RobotStats],
    ) -> Result<(), TransportError> {
        Ok(())
    }
}
