//! The true random number generator (RM0090 §24): CR (RNGEN, IE), SR (DRDY, CECS, SECS,
//! CEIS, SEIS), DR. A new 32-bit word every 40 PLL48CLK periods (§24.3.1) from a seeded
//! generator (runs are reproducible); no 48 MHz clock, or one below HCLK/16, is a clock
//! error (CECS, CEIS) and no data — the path on which embassy's `next_u32` loops forever.

use sim_rng::SplitMix64;

const CR: u32 = 0x00;
const SR: u32 = 0x04;
const DR: u32 = 0x08;

const RNGEN: u32 = 1 << 2;
const IE: u32 = 1 << 3;
const DRDY: u32 = 1 << 0;
const CECS: u32 = 1 << 1;
const CEIS: u32 = 1 << 5;
const SEIS: u32 = 1 << 6;
/// RNG clock periods per word.
const PERIODS_PER_WORD: u64 = 40;

/// The RNG.
pub struct Rng {
    cr: u32,
    /// CEIS and SEIS (rc_w0).
    sticky: u32,
    ready_at: u64,
    word: u32,
    source: SplitMix64,
    /// The clocks that matter, as of the last access: PLL48CLK and HCLK.
    pll48: u32,
    hclk: u32,
    /// A dead noise source: DRDY never rises and no error is flagged (issue 29's "RNG
    /// waits have no timeouts").
    dead: bool,
}

impl Rng {
    /// Reset state drawing from `seed`.
    pub fn new(seed: u64) -> Self {
        let mut source = SplitMix64::new(seed ^ 0x7256_4E47);
        let word = source.next_u64() as u32;
        Self {
            cr: 0,
            sticky: 0,
            ready_at: u64::MAX,
            word,
            source,
            pll48: 0,
            hclk: 16_000_000,
            dead: false,
        }
    }

    /// Kills the noise source (or revives it).
    pub fn set_dead(&mut self, dead: bool) {
        self.dead = dead;
    }

    /// Back to reset values (the generator's sequence goes on).
    pub fn reset(&mut self) {
        self.cr = 0;
        self.sticky = 0;
        self.ready_at = u64::MAX;
    }

    /// The clocks at `now`: a clock that becomes good starts the next word then.
    pub fn set_clocks(&mut self, pll48: u32, hclk: u32, now: u64) {
        let was_ok = self.clock_ok();
        self.pll48 = pll48;
        self.hclk = hclk;
        if !was_ok && self.clock_ok() && self.cr & RNGEN != 0 {
            self.ready_at = now + self.word_ns();
        }
    }

    fn clock_ok(&self) -> bool {
        self.pll48 > 0 && u64::from(self.pll48) * 16 >= u64::from(self.hclk)
    }

    fn word_ns(&self) -> u64 {
        (PERIODS_PER_WORD * 1_000_000_000).div_ceil(u64::from(self.pll48.max(1)))
    }

    fn sr(&self, now: u64) -> u32 {
        let mut v = self.sticky;
        if self.cr & RNGEN != 0 {
            if !self.clock_ok() {
                v |= CECS | CEIS;
            } else if now >= self.ready_at && !self.dead {
                v |= DRDY;
            }
        }
        v
    }

    /// The next time DRDY rises.
    pub fn next_event(&self) -> u64 {
        if self.cr & (RNGEN | IE) == RNGEN | IE && self.clock_ok() && !self.dead {
            self.ready_at
        } else {
            u64::MAX
        }
    }

    /// The HASH_RNG interrupt line at `now`.
    pub fn irq(&self, now: u64) -> bool {
        self.cr & IE != 0 && self.sr(now) & (DRDY | CEIS | SEIS) != 0
    }

    /// Register read at `now`.
    pub fn read(&mut self, offset: u32, now: u64) -> Option<u32> {
        Some(match offset {
            CR => self.cr,
            SR => {
                let v = self.sr(now);
                self.sticky |= v & CEIS;
                v
            }
            DR => {
                if self.sr(now) & DRDY == 0 {
                    return Some(0);
                }
                let w = self.word;
                self.word = self.source.next_u64() as u32;
                self.ready_at = now + self.word_ns();
                w
            }
            _ => return None,
        })
    }

    /// Register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        match offset {
            CR => {
                let was = self.cr & RNGEN != 0;
                self.cr = value & (RNGEN | IE);
                if !was && value & RNGEN != 0 {
                    self.ready_at = now + self.word_ns();
                }
            }
            SR => self.sticky &= value | !(CEIS | SEIS),
            DR => {}
            _ => return None,
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_arrive_every_40_rng_clocks_and_depend_on_the_seed() {
        let mut r = Rng::new(1);
        r.set_clocks(48_000_000, 168_000_000, 0);
        r.write(CR, RNGEN, 0);
        assert_eq!(r.read(SR, 833), Some(0));
        assert_eq!(r.read(SR, 834), Some(DRDY));
        let a = r.read(DR, 834).unwrap();
        assert_eq!(r.read(SR, 835), Some(0));
        let b = r.read(DR, 834 + 834).unwrap();
        assert_ne!(a, b);
        let mut other = Rng::new(2);
        other.set_clocks(48_000_000, 168_000_000, 0);
        other.write(CR, RNGEN, 0);
        assert_ne!(other.read(DR, 1_000).unwrap(), a);
    }

    #[test]
    fn without_the_48_mhz_clock_there_is_only_a_clock_error() {
        let mut r = Rng::new(1);
        r.set_clocks(0, 16_000_000, 0);
        r.write(CR, RNGEN | IE, 0);
        assert_eq!(r.read(SR, 1_000_000), Some(CECS | CEIS));
        assert!(r.irq(1_000_000));
        assert_eq!(r.read(DR, 1_000_000), Some(0));
        r.set_clocks(48_000_000, 168_000_000, 2_000_000);
        r.write(SR, !CEIS, 2_000_000);
        assert_eq!(r.read(SR, 2_000_000), Some(0));
        assert_eq!(r.read(SR, 2_000_834), Some(DRDY));
    }
}
