//! CLOCK: the HFXO and LFXO start-ups embassy-nrf's `init` waits for, a dead crystal, the
//! POWER_CLOCK interrupt line, RESETREAS and the retained GPREGRET.

use m4_sim::Bus;
use m4_sim::bus::ResetCause;

use super::{chip, chip_with, irq, r, w};
use crate::nrf52840::{ClockFaults, Config, resetreas};

const TASKS_HFCLKSTART: u32 = 0x4000_0000;
const EVENTS_HFCLKSTARTED: u32 = 0x4000_0100;
const TASKS_LFCLKSTART: u32 = 0x4000_0008;
const EVENTS_LFCLKSTARTED: u32 = 0x4000_0104;
const LFCLKSRC: u32 = 0x4000_0518;
const LFCLKSTAT: u32 = 0x4000_0418;
const INTENSET: u32 = 0x4000_0304;

#[test]
fn hfxo_starts_in_0_36_ms_and_raises_the_power_clock_interrupt() {
    let mut c = chip();
    w(&mut c, INTENSET, 1, 0);
    w(&mut c, EVENTS_HFCLKSTARTED, 0, 1_000);
    w(&mut c, TASKS_HFCLKSTART, 1, 1_000);
    assert_eq!(c.next_event_ns(), 361_000);
    assert_eq!(r(&mut c, EVENTS_HFCLKSTARTED, 360_999), 0);
    assert!(!irq(&c, 0));
    c.advance(361_000);
    assert_eq!(r(&mut c, EVENTS_HFCLKSTARTED, 361_000), 1);
    assert!(irq(&c, 0), "IRQ 0 = POWER_CLOCK");
    assert_eq!(
        r(&mut c, 0x4000_040C, 361_000),
        0x1_0001,
        "HFCLKSTAT: Xtal, running"
    );
    w(&mut c, EVENTS_HFCLKSTARTED, 0, 361_000);
    assert!(!irq(&c, 0));
}

#[test]
fn lfxo_takes_a_quarter_second() {
    let mut c = chip();
    w(&mut c, LFCLKSRC, 1, 0);
    w(&mut c, TASKS_LFCLKSTART, 1, 0);
    assert_eq!(r(&mut c, EVENTS_LFCLKSTARTED, 249_999_999), 0);
    assert_eq!(r(&mut c, EVENTS_LFCLKSTARTED, 250_000_000), 1);
    assert_eq!(r(&mut c, LFCLKSTAT, 250_000_000), 0x1_0001);
}

#[test]
fn lfrc_takes_0_6_ms() {
    let mut c = chip();
    w(&mut c, TASKS_LFCLKSTART, 1, 0);
    assert_eq!(c.next_event_ns(), 600_000);
}

#[test]
fn a_dead_crystal_never_starts() {
    let mut c = chip_with(Config {
        clock_faults: ClockFaults {
            hfxo_dead: true,
            lfxo_dead: true,
        },
        ..Config::default()
    });
    w(&mut c, TASKS_HFCLKSTART, 1, 0);
    w(&mut c, LFCLKSRC, 1, 0);
    w(&mut c, TASKS_LFCLKSTART, 1, 0);
    // What embassy-nrf's `while events_hfclkstarted == 0 {}` would see for ever.
    assert_eq!(r(&mut c, EVENTS_HFCLKSTARTED, 10_000_000_000), 0);
    assert_eq!(r(&mut c, EVENTS_LFCLKSTARTED, 10_000_000_000), 0);
    assert!(!c.hfxo_running());
}

#[test]
fn resetreas_accumulates_and_gpregret_survives_all_but_power_on() {
    let mut c = chip();
    w(&mut c, 0x4000_051C, 0xA5, 0);
    c.reset(ResetCause::Watchdog);
    c.reset(ResetCause::Other);
    assert_eq!(c.reset_reason(), resetreas::DOG | resetreas::SREQ);
    assert_eq!(r(&mut c, 0x4000_051C, 0), 0xA5);
    w(&mut c, 0x4000_0400, resetreas::DOG, 0);
    assert_eq!(c.reset_reason(), resetreas::SREQ);
    c.reset(ResetCause::PowerOn);
    assert_eq!(c.reset_reason(), 0);
    assert_eq!(r(&mut c, 0x4000_051C, 0), 0);
}

#[test]
fn mainregstatus_says_high_voltage_mode_and_dcdc_enables_stick() {
    let mut c = chip();
    assert_eq!(r(&mut c, 0x4000_0640, 0), 1);
    w(&mut c, 0x4000_0578, 1, 0);
    assert_eq!(r(&mut c, 0x4000_0578, 0), 1);
}

#[test]
fn a_lockup_resets_with_resetreas_lockup_and_keeps_the_watchdog() {
    let mut c = chip();
    w(&mut c, 0x4001_0000, 1, 0); // WDT TASKS_START
    c.lockup_reset();
    assert_eq!(c.reset_reason(), resetreas::LOCKUP);
    assert_eq!(r(&mut c, 0x4001_0400, 0), 1, "WDT RUNSTATUS");
}
