//! Progress for long commands (`run`, `sweep`, `bench`): an indicatif bar
//! when stderr is a terminal, plain lines when it is not.
//!
//! Plain lines are for logs: one line per tenth of the way, at most one per
//! second, and a last line at [`Progress::finish`] only if an earlier line
//! was printed, so a run that is over in a second prints nothing.
//! `MRSIM_PROGRESS=bar|lines|off` overrides the choice.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// An indicatif bar on stderr.
    Bar,
    /// Plain lines on stderr.
    Lines,
    /// Nothing.
    Off,
}

impl Style {
    /// `MRSIM_PROGRESS` if set to `bar`, `lines` or `off`; otherwise a bar
    /// when stderr is a terminal and lines when it is not.
    pub fn detect() -> Self {
        match std::env::var("MRSIM_PROGRESS").as_deref() {
            Ok("bar") => Style::Bar,
            Ok("lines") => Style::Lines,
            Ok("off") => Style::Off,
            _ if std::io::stderr().is_terminal() => Style::Bar,
            _ => Style::Lines,
        }
    }
}

/// A progress indicator of `len` steps.
#[derive(Debug)]
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    style: Style,
    label: String,
    len: u64,
    pos: u64,
    message: String,
    last_tenth: Option<u64>,
    last_line: Option<Instant>,
    printed: Option<String>,
    finished: bool,
}

impl Progress {
    /// Minimum time between two plain lines.
    pub const LINE_INTERVAL: Duration = Duration::from_secs(1);

    /// A progress indicator of `len` steps named `label`, styled by
    /// [`Style::detect`].
    pub fn new(len: u64, label: &str) -> Self {
        Self::with_style(len, label, Style::detect())
    }

    /// The same with a given style.
    pub fn with_style(len: u64, label: &str, style: Style) -> Self {
        let bar = (style == Style::Bar).then(|| {
            let bar = indicatif::ProgressBar::new(len);
            let template = format!(
                "{label:>5} [{{elapsed_precise}}] {{bar:32.cyan/blue}} {{pos}}/{{len}} {{msg}}"
            );
            if let Ok(s) = indicatif::ProgressStyle::with_template(&template) {
                bar.set_style(s.progress_chars("=> "));
            }
            bar
        });
        Self {
            bar,
            style,
            label: label.to_string(),
            len,
            pos: 0,
            message: String::new(),
            last_tenth: None,
            last_line: None,
            printed: None,
            finished: false,
        }
    }

    /// How progress is shown.
    pub fn style(&self) -> Style {
        self.style
    }

    /// Changes the number of steps.
    pub fn set_length(&mut self, len: u64) {
        self.len = len;
        if let Some(b) = &self.bar {
            b.set_length(len);
        }
    }

    /// Sets the text after the counter.
    pub fn set_message(&mut self, msg: impl Into<String>) {
        self.message = msg.into();
        if let Some(b) = &self.bar {
            b.set_message(self.message.clone());
        }
    }

    /// Moves to step `pos`.
    pub fn set_position(&mut self, pos: u64) {
        self.pos = pos.min(self.len);
        if let Some(b) = &self.bar {
            b.set_position(self.pos);
        }
        if self.style == Style::Lines {
            self.maybe_line(Instant::now());
        }
    }

    /// Advances by `n` steps.
    #[cfg(test)]
    pub fn inc(&mut self, n: u64) {
        self.set_position(self.pos.saturating_add(n));
    }

    /// Ends the indicator: the bar stays on screen with its last state; in
    /// plain-lines mode a last line is printed if any line was.
    pub fn finish(&mut self) {
        if self.finished {
            return;
        }
        self.finished = true;
        if let Some(b) = &self.bar {
            b.finish();
        }
        if self.style == Style::Lines && self.printed.is_some() {
            let line = self.line();
            if self.printed.as_deref() != Some(line.as_str()) {
                eprintln!("{line}");
            }
        }
    }

    fn tenth(&self) -> u64 {
        (self.pos.min(self.len) * 10)
            .checked_div(self.len)
            .unwrap_or(10)
    }

    fn line(&self) -> String {
        let pct = (self.pos * 100).checked_div(self.len).unwrap_or(100);
        let mut s = format!("{}: {}/{} ({pct}%)", self.label, self.pos, self.len);
        if !self.message.is_empty() {
            s.push(' ');
            s.push_str(&self.message);
        }
        s
    }

    /// The plain line due at `now`, if any (and records it as printed).
    fn next_line(&mut self, now: Instant) -> Option<String> {
        let tenth = self.tenth();
        if self.last_tenth == Some(tenth) {
            return None;
        }
        match self.last_line {
            // The first line waits a second: short runs print nothing.
            None if self.last_tenth.is_none() => {
                self.last_tenth = Some(tenth);
                self.last_line = Some(now);
                return None;
            }
            Some(t) if now.saturating_duration_since(t) < Self::LINE_INTERVAL => return None,
            _ => {}
        }
        self.last_tenth = Some(tenth);
        self.last_line = Some(now);
        let line = self.line();
        self.printed = Some(line.clone());
        Some(line)
    }

    fn maybe_line(&mut self, now: Instant) {
        if let Some(line) = self.next_line(now) {
            eprintln!("{line}");
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(b) = &self.bar
            && !b.is_finished()
        {
            b.abandon();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines_over(p: &mut Progress, steps: &[(u64, u64)]) -> Vec<String> {
        let t0 = Instant::now();
        let mut out = Vec::new();
        for &(pos, ms) in steps {
            p.pos = pos;
            if let Some(l) = p.next_line(t0 + Duration::from_millis(ms)) {
                out.push(l);
            }
        }
        out
    }

    #[test]
    fn plain_lines_come_once_per_tenth_and_at_most_once_a_second() {
        let mut p = Progress::with_style(100, "run", Style::Lines);
        p.set_message("2 at goal");
        let lines = lines_over(
            &mut p,
            &[
                (0, 0),
                (5, 500),
                (12, 1200),
                (15, 1500),
                (25, 1900),
                (35, 2400),
                (40, 3000),
            ],
        );
        assert_eq!(
            lines,
            vec!["run: 12/100 (12%) 2 at goal", "run: 35/100 (35%) 2 at goal"]
        );
        assert_eq!(p.printed.as_deref(), Some("run: 35/100 (35%) 2 at goal"));
    }

    #[test]
    fn a_run_over_within_a_second_prints_no_line() {
        let mut p = Progress::with_style(100, "run", Style::Lines);
        let lines = lines_over(&mut p, &[(0, 0), (50, 300), (100, 900)]);
        assert!(lines.is_empty(), "{lines:?}");
        assert!(p.printed.is_none());
    }

    #[test]
    fn positions_are_clamped_to_the_length() {
        let mut p = Progress::with_style(10, "sweep", Style::Off);
        p.inc(4);
        p.inc(40);
        assert_eq!(p.pos, 10);
        assert_eq!(p.line(), "sweep: 10/10 (100%)");
        p.finish();
    }
}
