//! Where an application's link secrets come from (spec §12): one 256-bit seed from the
//! hardware RNG at boot, expanded with SHA-512 under a label per use — the bind's CPace
//! scalars, the epoch nonces' seed, the phone sessions, the phrase salt, the session of the
//! flight side's setting changes — so no value can be worked back to another (each is a
//! one-way function of the seed and its own label and draw number), and simulations stay
//! deterministic (their seed is injected like the firmware's).

use super::sha512::sha512;

/// A seeded generator of 256-bit secrets.
#[derive(Clone)]
pub struct Entropy {
    seed: [u8; 32],
    draws: u64,
}

impl core::fmt::Debug for Entropy {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Entropy({} draws)", self.draws)
    }
}

impl Entropy {
    /// A generator on `seed` (32 bytes of a hardware RNG).
    pub const fn new(seed: [u8; 32]) -> Self {
        Self { seed, draws: 0 }
    }

    /// The next 32 bytes for `label`: SHA-512(seed ‖ draw number ‖ label), first half.
    pub fn draw(&mut self, label: &[u8]) -> [u8; 32] {
        self.draws = self.draws.wrapping_add(1);
        let digest = sha512(&[&self.seed, &self.draws.to_le_bytes(), label]);
        core::array::from_fn(|i| digest.get(i).copied().unwrap_or(0))
    }

    /// The next 64 bits for `label`.
    pub fn draw_u64(&mut self, label: &[u8]) -> u64 {
        let bytes = self.draw(label);
        u64::from_le_bytes(core::array::from_fn(|i| bytes.get(i).copied().unwrap_or(0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_differ_by_seed_label_and_number_and_repeat_for_one_seed() {
        let mut a = Entropy::new([1; 32]);
        let mut b = Entropy::new([1; 32]);
        let first = a.draw(b"nonces");
        assert_eq!(b.draw(b"nonces"), first, "deterministic");
        assert_ne!(a.draw(b"nonces"), first, "the next draw");
        assert_ne!(
            Entropy::new([1; 32]).draw(b"session"),
            first,
            "another label"
        );
        assert_ne!(Entropy::new([2; 32]).draw(b"nonces"), first, "another seed");
        assert_eq!(
            format!("{a:?}"),
            "Entropy(2 draws)",
            "the seed is never printed"
        );
    }
}
