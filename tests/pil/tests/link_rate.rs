//! The link's slot rate with the dist images (issue 28): once the flight side has locked, the
//! module's master sends every uplink slot of F250 at 1:4 telemetry (187.5 a second), the
//! flight radio hears them and the master hears every downlink — and it stays so.
//!
//! Before, the module's master awaited each SPI transfer (≈ 70 µs a register access at
//! 64 MHz): its uplinks went on air ≈ 300 µs late and the first after every downlink slot was
//! skipped (≈ 120 a second), the flight radio heard ≈ 10 % of them. With that fixed, the
//! follower still lost the grid within 1–3 s: the flight loop's interrupt executor preempts
//! its packet read-out and receiver set-up at a phase that holds for seconds, and its window
//! (100 µs early) opened after the preamble until a resync. Needs `cargo xtask dist`; run
//! with `cargo test --release -p pil --test link_rate -- --ignored`.

use pil::runner::emulated::EmulatedBoards;
use pil::runner::{Kind, Options, world};
use si4432_sim::{Outcome, RadioId, TraceFrame};

/// The window measured, ns after power-up: the flight side has locked by 1.2 s.
const FROM_NS: u64 = 1_500_000_000;
const TO_NS: u64 = 5_000_000_000;
/// The module's radio is the medium's first, the flight side's the second.
const MODULE: RadioId = RadioId(0);
const FLIGHT: RadioId = RadioId(1);

/// Frames `from` sent, and how many of them the other radio received.
fn sent_and_heard(frames: &[TraceFrame], from: RadioId) -> (usize, usize) {
    let sent: Vec<_> = frames.iter().filter(|f| f.radio == from).collect();
    let heard = sent
        .iter()
        .filter(|f| {
            f.receptions
                .iter()
                .any(|r| matches!(r.outcome, Outcome::Delivered { .. }))
        })
        .count();
    (sent.len(), heard)
}

#[test]
#[ignore = "runs the dist images (cargo xtask dist) for 5 s of virtual time"]
fn after_lock_every_uplink_and_downlink_slot_is_sent_and_heard() {
    let opts = Options::new(Kind::Boot);
    let mut world = world(&EmulatedBoards, &opts)
        .map_err(|e| e.to_string())
        .expect("the dist images load")
        .world;
    world.run_until(FROM_NS);
    world.medium().clear_trace();
    world.run_until(TO_NS);
    let ((up, up_heard), (down, down_heard)) = world.medium().with_trace(|frames| {
        (
            sent_and_heard(frames, MODULE),
            sent_and_heard(frames, FLIGHT),
        )
    });
    // F250 at 1:4: 187.5 uplink and 62.5 downlink slots a second, 3.5 s.
    assert!(up >= 650, "uplinks sent: {up} of 656");
    assert!(down >= 215, "downlinks sent: {down} of 219");
    assert!(
        up_heard * 100 >= up * 99,
        "uplinks heard: {up_heard} of {up}"
    );
    assert!(
        down_heard * 100 >= down * 99,
        "downlinks heard: {down_heard} of {down}"
    );
}
