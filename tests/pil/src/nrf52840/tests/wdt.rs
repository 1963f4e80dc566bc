//! WDT as the board starts it (Watchdog::try_new: 250 ms, one reload register, paused while
//! halted, running while asleep) and the supervisor feeds it.

use m4_sim::Bus;
use m4_sim::bus::ResetCause;

use super::{chip, r, run_to, w};
use crate::nrf52840::{WDT_RELOAD, resetreas};

const WDT: u32 = 0x4001_0000;
/// 250 ms in 32 768 Hz ticks, as board.rs computes it.
const CRV: u32 = 32_768 * 250 / 1_000;

fn start(c: &mut super::Chip, t: u64) {
    assert_eq!(r(c, WDT + 0x400, t), 0, "RUNSTATUS");
    w(c, WDT + 0x50C, 1, t); // SLEEP run, HALT pause
    w(c, WDT + 0x304, 1, t);
    w(c, WDT + 0x504, CRV, t);
    w(c, WDT + 0x508, 1, t);
    w(c, WDT + 0x000, 1, t);
    w(c, WDT + 0x600, WDT_RELOAD, t);
}

#[test]
fn fed_it_never_fires() {
    let mut c = chip();
    start(&mut c, 0);
    for k in 1..=20u64 {
        let t = k * 100_000_000;
        run_to(&mut c, t);
        assert_eq!(c.take_reset_request(), None);
        w(&mut c, WDT + 0x600, WDT_RELOAD, t);
    }
    assert_eq!(c.watchdog_timeouts(), 0);
}

#[test]
fn starved_it_times_out_after_crv_plus_one_ticks_then_resets() {
    let mut c = chip();
    start(&mut c, 0);
    // (8192 + 1) / 32 768 Hz = 250.03 ms; the TIMEOUT interrupt is on, so the reset
    // follows two 32 kHz cycles later.
    let expiry = (8_193u128 * 30_517_578_125).div_ceil(1_000_000) as u64;
    run_to(&mut c, expiry - 1);
    assert_eq!(r(&mut c, WDT + 0x100, expiry - 1), 0);
    run_to(&mut c, expiry);
    assert_eq!(r(&mut c, WDT + 0x100, expiry), 1, "TIMEOUT");
    assert_eq!(c.take_reset_request(), None);
    run_to(&mut c, expiry + 61_036);
    assert_eq!(c.take_reset_request(), Some(ResetCause::Watchdog));
    c.reset(ResetCause::Watchdog);
    assert_eq!(c.reset_reason() & resetreas::DOG, resetreas::DOG);
    assert_eq!(
        r(&mut c, WDT + 0x400, expiry + 61_036),
        0,
        "a watchdog reset stops it"
    );
}

#[test]
fn it_keeps_running_through_a_soft_reset_and_locks_its_configuration() {
    let mut c = chip();
    start(&mut c, 0);
    c.advance(1_000_000);
    c.reset(ResetCause::Other);
    assert_eq!(r(&mut c, WDT + 0x400, 1_000_000), 1);
    w(&mut c, WDT + 0x504, 0xFFFF, 1_000_000);
    assert_eq!(r(&mut c, WDT + 0x504, 1_000_000), CRV);
}

#[test]
fn paused_in_sleep_when_configured_so() {
    let mut c = chip();
    w(&mut c, WDT + 0x50C, 0, 0); // SLEEP pause
    w(&mut c, WDT + 0x504, CRV, 0);
    w(&mut c, WDT + 0x000, 1, 0);
    c.sleeping(true, 100_000_000);
    c.sleeping(false, 1_100_000_000);
    run_to(&mut c, 1_200_000_000);
    assert_eq!(c.watchdog_timeouts(), 0, "150 ms counted of 250");
    run_to(&mut c, 1_260_000_000);
    assert_eq!(c.watchdog_timeouts(), 1);
}
