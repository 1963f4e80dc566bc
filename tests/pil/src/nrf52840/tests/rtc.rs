//! RTC1 as embassy-time's driver uses it: CC[3] = 0x80_0000 for the half-period, OVRFLW and
//! COMPARE3 interrupts, CLEAR then START, alarms in CC[0].

use m4_sim::Bus;

use super::{chip, irq, r, run_to, start_lfxo, w};

const RTC1: u32 = 0x4001_1000;
const TICK_NS: u64 = 30_518; // 1 / 32 768 Hz, rounded up

fn embassy_time_init(c: &mut super::Chip, t: u64) {
    w(c, RTC1 + 0x54C, 0x80_0000, t); // CC[3]
    w(c, RTC1 + 0x304, (1 << 1) | (1 << 19), t); // INTENSET OVRFLW | COMPARE3
    w(c, RTC1 + 0x008, 1, t); // CLEAR
    w(c, RTC1 + 0x000, 1, t); // START
    assert_eq!(r(c, RTC1 + 0x504, t), 0, "COUNTER after CLEAR");
}

#[test]
fn counter_runs_at_32768_hz_once_the_lfclk_runs() {
    let mut c = chip();
    embassy_time_init(&mut c, 0);
    assert_eq!(
        r(&mut c, RTC1 + 0x504, 100_000_000),
        0,
        "no LFCLK, no counting"
    );
    let t0 = start_lfxo(&mut c, 100_000_000);
    assert_eq!(r(&mut c, RTC1 + 0x504, t0 + TICK_NS - 1), 0);
    assert_eq!(r(&mut c, RTC1 + 0x504, t0 + TICK_NS), 1);
    assert_eq!(r(&mut c, RTC1 + 0x504, t0 + 1_000_000_000), 32_768);
}

#[test]
fn compare_fires_when_the_counter_reaches_cc_and_raises_irq_17() {
    let mut c = chip();
    let t0 = start_lfxo(&mut c, 0);
    embassy_time_init(&mut c, t0);
    // An alarm 100 ticks ahead, as set_alarm writes it.
    w(&mut c, RTC1 + 0x540, 100, t0);
    w(&mut c, RTC1 + 0x304, 1 << 16, t0);
    let due = t0 + (100 * 1_000_000_000_000_000u128 / 32_768).div_ceil(1_000_000) as u64;
    assert_eq!(c.next_event_ns(), due);
    run_to(&mut c, due - 1);
    assert!(!irq(&c, 17));
    run_to(&mut c, due);
    assert!(irq(&c, 17), "IRQ 17 = RTC1");
    assert_eq!(r(&mut c, RTC1 + 0x140, due), 1);
}

#[test]
fn cc_equal_to_counter_waits_a_full_turn() {
    let mut c = chip();
    let t0 = start_lfxo(&mut c, 0);
    embassy_time_init(&mut c, t0);
    let t = t0 + 10 * TICK_NS;
    let now = r(&mut c, RTC1 + 0x504, t);
    w(&mut c, RTC1 + 0x540, now, t);
    w(&mut c, RTC1 + 0x304, 1 << 16, t);
    run_to(&mut c, t + 5_000_000);
    assert_eq!(r(&mut c, RTC1 + 0x140, t + 5_000_000), 0);
}

#[test]
fn half_period_and_overflow_come_at_2_23_and_2_24_ticks() {
    let mut c = chip();
    let t0 = start_lfxo(&mut c, 0);
    embassy_time_init(&mut c, t0);
    let half = t0 + ((1u128 << 23) * 30_517_578_125).div_ceil(1_000_000) as u64;
    assert_eq!(c.next_event_ns(), half);
    run_to(&mut c, half);
    assert_eq!(r(&mut c, RTC1 + 0x14C, half), 1, "COMPARE[3] at 0x80_0000");
    w(&mut c, RTC1 + 0x14C, 0, half);
    let wrap = t0 + ((1u128 << 24) * 30_517_578_125).div_ceil(1_000_000) as u64;
    run_to(&mut c, wrap);
    assert_eq!(r(&mut c, RTC1 + 0x104, wrap), 1, "OVRFLW");
    assert_eq!(r(&mut c, RTC1 + 0x504, wrap), 0);
    assert!(irq(&c, 17));
}

#[test]
fn trigovrflw_sets_the_counter_near_the_wrap() {
    let mut c = chip();
    let t0 = start_lfxo(&mut c, 0);
    embassy_time_init(&mut c, t0);
    w(&mut c, RTC1 + 0x00C, 1, t0);
    assert_eq!(r(&mut c, RTC1 + 0x504, t0), 0xFF_FFF0);
    let wrap = t0 + (16 * 30_517_578_125u128).div_ceil(1_000_000) as u64;
    run_to(&mut c, wrap);
    assert_eq!(r(&mut c, RTC1 + 0x104, wrap), 1);
}

#[test]
fn evten_decides_whether_an_rtc_event_reaches_the_ppi() {
    let mut c = chip();
    let t0 = start_lfxo(&mut c, 0);
    const RTC0: u32 = 0x4000_B000;
    const TIMER0: u32 = 0x4000_8000;
    const PPI: u32 = 0x4001_F000;
    // TIMER0 at 1 MHz; PPI CH5: RTC0 COMPARE[0] → TIMER0 CAPTURE[2].
    w(&mut c, TIMER0 + 0x508, 3, t0);
    w(&mut c, TIMER0 + 0x000, 1, t0);
    w(&mut c, PPI + 0x510 + 8 * 5, RTC0 + 0x140, t0);
    w(&mut c, PPI + 0x514 + 8 * 5, TIMER0 + 0x048, t0);
    w(&mut c, PPI + 0x504, 1 << 5, t0);
    w(&mut c, RTC0 + 0x540, 10, t0);
    w(&mut c, RTC0 + 0x000, 1, t0);
    let first = t0 + (10 * 30_517_578_125u128).div_ceil(1_000_000) as u64;
    run_to(&mut c, first);
    assert_eq!(
        r(&mut c, RTC0 + 0x140, first),
        1,
        "the event register is set"
    );
    assert_eq!(
        r(&mut c, TIMER0 + 0x548, first),
        0,
        "EVTEN clear: no PPI event"
    );
    // EVTENSET COMPARE0, next match 20 ticks on.
    w(&mut c, RTC0 + 0x344, 1 << 16, first);
    w(&mut c, RTC0 + 0x540, 30, first);
    let second = t0 + (30 * 30_517_578_125u128).div_ceil(1_000_000) as u64;
    run_to(&mut c, second);
    assert_eq!(
        r(&mut c, TIMER0 + 0x548, second),
        ((second - t0) / 1000) as u32
    );
}
