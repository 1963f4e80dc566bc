//! The PIL's run of a scenario beside flight-sitl's of the same plan, sample by sample: the
//! altitude, climb rate, the pilot's throttle and the mean motor command, every `STEP` s
//! from `FROM` s — how the differences in the README's table were found.
//! `cargo run --release -p pil --example side_by_side -- hover|panic [FROM] [STEP]`
//! (the dist images).

use flight_sitl::Sample;
use pil::chips::motors::to_quad;
use pil::runner::emulated::EmulatedBoards;
use pil::runner::{HOVER_S, Kind, Options, run};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = match args.get(1).map(String::as_str) {
        Some("hover") => Kind::Hover,
        Some("panic") => Kind::Panic,
        _ => {
            eprintln!("usage: side_by_side hover|panic [FROM] [STEP]");
            std::process::exit(2);
        }
    };
    let number =
        |i: usize, default: f64| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default);
    let (from, step) = (number(2, 0.0), number(3, 0.5).max(0.001));
    let opts = Options::new(kind);
    let mut sitl_opts = opts.sitl.clone();
    if kind == Kind::Hover {
        sitl_opts.duration_s = Some(HOVER_S);
    }
    let pil = match run(&EmulatedBoards, &opts) {
        Ok(out) => out,
        Err(e) => {
            eprintln!("side_by_side: {e}");
            std::process::exit(1);
        }
    };
    let sitl = match flight_sitl::runner::run_kind(kind.sitl(), &sitl_opts) {
        Ok(out) => out,
        Err(e) => {
            eprintln!("side_by_side: flight-sitl: {e}");
            std::process::exit(1);
        }
    };
    println!("   t s |  PIL: alt m  climb  stick  motors | SITL: alt m  climb  stick  motors");
    let mut t = from;
    while t < pil.plan.duration_s {
        let at = |samples: &[Sample]| samples.iter().find(|s| s.t_s >= t).map(row);
        if let (Some(a), Some(b)) = (at(&pil.sitl.samples), at(&sitl.sitl.samples)) {
            println!("{t:6.2} | {a} | {b}");
        }
        t += step;
    }
}

fn row(s: &Sample) -> String {
    let motors = s.motors.iter().map(|m| to_quad(*m)).sum::<f32>() / 4.0;
    format!(
        "{:10.2} {:6.2} {:6.3} {:7.3}",
        s.altitude_m, s.climb_mps, s.pilot.throttle, motors
    )
}
