//! Issue 13, "handset input lost": the Taranis' PPM stops (wire pulled) while the link is up.
//! Within 1 s the flight side, running the real follower with the flight firmware's 500 ms
//! silence timeout, must be in failsafe, and stay there while the input is gone, though the
//! link itself keeps running; when the PPM comes back, its channels fly again. Run at every
//! link rate the module's settings give (L50, M100, F250), PPM and CRSF input.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use common::{World, module_now, module_settings};
use module_core::channels::us_to_ticks;
use module_core::ports::LinkPort;
use module_core::settings::{InputProtocol, OutputProtocol, RateMode};
use taulink_handset::crsf::{Message, RcChannels, address};

/// The Taranis' 8 channel periods, µs; throttle (channel 3) high, as in a climb.
const WIDTHS_US: [u16; 8] = [1400, 1550, 1800, 1450, 1000, 2000, 1200, 1700];
/// EdgeTX's 8-channel PPM frame.
const FRAME_US: u64 = 22_500;
/// The input stops (no edge at or after this virtual time) …
const STOP_US: u64 = 2_000_000;
/// … and comes back.
const RESUME_US: u64 = 3_500_000;
/// Virtual run time.
const RUN_US: u64 = 5_000_000;
/// The flight firmware's link silence timeout (`flight-fw` tasks/link.rs `FAILSAFE_US`).
const FLIGHT_FAILSAFE_US: u64 = 500_000;

/// PPM frames from 50 ms on, none in [`STOP_US`, `RESUME_US`).
fn spawn_taranis(world: &mut World<'_>) {
    let app = world.app.clone();
    let time = world.time.clone();
    world.executor.spawn(async move {
        let mut frame_start = 50_000u64;
        loop {
            if (STOP_US..RESUME_US).contains(&frame_start) {
                frame_start = RESUME_US;
            }
            let mut t = frame_start;
            for width in WIDTHS_US.iter().map(|w| u64::from(*w)).chain([0]) {
                if (STOP_US..RESUME_US).contains(&t) {
                    break;
                }
                time.sleep_until(t).await;
                app.borrow_mut().on_ppm_edge(module_now(t) as u32);
                t += width;
            }
            frame_start += FRAME_US;
        }
    });
}

/// EdgeTX sending CRSF RC frames every 4 ms, none in [`STOP_US`, `RESUME_US`).
fn spawn_crsf_radio(world: &mut World<'_>) {
    let app = world.app.clone();
    let time = world.time.clone();
    let mut widths = [1500u16; 16];
    widths[..8].copy_from_slice(&WIDTHS_US);
    let mut frame = [0u8; 64];
    let len = Message::RcChannels(RcChannels::from_us(&widths))
        .encode(address::TX_MODULE, &mut frame)
        .unwrap()
        .len();
    world.executor.spawn(async move {
        let mut t = 50_000u64;
        loop {
            if (STOP_US..RESUME_US).contains(&t) {
                t = RESUME_US;
            }
            time.sleep_until(t).await;
            let mut app = app.borrow_mut();
            app.on_handset_bytes(module_now(t), &frame[..len]);
            app.on_handset_idle(module_now(t + 100));
            t += 4_000;
        }
    });
}

/// Runs one world; returns (failsafe entered, failsafe left) in virtual µs.
fn run(rate: RateMode, input: InputProtocol) -> (u64, u64) {
    let settings = module_settings(input, OutputProtocol::Off);
    let settings = module_core::settings::Settings { rate, ..settings };
    assert_eq!(settings.input_timeout_ms, 500, "factory input timeout");
    let mut world = World::with_flight_failsafe(settings, FLIGHT_FAILSAFE_US);
    match input {
        InputProtocol::Ppm => spawn_taranis(&mut world),
        InputProtocol::Crsf | InputProtocol::Crsf115200 | InputProtocol::Crsf921600 => {
            spawn_crsf_radio(&mut world)
        }
    }
    world.run_until(STOP_US);
    let expected: Vec<u16> = WIDTHS_US.iter().map(|w| us_to_ticks(*w)).collect();
    {
        let flight = world.flight.borrow();
        let (_, flying) = flight.outputs.last().expect("channels before the stop");
        assert_eq!(&flying[..8], &expected[..], "{rate:?} {input:?}");
        assert_eq!(flight.failsafe_changes.last().map(|c| c.1), Some(false));
    }
    // The module still hears the flight side while the input is gone: only the sticks stop.
    world.run_until(RESUME_US - 100_000);
    assert!(world.app.borrow().link().input_lost());
    assert!(world.app.borrow().link().stats().connected, "link kept up");
    world.run_until(RUN_US);

    let flight = world.flight.borrow();
    let changes: Vec<(u64, bool)> = flight
        .failsafe_changes
        .iter()
        .copied()
        .filter(|(t, _)| *t >= STOP_US)
        .collect();
    let [(entered, true), (left, false)] = changes[..] else {
        panic!("{rate:?} {input:?}: failsafe changes after the stop {changes:?}");
    };
    // Nothing but failsafe was flown in between: no update of the channels.
    assert!(
        !flight
            .outputs
            .iter()
            .any(|(t, _)| (entered..left).contains(t)),
        "{rate:?} {input:?}: channels flown while the input was lost"
    );
    let (_, back) = flight
        .outputs
        .last()
        .expect("channels after the input came back");
    assert_eq!(&back[..8], &expected[..], "{rate:?} {input:?}");
    assert!(
        left > RESUME_US,
        "{rate:?} {input:?}: left failsafe at {left}"
    );
    (entered, left)
}

#[test]
fn failsafe_within_one_second_of_the_handset_input_stopping_and_back_after() {
    for input in [InputProtocol::Ppm, InputProtocol::Crsf] {
        for rate in [RateMode::L50, RateMode::M100, RateMode::F250] {
            let (entered, left) = run(rate, input);
            let delay = entered - STOP_US;
            let back = left - RESUME_US;
            println!(
                "{input:?} {rate:?}: failsafe {delay} µs after the stop, left {back} µs after the input came back"
            );
            // The input timeout (500 ms) is honoured …
            assert!(
                delay >= 400_000,
                "{rate:?} {input:?}: failsafe too early, {delay} µs"
            );
            // … and the flight side is in failsafe within 1 s (issue 13).
            assert!(
                delay <= 1_000_000,
                "{rate:?} {input:?}: failsafe {delay} µs after the stop"
            );
            // PPM relocks after 5 clean frames; then the next uplink flies the sticks.
            assert!(
                back <= 500_000,
                "{rate:?} {input:?}: back {back} µs after the input"
            );
        }
    }
}
