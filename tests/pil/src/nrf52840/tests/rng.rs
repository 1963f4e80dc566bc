//! RNG as `Rng::blocking_next_u32` reads it: START, VALRDY per byte, VALUE.

use super::{chip_with, r, run_to, w};
use crate::nrf52840::Config;

const RNG: u32 = 0x4000_D000;

fn bytes(seed: u64) -> Vec<u32> {
    let mut c = chip_with(Config {
        rng_seed: seed,
        ..Config::default()
    });
    w(&mut c, RNG + 0x000, 1, 0);
    let mut out = Vec::new();
    for k in 1..=4u64 {
        let t = k * 30_000;
        run_to(&mut c, t - 1);
        assert_eq!(r(&mut c, RNG + 0x100, t - 1), 0, "a byte every 30 µs");
        run_to(&mut c, t);
        assert_eq!(r(&mut c, RNG + 0x100, t), 1);
        out.push(r(&mut c, RNG + 0x508, t));
        w(&mut c, RNG + 0x100, 0, t);
    }
    out
}

#[test]
fn bytes_come_every_30_us_and_follow_the_seed() {
    assert_eq!(bytes(7), bytes(7));
    assert_ne!(bytes(7), bytes(8));
    assert!(bytes(7).iter().all(|&b| b <= 0xFF));
}

#[test]
fn bias_correction_takes_120_us_a_byte() {
    let mut c = chip_with(Config::default());
    w(&mut c, RNG + 0x504, 1, 0);
    w(&mut c, RNG + 0x000, 1, 0);
    run_to(&mut c, 119_999);
    assert_eq!(r(&mut c, RNG + 0x100, 119_999), 0);
    run_to(&mut c, 120_000);
    assert_eq!(r(&mut c, RNG + 0x100, 120_000), 1);
}
