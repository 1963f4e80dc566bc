//! `ins-figures check|write` — the INS figures `tests/ins-sim/README.md` quotes as current
//! (the start-anywhere sweep and the rock-while-turning flight, `ins_sim::sweep`), run fresh
//! and checked against, or written into, the README's `ins-figures` block. CI runs `check`
//! (`.ci/sim-figures`).

use std::path::Path;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use sim_plot::docblock;

/// Run the INS sweep (every initial heading in 15° steps, tilts up to 30°) and the
/// rock-while-turning flight, and check or rewrite the table in tests/ins-sim/README.md.
#[derive(Parser, Debug)]
#[command(
    name = "ins-figures",
    version,
    after_help = "Examples:
  ins-figures check     # exit 1 when the README's table differs from a fresh run
  ins-figures write     # rewrite it

Exit status: 0 when current (check) or written, 1 when stale or unreadable, 2 for a
command-line error."
)]
struct Cli {
    /// `check` the README's block against a fresh run, or `write` it.
    #[arg(value_enum)]
    mode: Mode,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Mode {
    Check,
    Write,
}

const BLOCK: &str = "ins-figures";

fn main() -> ExitCode {
    let cli = Cli::parse();
    let starts = (ins_sim::sweep::TILTS_DEG.len() * ins_sim::sweep::HEADINGS_DEG.len()) as u64;
    let bar = sim_plot::progress::bar(
        starts + 1,
        "runs",
        sim_plot::progress::wanted(cli.quiet, false),
    );
    let mut sweep = Vec::new();
    for &tilt in &ins_sim::sweep::TILTS_DEG {
        for &heading in &ins_sim::sweep::HEADINGS_DEG {
            sweep.push(ins_sim::sweep::static_start(heading, tilt));
            bar.inc(1);
        }
    }
    let rock = ins_sim::sweep::rock_and_turn();
    bar.finish_and_clear();
    let table = ins_sim::sweep::table(&sweep, &rock);
    let readme = Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let mode = match cli.mode {
        Mode::Check => docblock::Mode::Check,
        Mode::Write => docblock::Mode::Write,
    };
    match docblock::apply(&readme, BLOCK, &table, mode) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) if matches!(cli.mode, Mode::Write) => ExitCode::SUCCESS,
        Ok(false) => {
            eprintln!(
                "ins-figures: the README's INS figures are stale: run `cargo run --release -p ins-sim --bin ins-figures -- write`"
            );
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("ins-figures: {e}");
            ExitCode::FAILURE
        }
    }
}
