//! What every operation's error has in common: either the input was refused
//! before anything started ([`Invalid`]), or something failed on the way.

/// A scenario, a command line or an output folder refused before anything
/// started. The message names what was refused and why (for a scenario:
/// the file, line and key).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Invalid(pub String);

impl Invalid {
    /// A refusal saying `msg`.
    pub fn new(msg: impl Into<String>) -> Self {
        Self(msg.into())
    }
}

/// An operation's error that may be a refusal of its input.
pub trait Refusal {
    /// The refusal, if the error is one (the input was refused before
    /// anything started); `None` for a failure on the way.
    fn refused(&self) -> Option<&Invalid>;
}

impl Refusal for Invalid {
    fn refused(&self) -> Option<&Invalid> {
        Some(self)
    }
}

/// `e` and every error under it, as one line: `what: why: why...` (for
/// callers that hand an error on as text: a sweep's row, Python).
pub fn in_words(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        text.push_str(&format!(": {s}"));
        src = s.source();
    }
    text
}
