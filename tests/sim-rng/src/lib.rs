//! The one seeded random source of every simulation in the workspace: SplitMix64 (Steele,
//! Lea, Flood 2014), so every simulated loss, bit error, fade and sensor noise sample is
//! reproducible from one seed. Used by the packet-level mock medium (`telemetry::mock`), the
//! virtual Si4432 and its RF medium (`si4432-sim`), the INS and quad simulators and the
//! simulators built on them. No dependencies, no global state.
//!
//! The distributions are the ones those simulators have always drawn, so a seed keeps giving
//! the same trace: [`SplitMix64::unit`] and [`SplitMix64::open_unit`] differ only by half a
//! step (the second never returns 0, for logarithms); [`SplitMix64::normal`] is the bounded
//! sum-of-four approximation, [`SplitMix64::gaussian`] Box–Muller.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

/// The golden-ratio increment of SplitMix64. The INS and quad simulators seed with
/// `seed ^ GOLDEN_GAMMA` (their historic seeding, kept so their seeds give the same noise).
pub const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// The generator: a 64-bit state advanced by [`GOLDEN_GAMMA`], then mixed; plus the spare
/// second sample of the last Box–Muller pair.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
    spare: Option<f64>,
}

impl SplitMix64 {
    /// A generator whose whole future is fixed by `seed` (any value, 0 included).
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed,
            spare: None,
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits (they fill an f64 mantissa exactly).
    #[allow(clippy::cast_precision_loss)] // 53 bits are exact in an f64
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / TWO_POW_53
    }

    /// Uniform in (0, 1]: [`Self::unit`]'s grid shifted by half a step (rounded to f64), so
    /// never 0 and safe to take the logarithm of.
    #[allow(clippy::cast_precision_loss)] // 53 bits are exact in an f64
    pub fn open_unit(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / TWO_POW_53
    }

    /// True with probability `p` (never for `p` ≤ 0, always for `p` ≥ 1).
    pub fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.unit() < p
    }

    /// Uniform integer in `0..n` by remainder (bias below n / 2^64); 0 for `n` = 0.
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 { 0 } else { self.next_u64() % n }
    }

    /// One random byte (the top 8 bits).
    pub fn byte(&mut self) -> u8 {
        self.next_u64().to_be_bytes()[0]
    }

    /// Approximately normal, mean 0, standard deviation `sigma`: the sum of four uniforms,
    /// so cheap and bounded (never beyond ±2√3 σ).
    pub fn normal(&mut self, sigma: f64) -> f64 {
        let s: f64 = (0..4).map(|_| self.unit()).sum::<f64>() - 2.0;
        // The variance of a sum of four U(0, 1) is 4/12.
        s * sigma * 3.0f64.sqrt()
    }

    /// Standard normal by Box–Muller; each pair's second value is returned by the next call.
    pub fn gaussian(&mut self) -> f64 {
        if let Some(value) = self.spare.take() {
            return value;
        }
        let (u1, u2) = (self.open_unit(), self.open_unit());
        let r = (-2.0 * u1.ln()).sqrt();
        let (sin, cos) = (2.0 * core::f64::consts::PI * u2).sin_cos();
        self.spare = Some(r * sin);
        r * cos
    }
}

/// 2^53 as an f64.
const TWO_POW_53: f64 = 9_007_199_254_740_992.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_reference_outputs_for_seed_zero() {
        // The published first outputs of SplitMix64 seeded with 0.
        let mut rng = SplitMix64::new(0);
        assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(rng.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(rng.next_u64(), 0x06C4_5D18_8009_454F);
    }

    #[test]
    fn unit_mean_is_one_half() {
        let mut rng = SplitMix64::new(42);
        let n = 100_000;
        let mean = (0..n).map(|_| rng.unit()).sum::<f64>() / f64::from(n);
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
    }

    #[test]
    fn open_unit_is_unit_shifted_by_half_a_step() {
        let (mut a, mut b) = (SplitMix64::new(3), SplitMix64::new(3));
        for _ in 0..1000 {
            let (closed, open) = (a.unit(), b.open_unit());
            assert!(open >= closed && open - closed <= 1.0 / TWO_POW_53);
            assert!(open > 0.0 && open <= 1.0);
        }
    }

    #[test]
    fn below_stays_in_range_and_covers_it() {
        let mut rng = SplitMix64::new(7);
        let mut seen = [0u32; 8];
        for _ in 0..8000 {
            seen[rng.below(8) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c > 850 && c < 1150), "{seen:?}");
        assert_eq!(rng.below(0), 0);
    }

    #[test]
    fn normal_and_gaussian_have_the_asked_spread() {
        let mut rng = SplitMix64::new(1);
        let n = 200_000;
        for (draw, sigma) in [
            (
                &mut (|r: &mut SplitMix64| r.gaussian()) as &mut dyn FnMut(&mut SplitMix64) -> f64,
                1.0,
            ),
            (&mut |r: &mut SplitMix64| r.normal(2.0), 2.0),
        ] {
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let x = draw(&mut rng);
                sum += x;
                sum2 += x * x;
            }
            let mean = sum / f64::from(n);
            let var = sum2 / f64::from(n) - mean * mean;
            assert!(mean.abs() < 0.01 * sigma, "{mean}");
            assert!((var / (sigma * sigma) - 1.0).abs() < 0.01, "{var}");
        }
    }

    #[test]
    fn byte_is_the_top_eight_bits() {
        let (mut a, mut b) = (SplitMix64::new(9), SplitMix64::new(9));
        assert_eq!(u64::from(a.byte()), b.next_u64() >> 56);
    }
}

/// The README's examples, run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
