//! SAADC as the battery task uses it: AIN0, gain 1/6, internal 0.6 V reference, 40 µs
//! acquisition, 12 bits, calibrate then sample.

use super::{chip, irq, r, run_to, w};
use crate::wire::Pin;

const SAADC: u32 = 0x4000_7000;
const RESULT: u32 = 0x2000_0800;

#[test]
fn a_sample_of_the_divided_battery_is_volts_times_gain_over_reference() {
    let mut c = chip();
    // 8.4 V through 100 k / 22 k: 1.5148 V at P0.02 (AIN0).
    c.outside_mut()
        .volts
        .insert(Pin::new(0, 2), 8.4 * 22.0 / 122.0);
    // Saadc::new: ENABLE, RESOLUTION 12 bit, OVERSAMPLE bypass, CH[0] PSELP AIN0, CONFIG.
    w(&mut c, SAADC + 0x500, 1, 0);
    w(&mut c, SAADC + 0x5F0, 2, 0);
    w(&mut c, SAADC + 0x5F4, 0, 0);
    w(&mut c, SAADC + 0x510, 1, 0);
    w(&mut c, SAADC + 0x518, 5 << 16, 0); // RESP bypass, GAIN 1/6, REFSEL internal, TACQ 40 µs
    w(&mut c, SAADC + 0x308, 0x003F_FFFF, 0);
    // calibrate()
    w(&mut c, SAADC + 0x110, 0, 0);
    w(&mut c, SAADC + 0x304, 1 << 4, 0);
    w(&mut c, SAADC + 0x00C, 1, 0);
    run_to(&mut c, 42_000);
    assert!(irq(&c, 7), "CALIBRATEDONE on IRQ 7 = SAADC");
    w(&mut c, SAADC + 0x110, 0, 42_000);
    // sample(): RESULT.PTR/MAXCNT, END interrupt, START, SAMPLE.
    let t = 100_000;
    w(&mut c, SAADC + 0x62C, RESULT, t);
    w(&mut c, SAADC + 0x630, 1, t);
    w(&mut c, SAADC + 0x104, 0, t);
    w(&mut c, SAADC + 0x304, 1 << 1, t);
    w(&mut c, SAADC + 0x000, 1, t);
    w(&mut c, SAADC + 0x004, 1, t);
    run_to(&mut c, t + 41_999);
    assert_eq!(r(&mut c, SAADC + 0x104, t + 41_999), 0);
    run_to(&mut c, t + 42_000);
    assert!(irq(&c, 7));
    let raw = i16::from_le_bytes([c.ram()[0x800], c.ram()[0x801]]);
    // 1.5148 V · (1/6) / 0.6 V · 4096 = 1723.5 → 1723.
    assert_eq!(raw, 1723);
    assert_eq!(r(&mut c, SAADC + 0x634, t + 42_000), 1, "RESULT.AMOUNT");
}

#[test]
fn vddhdiv5_reads_the_supply() {
    let mut c = chip();
    w(&mut c, SAADC + 0x500, 1, 0);
    w(&mut c, SAADC + 0x5F0, 2, 0);
    w(&mut c, SAADC + 0x510, 0x0D, 0);
    w(&mut c, SAADC + 0x518, 0, 0); // GAIN 1/6, 3 µs
    w(&mut c, SAADC + 0x62C, RESULT, 0);
    w(&mut c, SAADC + 0x630, 1, 0);
    w(&mut c, SAADC + 0x000, 1, 0);
    w(&mut c, SAADC + 0x004, 1, 0);
    run_to(&mut c, 5_000);
    let raw = i16::from_le_bytes([c.ram()[0x800], c.ram()[0x801]]);
    // 5 V / 5 · (1/6) / 0.6 · 4096 = 1137.8 → 1137.
    assert_eq!(raw, 1137);
}
