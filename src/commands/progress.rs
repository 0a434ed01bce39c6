//! Progress on the terminal: an indicatif bar that watches a render
//! ([`crate::render::RenderObserver`]), so that the renderer itself knows no UI crate.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::render::RenderObserver;

/// A progress bar on stderr, labelled with what renders; hidden unless asked for and stderr
/// is a terminal. Cleared when dropped.
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar labelled `label`, drawn only when `show`.
    pub fn new(show: bool, label: &str) -> Self {
        let target = if show { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        let bar = ProgressBar::with_draw_target(None, target);
        bar.set_style(
            ProgressStyle::with_template("{prefix:>8} [{bar:40}] {percent:>3}%  {elapsed} elapsed, ~{eta} left")
                .expect("a valid progress template")
                .progress_chars("=> "),
        );
        bar.set_prefix(label.to_string());
        Self { bar }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

impl RenderObserver for Progress {
    fn start(&self, total: u64) {
        self.bar.set_length(total);
    }

    fn advance(&self, n: u64) {
        self.bar.inc(n);
    }
}
