//! The PIL models the hardware, not the app: the same flight application built with a
//! different board glue fails as that hardware would. The flight image is built here from
//! the firmware source with a test knob `cargo xtask dist` never sets
//! (`pil::runner::variant`), kept in `target/pil-variants`:
//!
//! - `radio-cs-pc13`: the RFM22B's nSEL on PC13 instead of PA15 — the radio never hears the
//!   MCU, so `hover` never links (no telemetry, never armed);
//! - `iwdg-half`: the independent watchdog's timeout half the supervisor's feed period
//!   (25 ms at the fastest LSI against 50 ms) — `hover` reports watchdog resets.
//!
//! Each rebuilds flight-fw (its dependencies are those of `cargo xtask dist`, already built)
//! and flies 14 s of emulated time, so they are ignored
//! in a plain `cargo test`; run them with the dist images built (`cargo xtask dist`):
//! `cargo test --release -p pil --test hardware_not_app -- --ignored`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use pil::runner::emulated::EmulatedBoards;
use pil::runner::{Kind, Options, image, run};

fn build_variant(variant: &str) -> PathBuf {
    pil::runner::variant::build(variant).unwrap()
}

fn hover_with(flight_image: PathBuf) -> pil::runner::Outcome {
    let mut o = Options::new(Kind::Hover);
    o.flight_image = flight_image;
    o.module_image = image::dist_dir().join("module-nrf52840.elf");
    // 10 s after the warm-up: the take-off and the climb, long enough for either fault.
    o.sitl.duration_s = Some(10.0);
    run(&EmulatedBoards, &o).expect("the run is made")
}

#[test]
#[ignore = "builds a firmware variant and flies 14 s emulated: run with --ignored"]
fn a_radio_chip_select_on_the_wrong_pin_never_links() {
    let out = hover_with(build_variant("radio-cs-pc13"));
    assert_eq!(
        out.pil.telemetry_messages, 0,
        "no telemetry ever reached the phone"
    );
    assert_eq!(out.report.armings, 0, "never armed: no sticks ever arrived");
    assert!(
        out.report.max_altitude_m < 0.1,
        "never flew: {}",
        out.report.max_altitude_m
    );
    assert!(!out.failed.is_empty(), "hover's criteria fail");
}

#[test]
#[ignore = "builds a firmware variant and flies 14 s emulated: run with --ignored"]
fn a_halved_watchdog_timeout_resets_the_flight_controller() {
    let out = hover_with(build_variant("iwdg-half"));
    let [flight, _] = &out.images;
    assert!(
        flight.stats.watchdog_resets > 0,
        "watchdog resets: {}",
        flight.stats.watchdog_resets
    );
    assert_eq!(
        out.report.watchdog_resets.flight,
        flight.stats.watchdog_resets
    );
}
