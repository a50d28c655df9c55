//! A run id's iceoryx2 namespace claimed before a world starts: beside the
//! shared-memory transport it clears, and a leaf, so that both the launch
//! and a world started by hand call it without importing each other.

use crate::error::Invalid;
use mrsim_transport::Namespace;

/// Clears what a crashed earlier run with this id left behind, unless a
/// live world holds the run (then refuses: two worlds cannot share one).
pub(crate) fn claim(ns: &Namespace) -> Result<(), Invalid> {
    match mrsim_transport::shm::world_running(ns) {
        Ok(true) => Err(Invalid(format!(
            "run id `{}` is in use by a running world; choose another --run",
            ns.run_id()
        ))),
        _ => {
            ns.remove_leftovers();
            Ok(())
        }
    }
}
