//! `cargo run --release -p pil -- SCENARIO [options]`: the images of `cargo xtask dist` (or
//! your own, `--flight-image` / `--module-image`) fly a named scenario on the emulated
//! boards; prints each image's SHA-256, then flight-sitl's figures plus each image's, as
//! text or one JSON object (`--json`). `--help` lists the options (`runner/cli.rs`).

use std::process::ExitCode;

use clap::Parser;
use pil::runner::cli::Cli;
use pil::runner::emulated::EmulatedBoards;
use pil::runner::image::Image;

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = cli.check() {
        eprintln!("pil: {e}");
        return ExitCode::from(2);
    }
    let opts = cli.options();
    for path in [&opts.flight_image, &opts.module_image] {
        match Image::load(path) {
            Ok(image) => eprintln!("{}  {}", image.sha256, path.display()),
            Err(e) => {
                eprintln!("pil: {e} (build the images with `cargo xtask dist`, or name yours)");
                return ExitCode::FAILURE;
            }
        }
    }
    let outcome = match pil::runner::run(&EmulatedBoards, &opts) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("pil: {e}");
            return ExitCode::FAILURE;
        }
    };
    if cli.json {
        println!("{}", outcome.to_json());
    } else {
        print!("{}", outcome.to_text());
    }
    let virtual_s = outcome.plan.duration_s + flight_sitl::WARMUP_S;
    match outcome.cpu_s {
        Some(cpu) => eprintln!(
            "speed: {:.2} × real time on the CPU ({virtual_s:.1} s virtual in {cpu:.1} s of CPU; {:.2} × by the wall clock)",
            virtual_s / cpu.max(1e-9),
            virtual_s / outcome.wall_s.max(1e-9)
        ),
        None => eprintln!(
            "speed: {:.2} × real time by the wall clock",
            virtual_s / outcome.wall_s.max(1e-9)
        ),
    }
    if outcome.failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
