//! `replay SENSORS.csv|FLIGHT.ulg --out EST.csv [--truth TRUTH.csv] [--plot DIR]
//! [--declination-deg D]` — runs the 14-state INS over a PX4-format sensor log, or a flight
//! controller's ULog log as flown (see tests/ins-sim/README.md; `replay --help` lists the
//! flags).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use flight_app::logging::Profile;
use ins_sim::compare::{compare, parse_reference};
use ins_sim::flight_log;
use ins_sim::replay::{HEADER, Options, Row, parse_sensors, run_with_progress};
use sim_plot::PlotArgs;

/// Run the 14-state INS/GPS EKF of flight-core over a PX4 ECL replay-format sensor log, or
/// a TauLink flight log (ULog), write one estimate row per IMU sample, and optionally
/// compare with a truth or PX4 EKF2 history (JSON on stdout) and plot both.
///
/// A flight log written with `log.profile full` (every sample) replays through the flight
/// core's own estimate stage with the logged settings — the estimate the flight flew on,
/// checked against the logged one (a line on stderr). With --noise or --tuning, or a log
/// of another profile, its samples go through the research INS as a CSV log's do.
#[derive(Parser, Debug)]
#[command(
    name = "replay",
    version,
    allow_negative_numbers = true,
    after_help = "Examples:
  replay iris_gps.csv --out est.csv
  replay iris_gps.csv --out est.csv --truth ekf2_history.csv --plot figs
  replay flight.csv --out est.csv --declination-deg -3.5 --plot figs --plot-format svg
  replay hover.ulg --out est.csv                  (as flown: flight-sitl hover --log hover.ulg)
  replay hover.ulg --out est.csv --noise gyro=0.003,accel=0.05

Exit status: 0 on success, 1 if a file cannot be read or holds nonsense (the message names
the line), 2 for a command-line error."
)]
struct Cli {
    /// The sensor log: PX4 ECL replay CSV lines `time_us,kind,values...` (imu, mag, baro,
    /// gps; other kinds are skipped), or a TauLink flight log (ULog, told by its magic).
    #[arg(value_name = "SENSORS.csv|FLIGHT.ulg")]
    sensors: PathBuf,
    /// Where to write the estimates, one CSV row per IMU sample.
    #[arg(long, value_name = "EST.csv")]
    out: PathBuf,
    /// A truth or EKF2 estimate history to compare with (our CSV format or PX4's
    /// change-indication files); prints the comparison as JSON on stdout.
    #[arg(long, value_name = "TRUTH.csv")]
    truth: Option<PathBuf>,
    /// Magnetic declination at the flight, degrees, east positive (-180..=180).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, value_parser = declination)]
    declination_deg: f32,
    /// The sensors' 1σ white noise, any subset: gyro=G (rad/s), accel=A (m/s²), mag=M (file
    /// units), baro=B (m), gps_pos=P (m), gps_alt=H (m), gps_vel=V (m/s); the estimator derives
    /// its measurement and process noise from them (the rest from the default tuning).
    #[arg(long, value_name = "NAME=VALUE,...")]
    noise: Option<String>,
    /// A file with the whole noise set (the same NAME=VALUE pairs, one per line or comma
    /// separated); `--noise` overrides single figures.
    #[arg(long, value_name = "FILE")]
    tuning: Option<PathBuf>,
    #[command(flatten)]
    plot: PlotArgs,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

fn declination(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if v.is_finite() && (-180.0..=180.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "must be a finite angle within -180..=180 degrees, got {s}"
        ))
    }
}

fn main() -> ExitCode {
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    match real_main(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("replay: {e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(args: &Cli) -> Result<(), String> {
    let shown = |p: &PathBuf| p.display().to_string();
    let bytes =
        std::fs::read(&args.sensors).map_err(|e| format!("{}: {e}", shown(&args.sensors)))?;
    let told = args.noise.is_some() || args.tuning.is_some();
    let records = if flight_log::is_ulog(&bytes) {
        let log = flight_log::read(&bytes).map_err(|e| format!("{}: {e}", shown(&args.sensors)))?;
        if !told && log.profile() == Profile::Full {
            return as_flown(args, &log);
        }
        flight_log::records(&log)
    } else {
        let text = String::from_utf8(bytes)
            .map_err(|_| format!("{}: neither ULog nor text", shown(&args.sensors)))?;
        parse_sensors(&text).map_err(|e| format!("{}: {e}", shown(&args.sensors)))?
    };
    let tuning = match &args.tuning {
        Some(path) => {
            Some(std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", shown(path)))?)
        }
        None => None,
    };
    let options = Options {
        declination_deg: args.declination_deg,
        noise: ins_sim::noise::combine(tuning.as_deref(), args.noise.as_deref())?,
        ..Options::default()
    };
    let bar = sim_plot::progress::bar(
        records.len() as u64,
        "records",
        sim_plot::progress::wanted(args.quiet, false),
    );
    bar.set_message("replaying");
    let rows = run_with_progress(&records, &options, |i| bar.set_position(i as u64));
    bar.finish_and_clear();
    write_rows(&args.out, &rows)?;
    finish(args, &rows)
}

fn write_rows(out: &PathBuf, rows: &[Row]) -> Result<(), String> {
    let mut csv = String::with_capacity(rows.len() * 120);
    csv.push_str(HEADER);
    csv.push('\n');
    for r in rows {
        csv.push_str(&r.to_csv());
        csv.push('\n');
    }
    std::fs::write(out, csv).map_err(|e| format!("{}: {e}", out.display()))
}

/// A full-profile flight log through the flight core's estimate stage: the rows, and how
/// they compare with the estimate logged in flight.
fn as_flown(args: &Cli, log: &flight_log::FlightLog) -> Result<(), String> {
    let replayed = flight_log::as_flown(log)?;
    let logged = flight_log::logged(log);
    let check = flight_log::compare(&replayed, &logged);
    eprintln!(
        "replay: as flown, {} samples; {} of {} logged estimates bit-identical, largest attitude difference {:.3e}",
        replayed.len(),
        check.identical,
        check.compared,
        check.max_quaternion_diff
    );
    let rows: Vec<Row> = replayed.iter().map(flight_log::Replayed::row).collect();
    write_rows(&args.out, &rows)?;
    finish(args, &rows)
}

/// The comparison with a truth and the plots, for either replay.
fn finish(args: &Cli, rows: &[Row]) -> Result<(), String> {
    let shown = |p: &PathBuf| p.display().to_string();
    let reference = match &args.truth {
        Some(path) => {
            let t = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", shown(path)))?;
            let reference = parse_reference(&t).map_err(|e| format!("{}: {e}", shown(path)))?;
            println!("{}", compare(rows, &reference, 10.0).to_json());
            Some(reference)
        }
        None => None,
    };
    if let Some(dir) = &args.plot.plot {
        ins_sim::plot::write_plots(dir, args.plot.plot_format, rows, reference.as_deref())
            .map_err(|e| format!("plot: {e}"))?;
    }
    Ok(())
}
