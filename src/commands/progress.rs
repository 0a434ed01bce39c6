//! Progress of long work ([`crate::render::RenderObserver`]), so that the renderer itself
//! knows no UI crate: on a terminal an indicatif bar with the time left; otherwise (a pipe, a
//! log file, a Slurm task's output) one plain line every [`LINE_EVERY`] or every 10 % of the
//! work (at most one a second), and one at the end, with done/total and the time left, as
//! batch logs want.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::render::RenderObserver;

/// Longest time between two progress lines off a terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(5);

/// Progress on stderr, labelled with what is being done; nothing unless asked for.
pub struct Progress {
    label: String,
    kind: Kind,
}

enum Kind {
    Hidden,
    Bar(ProgressBar),
    Lines(Mutex<Lines>),
}

/// The state of line-by-line progress.
struct Lines {
    start: Instant,
    total: u64,
    done: u64,
    /// When, and at what share of the work, the last line was written.
    last: (Instant, u64),
}

impl Progress {
    /// Progress labelled `label`, shown when `show`: as a bar on a terminal, else as lines.
    pub fn new(show: bool, label: &str) -> Self {
        let kind = match (show, std::io::stderr().is_terminal()) {
            (false, _) => Kind::Hidden,
            (true, true) => {
                let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
                bar.set_style(
                    ProgressStyle::with_template(
                        "{prefix:>8} [{bar:40}] {percent:>3}%  {elapsed} elapsed, ~{eta} left",
                    )
                    .expect("a valid progress template")
                    .progress_chars("=> "),
                );
                bar.set_prefix(label.to_string());
                Kind::Bar(bar)
            }
            (true, false) => {
                let now = Instant::now();
                Kind::Lines(Mutex::new(Lines { start: now, total: 0, done: 0, last: (now, 0) }))
            }
        };
        Self { label: label.to_string(), kind }
    }
}

impl Lines {
    /// The line to write now, if one is due: every [`LINE_EVERY`], every 10 % (at most one a
    /// second), and at the end.
    fn due(&mut self) -> Option<String> {
        let now = Instant::now();
        let tenth = self.total.div_ceil(10).max(1);
        let finished = self.done >= self.total;
        let since = now - self.last.0;
        let step = self.done - self.last.1 >= tenth && since >= Duration::from_secs(1);
        if !(finished || since >= LINE_EVERY || step) {
            return None;
        }
        self.last = (now, self.done);
        let elapsed = now - self.start;
        let share = self.done as f64 / self.total.max(1) as f64;
        let left = if share > 0.0 { elapsed.as_secs_f64() * (1.0 - share) / share } else { f64::NAN };
        Some(format!(
            "{:.0}% ({}/{}), {:.1} s elapsed, ~{:.1} s left",
            100.0 * share,
            self.done,
            self.total,
            elapsed.as_secs_f64(),
            left
        ))
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Kind::Bar(bar) = &self.kind {
            bar.finish_and_clear();
        }
    }
}

impl RenderObserver for Progress {
    fn start(&self, total: u64) {
        match &self.kind {
            Kind::Hidden => {}
            Kind::Bar(bar) => bar.set_length(total),
            Kind::Lines(lines) => {
                let mut l = lines.lock().expect("progress lock");
                let now = Instant::now();
                (l.start, l.total, l.done, l.last) = (now, total, 0, (now, 0));
            }
        }
    }

    fn advance(&self, n: u64) {
        match &self.kind {
            Kind::Hidden => {}
            Kind::Bar(bar) => bar.inc(n),
            Kind::Lines(lines) => {
                let line = {
                    let mut l = lines.lock().expect("progress lock");
                    l.done = (l.done + n).min(l.total);
                    l.due()
                };
                if let Some(line) = line {
                    // A closed stderr does not stop the work.
                    let _ = writeln!(std::io::stderr(), "{:>8}: {line}", self.label);
                }
            }
        }
    }
}
