//! Issue 29's glue fixes, each proven on the image: the scenario passes with the dist image
//! (`.ci/pil-figures` runs and checks every scenario on the dist images: its table in the
//! README) and fails with the same source built as the glue was before the fix
//! (`pil::runner::variant`, flight-fw `build.rs`) — what these tests fly:
//!
//! | finding | scenario | before the fix (variant) | after (dist) |
//! |---|---|---|---|
//! | stuck I²C → boot loop | `i2c-stuck` | `i2c-unguarded`: watchdog resets, never flies | no reset, the baro measures, flies |
//! | a panic leaves the motors on | `panic` | `fault-halts`: motors at their last duty until the watchdog | off within 1 ms |
//! | a reset in the air is a crash | `panic` | `no-resume`: a cold boot, the quad falls | resumed, motors back within 150 ms, still flying |
//! | flash accelerator off | `boot` | `flash-slow`: the CPU load of 5 wait states without caches | the load the figures assume |
//!
//! Each builds a variant (only flight-fw recompiles after `cargo xtask dist`) and flies it,
//! so they are ignored in a plain `cargo test`:
//! `cargo test --release -p pil --test findings -- --ignored --test-threads 1`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use pil::runner::emulated::EmulatedBoards;
use pil::runner::{Kind, Options, Outcome, image, run, variant};

fn fly(kind: Kind, flight_image: Option<PathBuf>) -> Outcome {
    let mut o = Options::new(kind);
    if let Some(image) = flight_image {
        o.flight_image = image;
    }
    o.module_image = image::dist_dir().join("module-nrf52840.elf");
    run(&EmulatedBoards, &o).expect("the run is made")
}

fn before(fix: &str, kind: Kind) -> Outcome {
    fly(kind, Some(variant::build(fix).unwrap()))
}

#[test]
#[ignore = "builds a firmware variant and flies it: run with --ignored"]
fn a_stuck_i2c_bus_boot_loops_without_the_bus_clear_and_timeouts() {
    let out = before("i2c-unguarded", Kind::I2cStuck);
    let resets = out.images[0].stats.watchdog_resets;
    eprintln!(
        "i2c-stuck, i2c-unguarded: {resets} watchdog resets, {} armings",
        out.report.armings
    );
    assert!(resets >= 3, "a boot loop: {resets} watchdog resets");
    assert_eq!(out.report.armings, 0, "never flies");
    assert_eq!(out.pil.baro_conversions, 0, "the bus never recovers");
    assert!(!out.failed.is_empty());
}

#[test]
#[ignore = "builds a firmware variant and flies it: run with --ignored"]
fn without_the_handler_and_the_resume_a_panic_leaves_the_motors_on_and_the_quad_falls() {
    // panic-probe's spin: the timers keep their duty until the watchdog.
    let out = before("fault-halts", Kind::Panic);
    let ms = out.pil.motors_off_after_ms.unwrap_or(f64::INFINITY);
    eprintln!("panic, fault-halts: motors off {ms} ms after the panic");
    assert!(ms > 50.0, "motors on for {ms} ms after the panic");
    assert!(
        out.failed
            .iter()
            .any(|f| f == "every motor off within 1 ms of the panic")
    );

    // A cold boot after the reset: no resume, the motors stay off, the quad falls.
    let out = before("no-resume", Kind::Panic);
    let r = out.report.resume.unwrap_or_default();
    eprintln!(
        "panic, no-resume: resumed {}, motors off for {:?} s, final state {}, unmet: {:?}",
        r.resumed, r.motors_off_for_s, out.report.final_state, out.failed
    );
    assert!(!r.resumed);
    assert!(
        r.motors_off_for_s.is_none_or(|s| s > 0.15),
        "motors back after {:?} s",
        r.motors_off_for_s
    );
    assert!(out.failed.iter().any(|f| f == "the flight resumed"));
}

#[test]
#[ignore = "builds a firmware variant and flies it: run with --ignored"]
fn the_flash_accelerator_is_what_the_cpu_figures_assume() {
    let dist = fly(Kind::Boot, None);
    let out = before("flash-slow", Kind::Boot);
    let fast = dist.images[0].stats.cpu_load_pct().unwrap();
    let slow = out.images[0].stats.cpu_load_pct().unwrap();
    // Without the ART's cache and prefetch every 128-bit flash line (four Thumb-2
    // instructions at best) waits 5 cycles: the same work takes a third longer or more.
    eprintln!("boot CPU load: {fast:.1} % with the accelerator, {slow:.1} % without");
    assert!(
        slow > 1.25 * fast,
        "CPU load {slow:.1} % without against {fast:.1} % with"
    );
}
