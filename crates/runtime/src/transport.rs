//! Which transport a run's world and agents talk over: a leaf, so that
//! whatever needs to know it (the launch, the memory check, benches and
//! sweeps) imports nothing else for it.

/// The transport between the world and its agents.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Transport {
    /// iceoryx2 shared memory, one process per agent.
    #[default]
    Shm,
    /// crossbeam channels, the agents in a pool of threads of one process.
    Inproc,
    /// Zenoh over TCP, one process per agent (here on loopback; by hand,
    /// agents on other machines).
    Zenoh,
}

impl Transport {
    /// The name used on the command line and in metrics.json.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Shm => "shm",
            Transport::Inproc => "inproc",
            Transport::Zenoh => "zenoh",
        }
    }
}
