//! `usage.json` (what the agents used while the run ticked, written by the
//! launcher) and the per-agent files it is summed from.

use serde::{Deserialize, Serialize};

/// `usage.json`. Fields in alphabetical order, as the launcher writes them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Usage {
    /// Largest peak RSS of one agent process, KiB; null in-process (the
    /// agents share the world's process).
    pub agent_maxrss_kb: Option<u64>,
    /// CPU seconds of all agents from their first snapshot to the last.
    pub agents_cpu_s: f64,
    /// Agents that left a usage file.
    pub agents_reported: usize,
    /// `shm` or `inproc`.
    pub transport: String,
}

/// One agent's usage file ([`crate::agent_usage_file`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AgentUsage {
    /// CPU seconds from its first snapshot to the last.
    pub cpu_s: f64,
    /// Peak resident set size of its process, KiB.
    pub maxrss_kb: u64,
}
