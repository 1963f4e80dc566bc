//! Virtual time: processor cycles at the core clock the bus reports, converted to
//! nanoseconds exactly (the fraction of a nanosecond carries over when the clock changes).

use std::num::NonZeroU64;

const NS_PER_S: u64 = 1_000_000_000;
/// Cycles after the last rebase at which the time arithmetic rebases (keeps the products
/// of the hot path inside 64 bits).
const REBASE_SPAN: u64 = 1 << 32;

/// Cycles and the time they stand for.
#[derive(Clone, Debug)]
pub(crate) struct Clock {
    /// Cycles since power-on.
    pub cycles: u64,
    base_cycles: u64,
    base_ns: u64,
    /// The fraction of a nanosecond at the base, in units of 1/hz ns.
    base_rem: u64,
    hz: NonZeroU64,
}

impl Clock {
    pub fn new(hz: u32) -> Self {
        Clock {
            cycles: 0,
            base_cycles: 0,
            base_ns: 0,
            base_rem: 0,
            hz: NonZeroU64::new(u64::from(hz)).unwrap_or(NonZeroU64::MIN),
        }
    }

    pub fn hz(&self) -> u64 {
        self.hz.get()
    }

    /// Nanoseconds at the current cycle count (rounded down).
    #[inline]
    pub fn now_ns(&self) -> u64 {
        self.ns_at(self.cycles)
    }

    /// Nanoseconds at cycle `c` (not before the base).
    #[inline]
    pub fn ns_at(&self, c: u64) -> u64 {
        let dc = c.saturating_sub(self.base_cycles);
        if dc < REBASE_SPAN * 4 {
            self.base_ns + (dc * NS_PER_S + self.base_rem) / self.hz
        } else {
            let total = u128::from(dc) * u128::from(NS_PER_S) + u128::from(self.base_rem);
            self.base_ns + (total / u128::from(self.hz.get())) as u64
        }
    }

    /// The first cycle at which the time is at least `ns` (the current cycle when `ns` is
    /// not in the future; `u64::MAX` for `u64::MAX`).
    pub fn cycle_at(&self, ns: u64) -> u64 {
        if ns == u64::MAX {
            return u64::MAX;
        }
        if ns <= self.now_ns() {
            return self.cycles;
        }
        let dns = ns - self.base_ns;
        // The common case in 64 bits (spans of up to a minute or so); else in 128.
        if let Some(d) = dns.checked_mul(self.hz.get()) {
            let dc = d.saturating_sub(self.base_rem).div_ceil(NS_PER_S);
            return self.base_cycles.saturating_add(dc);
        }
        let d = u128::from(dns) * u128::from(self.hz.get());
        let need = d.saturating_sub(u128::from(self.base_rem));
        let dc = need.div_ceil(u128::from(NS_PER_S));
        self.base_cycles
            .saturating_add(u64::try_from(dc).unwrap_or(u64::MAX))
    }

    /// Moves the base to now without losing the fraction of a nanosecond.
    fn rebase(&mut self) {
        let dc = self.cycles - self.base_cycles;
        let total = u128::from(dc) * u128::from(NS_PER_S) + u128::from(self.base_rem);
        let hz = u128::from(self.hz.get());
        self.base_ns += (total / hz) as u64;
        self.base_rem = (total % hz) as u64;
        self.base_cycles = self.cycles;
    }

    /// Counts from now at a new clock frequency.
    pub fn set_hz(&mut self, hz: u32) {
        let hz = NonZeroU64::new(u64::from(hz)).unwrap_or(NonZeroU64::MIN);
        if hz != self.hz {
            self.rebase();
            // The carried fraction was in units of the old clock's 1/hz ns.
            self.base_rem = self.base_rem * hz.get() / self.hz.get();
            self.hz = hz;
        }
    }

    /// The cycle at which the hot path's arithmetic wants a rebase.
    pub fn rebase_due(&self) -> u64 {
        self.base_cycles + REBASE_SPAN
    }

    /// Rebases when the span since the base grew large.
    pub fn rebase_if_far(&mut self) {
        if self.cycles >= self.rebase_due() {
            self.rebase();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nanoseconds_follow_cycles_at_the_clock() {
        let mut c = Clock::new(168_000_000);
        c.cycles = 168;
        assert_eq!(c.now_ns(), 1000);
        c.cycles = 169;
        assert_eq!(c.now_ns(), 1005); // 1005.95 rounded down
        assert_eq!(c.cycle_at(1006), 170);
        assert_eq!(c.cycle_at(1005), 169);
    }

    #[test]
    fn a_clock_change_rebases_exactly() {
        let mut c = Clock::new(3);
        c.cycles = 1; // 333.33 ns
        c.set_hz(6);
        assert_eq!(c.now_ns(), 333_333_333);
        c.cycles = 3; // + 2 cycles at 6 Hz = 333.33 ns: 666.67 ns in all
        assert_eq!(c.now_ns(), 666_666_666);
        c.cycles = 5; // 1 s exactly
        assert_eq!(c.now_ns(), 1_000_000_000);
    }

    #[test]
    fn cycle_at_inverts_now_ns() {
        let mut c = Clock::new(64_000_000);
        c.cycles = 12_345;
        c.set_hz(168_000_000);
        for ns in [200_000u64, 200_001, 7_777_777, 1_000_000_000] {
            let at = c.cycle_at(ns);
            let mut probe = c.clone();
            probe.cycles = at;
            assert!(probe.now_ns() >= ns);
            probe.cycles = at - 1;
            assert!(probe.now_ns() < ns);
        }
    }

    #[test]
    fn long_spans_rebase_without_drift() {
        let mut c = Clock::new(168_000_000);
        c.cycles = 3 * REBASE_SPAN + 7;
        let before = c.now_ns();
        c.rebase_if_far();
        assert_eq!(c.now_ns(), before);
        c.cycles += 168_000_000;
        assert_eq!(c.now_ns(), before + 1_000_000_000);
    }
}
