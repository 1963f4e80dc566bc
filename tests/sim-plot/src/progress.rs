//! The progress bar of long host runs (a sweep, an identification, a log replay): on stderr,
//! only when stderr is a terminal and the user did not ask for `--quiet` or `--json`, so
//! pipes, CI logs and JSON consumers never see control characters.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

/// Whether a tool should draw live progress: not quiet, not printing JSON, stderr a terminal.
#[must_use]
pub fn wanted(quiet: bool, json: bool) -> bool {
    !quiet && !json && std::io::stderr().is_terminal()
}

/// A bar of `total` steps labelled `what` (e.g. "virtual s"), drawn on stderr when `show`
/// (see [`wanted`]), otherwise hidden (every call on it is then free of output).
#[must_use]
pub fn bar(total: u64, what: &str, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    let template = format!(
        "{{spinner}} {{msg}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {what} (eta {{eta}})"
    );
    // The template is a constant apart from `what`; fall back to the default style if a
    // caller's label ever breaks it.
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}
