//! `cargo run --release -p flight-sitl -- SCENARIO [options]`: flies a named scenario
//! through the firmware-in-the-loop world and prints its figures, as text or one JSON
//! object, optionally drawn; `table` runs the acceptance set and prints it as Markdown
//! (`--check` / `--write`: against the README's `runner-table` block);
//! `serve [ADDR]` serves the web ground station against the world (`serve/cli.rs`);
//! `log-figures [--check|--write]` measures the flight log's bytes per second per profile
//! (against the flight README's `log-profiles` block); `ulog-csv FILE.ulg --out DIR` writes
//! a log's data as pyulog's `ulog2csv` lays it out, read with this project's reader (CI holds
//! the two against each other, `ulog_check.py`); `overlay LOG.ulg --out DIR [--fps N]`
//! draws a log as transparent video-overlay frames (`overlay.rs`).
//! `--help` lists the options (`runner/cli.rs`).

use std::process::ExitCode;

use clap::Parser;
use flight_sitl::runner::{self, cli::Cli};
use flight_sitl::serve::cli::ServeCli;
use quad_sim::experiments::oneshot::{OneShotArgs, run_cli};
use sim_plot::docblock;

/// `flight-sitl oneshot-experiment`: the Tau Labs seed's OneShot125 experiment — the ESC
/// time constant identified with conventional 400 Hz PWM (asynchronous to a 500 Hz loop) and
/// with synchronous OneShot125 at 500 Hz and 1 kHz, several runs each, one-way ANOVA.
#[derive(Parser, Debug)]
#[command(name = "flight-sitl oneshot-experiment", version)]
struct OneShotCli {
    #[command(flatten)]
    args: OneShotArgs,
}

fn main() -> ExitCode {
    if std::env::args().nth(1).as_deref() == Some("serve") {
        let cli = ServeCli::parse_from(std::env::args().skip(1));
        return match cli.options() {
            Ok(o) => ExitCode::from(u8::try_from(flight_sitl::serve::main(o)).unwrap_or(1)),
            Err(e) => {
                eprintln!("flight-sitl serve: {e}");
                ExitCode::from(2)
            }
        };
    }
    if std::env::args().nth(1).as_deref() == Some("oneshot-experiment") {
        let cli = OneShotCli::parse_from(std::env::args().skip(1));
        return match run_cli(&cli.args) {
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("flight-sitl oneshot-experiment: {e}");
                ExitCode::FAILURE
            }
        };
    }
    if std::env::args().nth(1).as_deref() == Some("overlay") {
        let args: Vec<String> = std::env::args().skip(2).collect();
        return overlay(&args);
    }
    if std::env::args().nth(1).as_deref() == Some("ulog-csv") {
        let args: Vec<String> = std::env::args().skip(2).collect();
        return ulog_csv(&args);
    }
    if std::env::args().nth(1).as_deref() == Some("log-figures") {
        return log_figures(std::env::args().nth(2).as_deref());
    }
    let cli = Cli::parse();
    let opts = match cli.options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("flight-sitl: {e}");
            return ExitCode::from(2);
        }
    };
    let Some(kind) = cli.scenario.kind() else {
        let show = sim_plot::progress::wanted(cli.quiet, cli.json);
        // 4 link-cut rate modes, the link cut with a fix, 12 other scenarios.
        let bar = sim_plot::progress::bar(17, "runs", show);
        let rows = runner::acceptance::all(|name| {
            bar.set_message(name.to_owned());
            bar.inc(1);
        });
        bar.finish_and_clear();
        let mode = if cli.check {
            docblock::Mode::Check
        } else if cli.write {
            docblock::Mode::Write
        } else {
            docblock::Mode::Print
        };
        let readme = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
        return match rows.map(|rows| runner::acceptance::markdown(&rows)) {
            Ok(table) => match docblock::apply(&readme, "runner-table", &table, mode) {
                Ok(current) if current || mode == docblock::Mode::Write => ExitCode::SUCCESS,
                Ok(_) => {
                    eprintln!(
                        "flight-sitl: the README's runner table is stale: run `cargo run --release -p flight-sitl -- table --write`"
                    );
                    ExitCode::FAILURE
                }
                Err(e) => {
                    eprintln!("flight-sitl: {e}");
                    ExitCode::FAILURE
                }
            },
            Err(e) => {
                eprintln!("flight-sitl: {e}");
                ExitCode::FAILURE
            }
        };
    };
    let outcome = match runner::run_kind(kind, &opts) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("flight-sitl: {e}");
            return ExitCode::FAILURE;
        }
    };
    if cli.json {
        println!("{}", outcome.report.to_json());
    } else {
        print!("{}", outcome.report.to_text());
        let d = outcome.plan.duration_s;
        if let Some(cpu) = outcome.cpu_s {
            eprintln!(
                "speed: {:.0} × real time on the CPU ({d:.1} s virtual in {cpu:.3} s of CPU, the final run alone; {:.0} × by the wall clock)",
                d / cpu.max(1e-9),
                d / outcome.wall_s.max(1e-9),
            );
        } else {
            eprintln!(
                "speed: {:.0} × real time by the wall clock ({d:.1} s virtual in {:.3} s, the final run alone)",
                d / outcome.wall_s.max(1e-9),
                outcome.wall_s
            );
        }
    }
    if let Some(path) = &cli.log
        && let Err(e) = runner::write_logs(path, &outcome.sitl.flight_logs)
    {
        eprintln!("flight-sitl: --log {}: {e}", path.display());
        return ExitCode::FAILURE;
    }
    if let Some(path) = cli.plot.path(kind.name())
        && let Err(e) = runner::plot::figure(&outcome).save_as(&path, cli.plot.plot_format)
    {
        eprintln!("flight-sitl: plot {}: {e}", path.display());
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

/// `flight-sitl log-figures [--check|--write]`: the flight log's profiles measured, printed
/// or checked against (or written into) the flight README.
fn log_figures(arg: Option<&str>) -> ExitCode {
    let mode = match arg {
        None => docblock::Mode::Print,
        Some("--check") => docblock::Mode::Check,
        Some("--write") => docblock::Mode::Write,
        Some(other) => {
            eprintln!("flight-sitl log-figures: unknown argument {other:?} (--check or --write)");
            return ExitCode::from(2);
        }
    };
    let readme = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../flight/README.md");
    let result = flight_sitl::log_figures::table()
        .and_then(|table| docblock::apply(&readme, "log-profiles", &table, mode));
    match result {
        Ok(current) if current || mode == docblock::Mode::Write => ExitCode::SUCCESS,
        Ok(_) => {
            eprintln!(
                "flight-sitl: the flight README's log profiles are stale: run `cargo run --release -p flight-sitl -- log-figures --write`"
            );
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("flight-sitl log-figures: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `flight-sitl ulog-csv FILE.ulg --out DIR`: one CSV per subscription, named and laid out
/// as `ulog2csv` names them (`DIR/STEM_NAME_MULTIID.csv`).
fn ulog_csv(args: &[String]) -> ExitCode {
    let [file, flag, dir] = args else {
        eprintln!("usage: flight-sitl ulog-csv FILE.ulg --out DIR");
        return ExitCode::from(2);
    };
    if flag != "--out" {
        eprintln!(
            "flight-sitl ulog-csv: unknown argument {flag:?} (usage: ulog-csv FILE.ulg --out DIR)"
        );
        return ExitCode::from(2);
    }
    let path = std::path::Path::new(file);
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("log");
    let written = std::fs::read(path)
        .map_err(|e| format!("{file}: {e}"))
        .and_then(|bytes| flight_sitl::ulog_csv::tables(&bytes).map_err(|e| format!("{file}: {e}")))
        .and_then(|tables| {
            std::fs::create_dir_all(dir).map_err(|e| format!("{dir}: {e}"))?;
            for (suffix, text) in &tables {
                let out = std::path::Path::new(dir).join(format!("{stem}_{suffix}"));
                std::fs::write(&out, text).map_err(|e| format!("{}: {e}", out.display()))?;
            }
            Ok(tables.len())
        });
    match written {
        Ok(n) => {
            eprintln!("flight-sitl ulog-csv: {n} tables into {dir}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("flight-sitl ulog-csv: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `flight-sitl overlay LOG.ulg --out DIR [--fps N]`: the log's overlay frames.
fn overlay(args: &[String]) -> ExitCode {
    const USAGE: &str = "usage: flight-sitl overlay LOG.ulg --out DIR [--fps N]";
    let (file, dir, fps) = match args {
        [file, o, dir] if o == "--out" => (file, dir, Ok(30.0)),
        [file, o, dir, f, fps] if o == "--out" && f == "--fps" => (
            file,
            dir,
            fps.parse::<f64>().map_err(|e| format!("--fps {fps}: {e}")),
        ),
        _ => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    let fps = match fps {
        Ok(f) => f,
        Err(e) => {
            eprintln!("flight-sitl overlay: {e}");
            return ExitCode::from(2);
        }
    };
    let written = std::fs::read(file)
        .map_err(|e| format!("{file}: {e}"))
        .and_then(|bytes| flight_sitl::overlay::write(&bytes, std::path::Path::new(dir), fps));
    match written {
        Ok(n) => {
            eprintln!("flight-sitl overlay: {n} frames at {fps} fps into {dir}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("flight-sitl overlay: {e}");
            ExitCode::FAILURE
        }
    }
}
