//! CPU time and peak memory of the run's parts (usage.json, read by `mrsim bench`).
//!
//! Each part measures itself with getrusage (the same counters as
//! /proc/PID/stat's utime + stime and /proc/PID/status's VmHWM, read by
//! the process itself before it exits, when they are still there). An
//! agent counts CPU from its first snapshot to the run's end only, so
//! process start-up (exec, linking, join) is left out, as it is for the
//! world (`timing.process_cpu_s` in metrics.json).

use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader};
use mrsim_runfolder::USAGE_FILE;
use mrsim_transport::{AgentTransport, TransportError};
use std::path::Path;
use std::time::Duration;

pub use mrsim_sys::usage::{Scope, rusage};

pub use mrsim_runfolder::usage::AgentUsage;
use mrsim_runfolder::usage::Usage;

/// Writes what an agent used as its usage file (read by [`read_agent`]).
pub fn write_agent(path: &Path, usage: &AgentUsage) -> std::io::Result<()> {
    std::fs::write(path, serde_json::to_string(usage)?)
}

/// Reads a file written by [`write_agent`].
pub fn read_agent(path: &Path) -> Option<AgentUsage> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// An agent transport that notes the CPU time at the first snapshot and at
/// the last one it hands over; everything else is passed through.
pub struct Metered<'a> {
    inner: &'a mut dyn AgentTransport,
    scope: Scope,
    start: Option<f64>,
    end: Option<f64>,
}

impl<'a> Metered<'a> {
    /// Wraps `inner`.
    pub fn new(inner: &'a mut dyn AgentTransport, scope: Scope) -> Self {
        Self {
            inner,
            scope,
            start: None,
            end: None,
        }
    }

    /// Reads the CPU clock at the first snapshot and at the last.
    fn note(scope: Scope, start: &mut Option<f64>, end: &mut Option<f64>, header: &SnapshotHeader) {
        if header.finished != 0 {
            if end.is_none() {
                *end = Some(rusage(scope).0);
            }
        } else if start.is_none() {
            *start = Some(rusage(scope).0);
        }
    }

    /// What was used between the first and the last snapshot (up to now if
    /// the run did not finish).
    pub fn usage(&self) -> AgentUsage {
        let (now, maxrss_kb) = rusage(self.scope);
        let cpu_s = match self.start {
            Some(s) => (self.end.unwrap_or(now) - s).max(0.0),
            None => 0.0,
        };
        AgentUsage { cpu_s, maxrss_kb }
    }
}

impl AgentTransport for Metered<'_> {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        self.inner.request_join(req)
    }
    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        self.inner.poll_join_reply(nonce)
    }
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        self.inner.setup()
    }
    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        self.inner.wait(timeout)
    }
    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        let got = self.inner.latest_snapshot(header, bodies)?;
        if got {
            Self::note(self.scope, &mut self.start, &mut self.end, header);
        }
        Ok(got)
    }
    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError> {
        self.inner.send_command(cmd)
    }
    fn with_latest_snapshot(
        &mut self,
        scratch: &mut (SnapshotHeader, Vec<BodyState>),
        f: &mut mrsim_transport::SnapshotFn<'_>,
    ) -> Result<bool, TransportError> {
        let (scope, start, end) = (self.scope, &mut self.start, &mut self.end);
        self.inner
            .with_latest_snapshot(scratch, &mut |header, bodies, send| {
                Self::note(scope, start, end, header);
                f(header, bodies, send)
            })
    }
    fn world_alive(&mut self) -> bool {
        self.inner.world_alive()
    }
    fn termination_requested(&self) -> bool {
        self.inner.termination_requested()
    }
    fn joined(&mut self) {
        self.inner.joined()
    }
}

/// Writes `usage.json` into `dir`: what the agents used while the run
/// ticked, over `transport` (`shm`, `zenoh` or `inproc`).
pub fn write_report(dir: &Path, transport: &str, usage: &[AgentUsage]) -> std::io::Result<()> {
    let report = Usage {
        transport: transport.to_string(),
        agents_reported: usage.len(),
        agents_cpu_s: usage.iter().map(|u| u.cpu_s).sum::<f64>(),
        // In-process agents share the world's process: no RSS of their own.
        agent_maxrss_kb: (transport != "inproc")
            .then(|| usage.iter().map(|u| u.maxrss_kb).max())
            .flatten(),
    };
    let text = serde_json::to_string_pretty(&report)?;
    std::fs::write(dir.join(USAGE_FILE), format!("{text}\n"))
}
