//! Before a run starts: everything it needs claimed, so that a refusal
//! comes before any process.

use super::zenoh::{free_loopback_endpoint, loopback_of};
use super::{Event, Starter};
use super::{LaunchError, RunRequest, Transport};
use crate::error::Invalid;
use crate::finish::Outcome;
use crate::sched::Applied;
use crate::validate::Validated;
use mrsim_transport::Namespace;
use mrsim_transport::zenoh::ZenohOptions;
use std::path::{Path, PathBuf};

/// A run ready to start: its folder, namespace and scheduling are claimed.
#[derive(Debug)]
pub struct Prepared {
    pub(super) validated: Validated,
    pub(super) request: RunRequest,
    pub(super) dir: PathBuf,
    pub(super) ns: Namespace,
    pub(super) applied: Applied,
    /// Realtime under `[world.cpus]`: the agents' CPUs and policies.
    pub(super) cores: Option<crate::cores::Cores>,
}

/// Claims what the run needs: the output folder (created, writable), the
/// run id's namespace (what a crashed earlier run left is cleared; a live
/// world's is refused), the scheduling of this process and its children,
/// and the termination signals (from now on they stop the run instead of
/// this process).
pub fn prepare(validated: Validated, request: RunRequest) -> Result<Prepared, LaunchError> {
    check_transport(&validated, request.transport)?;
    check_memory(&validated, request.transport)?;
    let dir = crate::out::prepare(request.out.as_deref(), &validated.scenario().name)?;
    write_source(&dir, validated.source())?;
    let run_id = request
        .run_id
        .clone()
        .unwrap_or_else(Namespace::fresh_run_id);
    let ns = Namespace::new(&run_id).map_err(|e| Invalid(e.to_string()))?;
    crate::namespace::claim(&ns)?;
    let applied = crate::sched::apply(&request.sched)?;
    let cores = crate::cores::claim(
        validated.scenario(),
        validated.origin(),
        request.transport,
        &applied.cpus,
    )?;
    mrsim_sys::signal::catch_termination();
    let mut request = request;
    if request.transport == Transport::Zenoh && request.zenoh.endpoint.is_none() {
        // Chosen now, so that the launcher's own observer knows where to
        // look before the world is up.
        request.zenoh.endpoint = Some(free_loopback_endpoint()?);
    }
    Ok(Prepared {
        validated,
        request,
        dir,
        ns,
        applied,
        cores,
    })
}

/// Writes the run folder's source.json: how `mrsim rerun` loads the
/// scenario again (the file made absolute).
pub(super) fn write_source(
    dir: &Path,
    source: &crate::validate::ScenarioSource,
) -> Result<(), Invalid> {
    let doc = mrsim_runfolder::SourceDoc {
        file: source
            .path
            .as_ref()
            .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone())),
        set: source.set.clone(),
        mode: source
            .mode
            .map(|m| crate::validate::mode_name(m).to_string()),
    };
    mrsim_runfolder::write_source(dir, &doc)
        .map_err(|e| Invalid(format!("cannot write the run folder: {e}")))
}

/// Refuses a transport the scenario's robots cannot run over: an
/// in-process run has no way in for an `external` robot's program, and an
/// agent process knows only the built-in planners, not a program's own.
pub(super) fn check_transport(validated: &Validated, transport: Transport) -> Result<(), Invalid> {
    let (robots, why) = match transport {
        Transport::Inproc => (
            [validated.external_robots(), validated.ros2_robots()].concat(),
            "has planner = \"external\" or \"ros2\": its own program (or the ROS 2 agent) \
             joins the run over shared memory or Zenoh, which an in-process run (--transport \
             inproc) does not offer; run it without --transport inproc, or register the \
             program's planner for an in-process run",
        ),
        Transport::Shm | Transport::Zenoh => (
            validated.robots_with_own_planners(),
            "has a planner registered in this program only: agent processes know the \
             built-in planners alone; run it in-process",
        ),
    };
    if robots.is_empty() {
        return Ok(());
    }
    let quoted: Vec<String> = robots.iter().map(|r| format!("`{r}`")).collect();
    Err(Invalid(format!(
        "{}: robot {} {why}",
        validated.origin(),
        mrsim_world::names::first_few(&quoted, 5)
    )))
}

/// Refuses a run that would not fit in the memory available now or under
/// this process's limits ([`crate::memory`]).
pub(super) fn check_memory(validated: &Validated, transport: Transport) -> Result<(), Invalid> {
    crate::memory::check(
        validated.origin(),
        validated.scenario(),
        transport,
        &mrsim_sys::memory::limits(),
    )
}

impl Prepared {
    /// The scenario to run.
    pub fn validated(&self) -> &Validated {
        &self.validated
    }

    /// The run folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The run's namespace (where an observer finds its world).
    pub fn namespace(&self) -> &Namespace {
        &self.ns
    }

    /// Over Zenoh, how an observer on this machine reaches the world (as
    /// its agents do); `None` with another transport.
    pub fn zenoh_observer(&self) -> Option<ZenohOptions> {
        let opts = &self.request.zenoh;
        (self.request.transport == Transport::Zenoh).then(|| ZenohOptions {
            endpoint: opts.endpoint.as_deref().map(loopback_of),
            config_file: opts.config_file.clone(),
        })
    }

    /// What the scheduling request gave.
    pub fn applied(&self) -> &Applied {
        &self.applied
    }

    /// Runs to the end and finishes; `on_event` hears what happens on the
    /// way. A run as processes starts each with the command `starter`
    /// builds for it; an in-process run starts none.
    pub fn start(
        self,
        starter: &dyn Starter,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> Result<Outcome, LaunchError> {
        match self.request.transport {
            Transport::Inproc => Ok(self.run_inproc(on_event)?),
            Transport::Shm | Transport::Zenoh => self.run_processes(starter, on_event),
        }
    }
}
