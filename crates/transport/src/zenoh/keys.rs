//! The key expressions of one run: every key lives under
//! `mrsim/<run id>/`, so two runs on one network never see each other's
//! messages (a world and its agents must agree on the run id as well as on
//! the address).

use crate::Namespace;

/// The keys of one run.
#[derive(Debug, Clone)]
pub struct Keys {
    /// The resolved scenario (a queryable of the world: late joiners ask).
    pub setup: String,
    /// One snapshot per tick, world -> agents and observers.
    pub snapshot: String,
    /// Join requests, agents -> world.
    pub join: String,
    /// Join replies, world -> joining agents (each keeps the one with its
    /// nonce).
    pub join_reply: String,
    /// Commands (and ready messages), agents -> world.
    pub command: String,
    /// Live statistics, world -> observers.
    pub stats: String,
    /// The world's liveliness token.
    pub world_alive: String,
    /// Prefix of the agents' liveliness tokens (`<prefix>/<pid>`).
    pub agent_alive: String,
}

impl Keys {
    /// The keys of run `ns` (run ids are `a-z 0-9 -`, valid key chunks).
    pub fn new(ns: &Namespace) -> Self {
        let root = format!("mrsim/{}", ns.run_id());
        Self {
            setup: format!("{root}/setup"),
            snapshot: format!("{root}/snapshot"),
            join: format!("{root}/join"),
            join_reply: format!("{root}/join-reply"),
            command: format!("{root}/command"),
            stats: format!("{root}/stats"),
            world_alive: format!("{root}/alive/world"),
            agent_alive: format!("{root}/alive/agent"),
        }
    }

    /// The liveliness token of the agent process `pid`.
    pub fn agent_token(&self, pid: u32) -> String {
        format!("{}/{pid}", self.agent_alive)
    }

    /// The process id in an agent's liveliness token, if `key` is one.
    pub fn agent_pid(&self, key: &str) -> Option<u32> {
        key.strip_prefix(self.agent_alive.as_str())?
            .strip_prefix('/')?
            .parse()
            .ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_of_two_runs_never_overlap() {
        let a = Keys::new(&Namespace::new("run-a").unwrap());
        let b = Keys::new(&Namespace::new("run-ab").unwrap());
        for (x, y) in [(&a.command, &b.command), (&a.snapshot, &b.snapshot)] {
            assert_ne!(x, y);
            assert!(!y.starts_with(&format!("{x}/")));
        }
    }

    #[test]
    fn an_agent_token_gives_back_its_pid() {
        let k = Keys::new(&Namespace::new("r1").unwrap());
        assert_eq!(k.agent_pid(&k.agent_token(4242)), Some(4242));
        assert_eq!(k.agent_pid("mrsim/r1/alive/agent/x"), None);
        assert_eq!(k.agent_pid(&k.world_alive), None);
    }
}
