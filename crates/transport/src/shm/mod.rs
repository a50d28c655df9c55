//! The iceoryx2 transport: zero-copy shared memory between processes.
//!
//! Services of one run (all under the run's prefix and root path):
//!
//! | service | pattern | from -> to |
//! | --- | --- | --- |
//! | `mrsim/setup` | publish-subscribe `[u8]`, history 1 | world -> agents |
//! | `mrsim/snapshot` | publish-subscribe `[BodyState]` + `SnapshotHeader` | world -> agents |
//! | `mrsim/tick` | event (join replies) | world -> joining agents |
//! | `/dev/shm/PREFIXdoorbell` | futex word ([`doorbell`]): a new snapshot | world -> agents |
//! | `mrsim/join` | publish-subscribe `JoinRequest` | agents -> world |
//! | `mrsim/join-reply` | publish-subscribe `JoinReply` | world -> agents |
//! | `mrsim/command` | publish-subscribe `CommandMsg` | agents -> world |
//! | `mrsim/wake` | event (ready, join requests), notifier-dead event | agents -> world |
//! | `/dev/shm/PREFIXdoorbell` | futex word: the tick's answers counted, the last wakes | agents -> world |
//! | `mrsim/stats` | publish-subscribe `[RobotStats]` + `StatsHeader`, history 1 | world -> observers |
//!
//! An observer ([`ShmObserver`]) only subscribes to `setup`, `snapshot` and
//! `stats`: it never joins, sends or listens to the tick event, and the
//! world's publishers overwrite the oldest sample of a subscriber that falls
//! behind (iceoryx2's safe overflow) instead of waiting for it.
//!
//! Limits (publishers, subscribers, listeners, notifiers, nodes) are raised
//! from the scenario's robot count, with room to spare for restarted agents,
//! strangers and observers. Waiting is event driven (no busy polling).
//!
//! Each tick's wake-up of the agents is the doorbell, not an iceoryx2
//! event: one futex wake for all agents instead of a datagram per agent
//! (see [`doorbell`] for why and how). The snapshot itself, and
//! everything else, goes through iceoryx2. Likewise an agent's answer to a
//! tick is counted on the doorbell page rather than notified: the world is
//! woken once, by the last answer it waits for, instead of by every
//! command.
//!
//! One module per side: `world` ([`ShmWorld`]: creates every service,
//! publishes, answers joins, takes in commands), `agent` ([`ShmAgent`]),
//! `observer` ([`ShmObserver`]); what they share is in `service` (the
//! run's iceoryx2 configuration, nodes, service names, waits and
//! subscribers) and `watch` (whether the world process is alive, for
//! agents and observers), and the futex page in [`doorbell`]. The sides
//! import these; none imports another side.

mod agent;
pub mod doorbell;
mod observer;
mod service;
mod watch;
mod world;

pub use agent::ShmAgent;
pub use observer::ShmObserver;
pub use service::{WORLD_NODE, config};
pub use watch::world_running;
pub use world::ShmWorld;
