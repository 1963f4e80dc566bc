//! `magcal MAG.csv [--json]` — hard- and soft-iron magnetometer calibration from a log of
//! the frame being turned through every orientation (see tests/ins-sim/README.md).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use ins_sim::magcal::{calibrate, parse_csv, to_json, to_text};

/// Fit a hard-iron offset and soft-iron matrix (calibrated = matrix · (raw − offset)) to a
/// magnetometer log, check it (samples, rotation in more than one plane, coverage of
/// orientations, residual) and print it.
#[derive(Parser, Debug)]
#[command(
    name = "magcal",
    version,
    after_help = "Exit status: 0 with a calibration, 1 when the file cannot be read or the data \
cannot determine a calibration (the reason is printed), 2 for a command-line error."
)]
struct Cli {
    /// Magnetometer log, CSV with the header `time_us,mx,my,mz` (any consistent unit).
    #[arg(value_name = "MAG.csv")]
    input: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let shown = cli.input.display().to_string();
    let run = || -> Result<String, String> {
        let text = std::fs::read_to_string(&cli.input).map_err(|e| format!("{shown}: {e}"))?;
        let samples = parse_csv(&text).map_err(|e| format!("{shown}: {e}"))?;
        let cal = calibrate(&samples).map_err(|e| format!("{shown}: no calibration: {e}"))?;
        Ok(if cli.json {
            to_json(&cal, samples.len())
        } else {
            to_text(&cal, samples.len())
        })
    };
    match run() {
        Ok(out) => {
            println!("{}", out.trim_end());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("magcal: {e}");
            ExitCode::FAILURE
        }
    }
}
