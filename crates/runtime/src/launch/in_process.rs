//! The in-process path: the world in the calling thread, the robots'
//! planners in a pool of threads ([`crate::inproc`]).

use super::embed::InProcessError;
use super::prepare::Prepared;
use super::processes::alike;
use super::{Event, Observing, Transport};
use crate::finish::{Ending, Outcome};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

impl Prepared {
    pub(super) fn run_inproc(
        self,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> Result<Outcome, InProcessError> {
        let Prepared {
            validated,
            request,
            dir,
            ns,
            ..
        } = self;
        let registry = validated.registry().clone();
        let (scenario, world) = validated.into_world();
        let stop = Arc::new(AtomicBool::new(false));
        // A planner that fails in lockstep stops the run as a signal would.
        let halt = mrsim_agents::Halt::new(stop.clone());
        let mut agents = mrsim_agents::AgentOptions::new("");
        agents.registry = registry;
        agents.halt = Some(halt.clone());
        let done = Arc::new(AtomicBool::new(false));
        // A signal to the launcher stops the in-process run as SIGTERM stops
        // a world process.
        let watcher = {
            let (stop, done) = (stop.clone(), done.clone());
            std::thread::spawn(move || {
                while !done.load(Ordering::SeqCst) {
                    if mrsim_sys::signal::received().is_some() {
                        stop.store(true, Ordering::SeqCst);
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
            })
        };
        let outcome = crate::inproc::run_scenario(
            &scenario,
            world,
            &dir,
            ns.run_id(),
            stop,
            &agents,
            request.plan_timeout,
            &mut |obs| on_event(Event::WaitingInproc(Observing(obs))),
        );
        on_event(Event::WorldEnded);
        done.store(true, Ordering::SeqCst);
        let _ = watcher.join();
        let outcome = outcome?;
        let agent_failures = alike(
            scenario
                .robots
                .iter()
                .zip(&outcome.agent_errors)
                .filter_map(|(r, e)| Some((r.name.as_str(), format!("failed: {}", e.as_ref()?)))),
        );
        let finished = crate::finish::finish(Ending {
            dir: &dir,
            world_failure: None,
            agent_failures,
            usage: Some((Transport::Inproc.name(), &outcome.agent_usage)),
            render: request.render,
            metrics: Some(outcome.metrics),
        })?;
        match halt.failure() {
            Some(failure) => Err(InProcessError::Planner { failure, dir }),
            None => Ok(finished),
        }
    }
}
