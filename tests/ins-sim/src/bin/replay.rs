//! `replay SENSORS.csv --out EST.csv [--truth TRUTH.csv] [--plot DIR] [--declination-deg D]`
//! — runs the 14-state INS over a PX4-format sensor log (see tests/ins-sim/README.md).

use std::process::ExitCode;

use ins_sim::compare::{compare, parse_reference};
use ins_sim::replay::{HEADER, Options, parse_sensors, run};

struct Args {
    sensors: String,
    out: String,
    truth: Option<String>,
    plot: Option<String>,
    declination_deg: f32,
    noise: Option<String>,
    tuning: Option<String>,
}

const USAGE: &str = "usage: replay SENSORS.csv --out EST.csv [--truth TRUTH.csv] [--plot DIR] [--declination-deg D] [--noise gyro=G,accel=A,mag=M,baro=B,gps_pos=P,gps_alt=H,gps_vel=V] [--tuning FILE]";

fn parse_args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let (mut sensors, mut out, mut truth, mut plot, mut declination_deg) =
        (None, None, None, None, 0.0);
    let (mut noise, mut tuning) = (None, None);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => out = it.next(),
            "--truth" => truth = it.next(),
            "--plot" => plot = it.next(),
            "--noise" => noise = it.next(),
            "--tuning" => tuning = it.next(),
            "--declination-deg" => {
                declination_deg = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or("--declination-deg needs a number")?;
            }
            "-h" | "--help" => return Err(USAGE.into()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}\n{USAGE}")),
            _ => sensors = Some(a),
        }
    }
    Ok(Args {
        sensors: sensors.ok_or(USAGE)?,
        out: out.ok_or(USAGE)?,
        truth,
        plot,
        declination_deg,
        noise,
        tuning,
    })
}

fn main() -> ExitCode {
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main() -> Result<(), String> {
    let args = parse_args()?;
    let text =
        std::fs::read_to_string(&args.sensors).map_err(|e| format!("{}: {e}", args.sensors))?;
    let records = parse_sensors(&text).map_err(|e| format!("{}: {e}", args.sensors))?;
    let tuning = match &args.tuning {
        Some(path) => Some(std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?),
        None => None,
    };
    let options = Options {
        declination_deg: args.declination_deg,
        noise: ins_sim::noise::combine(tuning.as_deref(), args.noise.as_deref())?,
        ..Options::default()
    };
    let rows = run(&records, &options);
    let mut csv = String::with_capacity(rows.len() * 120);
    csv.push_str(HEADER);
    csv.push('\n');
    for r in &rows {
        csv.push_str(&r.to_csv());
        csv.push('\n');
    }
    std::fs::write(&args.out, csv).map_err(|e| format!("{}: {e}", args.out))?;
    let reference = match &args.truth {
        Some(path) => {
            let t = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
            let reference = parse_reference(&t).map_err(|e| format!("{path}: {e}"))?;
            println!("{}", compare(&rows, &reference, 10.0).to_json());
            Some(reference)
        }
        None => None,
    };
    if let Some(dir) = &args.plot {
        ins_sim::plot::write_plots(std::path::Path::new(dir), &rows, reference.as_deref())
            .map_err(|e| format!("plot: {e}"))?;
    }
    Ok(())
}
