//! Printing a run's [`Outcome`]: notes and warnings on stderr, the summary
//! table and the run folder on stdout; the exit status.

use crate::exit::{EXIT_FAILED, EXIT_INTERRUPTED};
use mrsim_runtime::Outcome;

/// Prints `outcome` (the table unless `quiet`, then `beside`, the
/// predicted and measured misses, if given) and gives the exit status.
pub fn print(outcome: &Outcome, quiet: bool, beside: Option<&str>) -> i32 {
    match &outcome.diagnostics {
        Ok(s) if s.skipped > 0 => eprintln!(
            "note: diagnostics: {} unfinished or malformed lines left out",
            s.skipped
        ),
        Ok(_) => {}
        Err(e) => eprintln!(
            "warning: cannot merge the agents' diagnostics in {}: {e}",
            outcome.dir.display()
        ),
    }
    if let Some(w) = &outcome.world_failure {
        eprintln!(
            "error: the world process (pid {}) {}; outputs so far are in {}",
            w.pid,
            w.how,
            outcome.dir.display()
        );
        return EXIT_FAILED;
    }
    for f in &outcome.agent_failures {
        eprintln!("note: {f} (see events.jsonl)");
    }
    if let Some(e) = &outcome.render_error {
        eprintln!("warning: cannot draw the run's plots and replay: {e}");
    }
    if !quiet && let Some(m) = &outcome.metrics {
        print!("{}", crate::table::summary(m));
        if let Some(b) = beside {
            print!("{b}");
        }
    }
    println!("run folder: {}", outcome.dir.display());
    if outcome.interrupted() {
        EXIT_INTERRUPTED
    } else {
        0
    }
}
