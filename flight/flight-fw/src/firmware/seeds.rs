//! The boot's random seeds (the phone's change session, the link's epoch nonces), from the
//! true RNG under a time limit. embassy-stm32's `Rng` waits for a word without one — from
//! `Rng::new` on (it discards the first) — and the RNG runs from the PLL's 48 MHz output:
//! a board whose clock tree came up wrong would hang there, before the watchdog runs. Here a
//! word not ready within [`RNG_WAIT_US`] (or a seed/clock error) falls back to the chip's
//! unique ID mixed with the cycle counter — unique per board and varying with boot timing,
//! not secret — and the boot reports it (`BootFacts::rng_fallback`).

use cortex_m::peripheral::DWT;
use embassy_stm32::Peri;
use embassy_stm32::pac;
use embassy_stm32::peripherals::RNG;

/// How long one word may take, µs (RM0090: 40 periods of the 48 MHz clock, under 1 µs).
const RNG_WAIT_US: u32 = 1_000;
/// The core's clock while the seeds are drawn (the clock tree is up), Hz.
const HCLK_HZ: u32 = 168_000_000;
/// The 96-bit unique device ID (RM0090 §39.1).
const UID: *const u32 = 0x1FFF_7A10 as *const u32;

/// A word of randomness, or `None` if the RNG gave nothing in time.
fn next(_rng: &mut Peri<'static, RNG>) -> Option<u32> {
    let rng = pac::RNG;
    // Timed on the cycle counter (on since `clocks::probe`): a delay loop's cycles per pass
    // depend on the flash and the pipeline, and one that assumed a cycle each waited about
    // four times the limit.
    let start = DWT::cycle_count();
    while DWT::cycle_count().wrapping_sub(start) < HCLK_HZ / 1_000_000 * RNG_WAIT_US {
        let sr = rng.sr().read();
        if sr.seis() || sr.ceis() {
            return None;
        }
        if sr.drdy() {
            return Some(rng.dr().read());
        }
    }
    None
}

/// The fallback: the unique ID folded and mixed with the cycle counter (SplitMix32-style
/// finaliser).
fn weak(salt: u32) -> u32 {
    // SAFETY: the unique ID is three readable words of system memory on every F405.
    let uid = unsafe {
        [
            UID.read_volatile(),
            UID.add(1).read_volatile(),
            UID.add(2).read_volatile(),
        ]
    };
    let mut z = uid[0] ^ uid[1].rotate_left(11) ^ uid[2].rotate_left(22) ^ salt;
    z ^= DWT::cycle_count();
    z = (z ^ (z >> 16)).wrapping_mul(0x85EB_CA6B);
    z = (z ^ (z >> 13)).wrapping_mul(0xC2B2_AE35);
    z ^ (z >> 16)
}

/// `N` seed words, and whether they are the fallback's.
pub fn seeds<const N: usize>(mut rng: Peri<'static, RNG>) -> ([u32; N], bool) {
    pac::RCC.ahb2enr().modify(|w| w.set_rngen(true));
    pac::RNG.cr().modify(|w| w.set_rngen(true));
    // The first word after enabling is discarded (RM0090 §24.3.1).
    let first = next(&mut rng);
    let mut words = [0u32; N];
    let mut fallback = first.is_none();
    for (i, w) in words.iter_mut().enumerate() {
        // Once the RNG failed, it is not waited for again: one limit, not one a word.
        let word = if fallback { None } else { next(&mut rng) };
        *w = match word {
            Some(word) => word,
            None => {
                fallback = true;
                weak(i as u32)
            }
        };
    }
    (words, fallback)
}
