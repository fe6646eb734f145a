//! The progress bar of a simulated run (`run`, `sim log`): simulated seconds against the run's expected end.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A bar for scenario `name` of `duration` simulated seconds; hidden when `quiet` or stderr is no terminal.
pub fn bar(name: &str, duration: f64, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new((duration * 10.0) as u64);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {prefix} sim s, {elapsed} wall, ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(name.to_string());
    bar
}

/// Moves `bar` to simulated time `t` of a run expected to end at `end` (what the runner's progress reports).
pub fn show(bar: &ProgressBar, t: f64, end: f64) {
    bar.set_length((end.max(t) * 10.0) as u64);
    bar.set_position((t * 10.0) as u64);
    bar.set_prefix(format!("{t:.0}/{end:.0}"));
}
