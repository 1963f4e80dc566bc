//! Runs `boot`'s world as the runner builds it and prints, every `STEP_MS`, the link as the
//! medium and the HM-10 see it: what each radio put on air and what the other made of it
//! (radio 0 = the module, 1 = the flight side), whether the phone is connected, and how many
//! telemetry messages it got; with `--frames AT`, every frame of the step that ends at or
//! after AT seconds after power-up. A debugging aid for a link that does not come up (issue
//! 28's findings were made with it): `cargo run --release -p pil --example debug_link --
//! FLIGHT.elf MODULE.elf SECONDS [STEP_MS] [--frames AT] [--sparky2]`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use pil::board::flight::FlightBoardKind;
use pil::runner::emulated::EmulatedBoards;
use pil::runner::{Kind, Options};
use pil::world::machine::Machine;
use si4432_sim::TraceFrame;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(flight), Some(module), Some(secs)) = (args.get(1), args.get(2), args.get(3)) else {
        eprintln!(
            "usage: debug_link FLIGHT.elf MODULE.elf SECONDS [STEP_MS] [--frames AT] [--sparky2]"
        );
        std::process::exit(2);
    };
    let Ok(secs) = secs.parse::<f64>() else {
        eprintln!("debug_link: SECONDS must be a number, got {secs}");
        std::process::exit(2);
    };
    let step_ms: u64 = args
        .get(4)
        .and_then(|s| s.parse().ok())
        .unwrap_or(250)
        .max(1);
    let frames = args
        .iter()
        .position(|a| a == "--frames")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse::<f64>().ok())
        .map(|s| (s * 1e9) as u64);
    let sparky2 = args.iter().any(|a| a == "--sparky2");
    if let Err(e) = run(flight, module, secs, step_ms, frames, sparky2) {
        eprintln!("debug_link: {e}");
        std::process::exit(1);
    }
}

fn run(
    flight: &str,
    module: &str,
    secs: f64,
    step_ms: u64,
    frames: Option<u64>,
    sparky2: bool,
) -> Result<(), String> {
    let mut opts = Options::new(Kind::Boot);
    if sparky2 {
        opts.board = FlightBoardKind::Sparky2;
    }
    opts.flight_image = PathBuf::from(flight);
    opts.module_image = PathBuf::from(module);
    opts.sitl.duration_s = Some(secs.max(0.001));
    let mut world = pil::runner::world(&EmulatedBoards, &opts)
        .map_err(|e| e.to_string())?
        .world;
    let medium = world.medium().clone();
    let end = ((flight_sitl::world::WARMUP_S + secs) * 1e9) as u64;
    let mut t = 0;
    while t < end {
        t += step_ms * 1_000_000;
        world.run_until(t);
        let seen = medium.with_trace(outcomes);
        if frames.is_some_and(|at| t >= at && t < at + step_ms * 1_000_000) {
            medium.with_trace(|all| all.iter().for_each(|fr| println!("{fr}")));
        }
        medium.clear_trace();
        let connected = world.module.board().hm10.connected();
        println!(
            "{:7.3} s  air {seen:?}  phone connected {connected}  telemetry {}",
            t as f64 * 1e-9,
            world.telemetry().len(),
        );
    }
    // The flight side's own account of its boot (RNG or clock fallback, sensors).
    if let Some((t, health)) = world.telemetry().iter().find_map(|(t, m)| match m {
        telemetry::messages::Message::Health(h) => Some((t, h)),
        _ => None,
    }) {
        println!("first Health at {:.3} s: {health:?}", *t as f64 * 1e-9);
    }
    Ok(())
}

/// (sender, outcome at the other radio) → frames.
fn outcomes(frames: &[TraceFrame]) -> BTreeMap<(usize, String), u32> {
    let mut seen = BTreeMap::new();
    for fr in frames {
        let mut name = |o: String| *seen.entry((fr.radio.0, o)).or_default() += 1;
        if fr.receptions.is_empty() {
            name("none".into());
        }
        for r in &fr.receptions {
            let o = format!("{:?}", r.outcome);
            name(o.split(['(', ' ']).next().unwrap_or_default().to_owned());
        }
    }
    seen
}
