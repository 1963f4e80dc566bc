//! `oneshot [--runs N] [--json] [--plot DIR]`: the seed's OneShot125 experiment in
//! simulation — the identified motor τ with PWM at 400 Hz asynchronous to a 500 Hz loop,
//! OneShot125 synchronous at 500 Hz and at 1 kHz, a one-way ANOVA and the reduction in
//! percent (`quad_sim::experiments::oneshot`; the README explains the model).

use clap::Parser;
use quad_sim::experiments::oneshot::{OneShotArgs, run_cli};
use std::process::ExitCode;

/// Reproduce the seed's OneShot125 experiment: identify the motor time constant under three
/// output paths, several runs each, and test the difference (one-way ANOVA).
#[derive(Parser, Debug)]
#[command(
    name = "oneshot",
    version,
    after_help = "Examples:
  oneshot                          three 60 s runs per condition, table
  oneshot --runs 5 --plot out      five runs, box plot in out/oneshot.png
  oneshot --esc-filter 4 --json    ESCs that average four pulses, JSON

Exit status: 0 on success, 1 if the experiment fails, 2 for a command-line error."
)]
struct Cli {
    #[command(flatten)]
    args: OneShotArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run_cli(&cli.args) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("oneshot: {e}");
            ExitCode::FAILURE
        }
    }
}
