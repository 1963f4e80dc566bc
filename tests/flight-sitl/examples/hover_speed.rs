//! How fast the world runs: 30 s of hover at F500 (take-off, then hover throttle), the
//! wall time and the speed-up over real time. `cargo run --release -p flight-sitl --example
//! hover_speed`.

use std::time::Instant;

use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, WARMUP_S, run};
use telemetry::link::RateMode;

fn main() {
    let (quad, settings) = default_airframe();
    let pilot = Box::new(|t: f64| {
        let base = PilotInput::default();
        if (0.5..2.0).contains(&t) {
            PilotInput { yaw: 1.0, ..base }
        } else if (2.5..3.5).contains(&t) {
            PilotInput {
                throttle: 0.17,
                ..base
            }
        } else if t >= 3.5 {
            PilotInput {
                throttle: 0.11,
                ..base
            }
        } else {
            base
        }
    });
    let duration_s = 30.0;
    let start = Instant::now();
    let sitl = run(Scenario {
        rate: RateMode::F500,
        ..Scenario::new(settings, quad, duration_s, pilot)
    });
    let wall_s = start.elapsed().as_secs_f64();
    let simulated_s = duration_s + WARMUP_S;
    let top = sitl
        .samples
        .iter()
        .map(|s| s.altitude_m)
        .fold(0.0, f64::max);
    println!(
        "hover 30 s at F500 (+{WARMUP_S} s boot and bind window): {wall_s:.2} s wall, {:.0}× real time; {} samples, max altitude {top:.1} m, resets {:?}",
        simulated_s / wall_s,
        sitl.samples.len(),
        sitl.watchdog_resets
    );
}
