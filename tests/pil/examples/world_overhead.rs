//! The co-simulation's own cost, without any emulated CPU: 34 s of virtual time (the 4 s
//! warm-up and a 30 s hover) with scripted MCUs that do nothing, at the default 5 µs
//! quantum. `cargo run --release -p pil --example world_overhead` prints the CPU time; the
//! emulated cores' time comes on top.

use flight_app::control::mixer::QUAD_X;
use flight_app::outputs::Protocol;
use flight_sitl::{PilotInput, Scenario};
use pil::world::machine::FakeMachine;
use pil::world::{Radios, World, WorldConfig, flight_board, module_board};
use quad_sim::quad::QuadParams;

fn main() {
    let scenario = Scenario::new(
        flight_app::settings::Settings::default(),
        QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X),
        30.0,
        Box::new(|_| PilotInput::default()),
    );
    let config = WorldConfig::default();
    let mut radios = Radios::new(7, 0.0);
    let protocol = Protocol::Brushed {
        frequency_hz: 32_000,
    };
    let Some(fb) = flight_board(&config, &mut radios, protocol, &scenario) else {
        return;
    };
    let Some(mb) = module_board(&mut radios) else {
        return;
    };
    let flight = FakeMachine::new(fb, |_, _, _| {});
    let module = FakeMachine::new(mb, |_, _, _| {});
    let mut world = World::new(scenario, config, radios, flight, module);
    let cpu = pil::runner::report::thread_cpu_s();
    let wall = std::time::Instant::now();
    world.run_to_end();
    let used = pil::runner::report::thread_cpu_s()
        .zip(cpu)
        .map(|(a, b)| a - b);
    println!(
        "34 s virtual: {:.2} s of CPU ({:.2} s wall), {} quanta",
        used.unwrap_or(f64::NAN),
        wall.elapsed().as_secs_f64(),
        world.now_ns() / WorldConfig::default().quantum_ns
    );
}
