//! Progress on stderr: a bar when stderr is a terminal, nothing otherwise.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

pub struct Progress {
    bar: ProgressBar,
    quiet: bool,
}

impl Progress {
    /// A bar that shows only on a terminal and never with `--quiet`.
    pub fn new(quiet: bool) -> Progress {
        let target = if quiet || !std::io::stderr().is_terminal() {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        let bar = ProgressBar::with_draw_target(Some(1000), target);
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>18} [{bar:40}] {percent:>3}% {elapsed}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.enable_steady_tick(Duration::from_millis(200));
        Progress { bar, quiet }
    }

    /// Starts a stage with its name.
    pub fn stage(&self, name: &'static str) {
        self.bar.set_message(name);
        self.bar.set_position(0);
    }

    /// The library's progress: a new stage starts from 0.
    pub fn update(&self, stage: aureole::Stage, fraction: f64) {
        if self.bar.message() != stage.describe() {
            self.bar.set_message(stage.describe());
        }
        self.set(fraction);
    }

    /// Sets the stage's fraction done.
    pub fn set(&self, fraction: f64) {
        self.bar
            .set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
    }

    /// A line on stderr, the bar out of its way.
    pub fn println(&self, line: &str) {
        self.bar.suspend(|| say!("{line}"));
    }

    /// A note on stderr, unless `--quiet`.
    pub fn note(&self, line: &str) {
        if !self.quiet {
            self.println(line);
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
