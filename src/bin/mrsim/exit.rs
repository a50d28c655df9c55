//! Exit statuses, and how an error becomes one.

use mrsim_runtime::{Invalid, Refusal};

/// Exit status for a refused scenario or command line.
pub const EXIT_INVALID: i32 = 2;
/// Exit status for a run that failed.
pub const EXIT_FAILED: i32 = 1;
/// Exit status for a run stopped by a signal (it wrote what it had).
pub const EXIT_INTERRUPTED: i32 = 130;

/// A refusal of the command line (exit status 2).
pub fn invalid(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Invalid::new(msg))
}

/// A runtime error as the command line reports it: a refusal keeps only
/// its message (exit status 2), a failure its whole chain of causes.
pub fn fail<E>(e: E) -> anyhow::Error
where
    E: Refusal + std::error::Error + Send + Sync + 'static,
{
    match e.refused() {
        Some(i) => anyhow::Error::new(i.clone()),
        None => anyhow::Error::new(e),
    }
}

/// Prints an error on stderr and gives the exit status.
pub fn code(result: anyhow::Result<i32>) -> i32 {
    match result {
        Ok(code) => code,
        Err(e) => {
            if let Some(invalid) = e.downcast_ref::<Invalid>() {
                eprintln!("error: {invalid}");
                return EXIT_INVALID;
            }
            eprintln!("error: {e:#}");
            EXIT_FAILED
        }
    }
}
