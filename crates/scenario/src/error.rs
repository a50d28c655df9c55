//! Errors of loading a scenario, with the file and line they point at.

use std::ops::Range;
use std::path::PathBuf;

/// Why a scenario was refused.
///
/// Every variant that comes from the file names the file (its `origin`) and,
/// where one can be found, the line, so that `Display` reads like a compiler
/// message: `scenarios/x.toml:12: robot `r1`: radius must be >= 0, got -1`.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The file is not valid TOML.
    #[error("{origin}:{line}:{column}: {message}")]
    Syntax {
        /// The file (or the name given to `parse`).
        origin: String,
        /// 1-based line.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// What the TOML parser said.
        message: String,
    },
    /// The file is TOML but not a valid scenario.
    #[error("{origin}{}: {what}{}{reason}", line_suffix(*line), if what.is_empty() { "" } else { ": " })]
    Invalid {
        /// The file (or the name given to `parse`).
        origin: String,
        /// 1-based line of the offending key or table, if there is one.
        line: Option<usize>,
        /// What is wrong, e.g. ``robot `r1` `` or `world`.
        what: String,
        /// Why, e.g. `radius must be >= 0, got -1`.
        reason: String,
    },
    /// A command-line override (`KEY=VALUE`) is unknown or gives an invalid value.
    #[error("override `{key}`: {reason}")]
    Override {
        /// The override's dotted key as given.
        key: String,
        /// Why it was refused.
        reason: String,
    },
}

fn line_suffix(line: Option<usize>) -> String {
    match line {
        Some(l) => format!(":{l}"),
        None => String::new(),
    }
}

impl ScenarioError {
    /// The 1-based line the error points at, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            ScenarioError::Syntax { line, .. } => Some(*line),
            ScenarioError::Invalid { line, .. } => *line,
            ScenarioError::Io { .. } | ScenarioError::Override { .. } => None,
        }
    }
}

/// An error found while resolving, before it is given a file and line.
#[derive(Debug, Clone)]
pub(crate) struct Fail {
    /// Byte range in the source (or an override sentinel, see `Spans`).
    pub span: Option<Range<usize>>,
    /// What is wrong (``robot `r1` ``, `world`, ...).
    pub what: String,
    /// Why.
    pub reason: String,
}

impl Fail {
    pub(crate) fn new(
        span: Option<Range<usize>>,
        what: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        Fail {
            span,
            what: what.into(),
            reason: reason.into(),
        }
    }
}

/// Maps byte offsets to lines, and override sentinels back to overrides.
///
/// Values that come from an override `KEY=VALUE` are given a span that starts
/// past the end of the source (`base + index of the override`), so an error
/// about them can name the override instead of a line.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Spans<'a> {
    pub source: &'a str,
    pub origin: &'a str,
    pub overrides: &'a [(String, String)],
}

impl Spans<'_> {
    /// First offset that marks an override (one past the source's end).
    pub(crate) fn base(&self) -> usize {
        self.source.len() + 1
    }

    /// The sentinel span of override `i`.
    pub(crate) fn sentinel(&self, i: usize) -> Range<usize> {
        let s = self.base() + i;
        s..s
    }

    /// The override a span stands for, if it is a sentinel.
    pub(crate) fn override_of(&self, span: &Range<usize>) -> Option<usize> {
        let b = self.base();
        (span.start >= b && span.start - b < self.overrides.len()).then(|| span.start - b)
    }

    /// 1-based line and column of a byte offset in the source.
    pub(crate) fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.source.len());
        let bytes = &self.source.as_bytes()[..offset];
        let line = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        let column = match self.source.get(line_start..offset) {
            Some(s) => s.chars().count(),
            None => offset - line_start,
        } + 1;
        (line, column)
    }

    /// Turns a `Fail` into the public error.
    pub(crate) fn error(&self, fail: Fail) -> ScenarioError {
        if let Some(span) = &fail.span
            && let Some(i) = self.override_of(span)
        {
            let reason = if fail.what.is_empty() {
                fail.reason
            } else {
                format!("{}: {}", fail.what, fail.reason)
            };
            return ScenarioError::Override {
                key: self.overrides[i].0.clone(),
                reason,
            };
        }
        ScenarioError::Invalid {
            origin: self.origin.to_string(),
            line: fail.span.map(|s| self.line_col(s.start).0),
            what: fail.what,
            reason: fail.reason,
        }
    }
}
