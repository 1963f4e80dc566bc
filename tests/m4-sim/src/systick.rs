//! SysTick (ARM ARM B3.3): a 24-bit down-counter on the processor clock or the SoC's
//! reference clock, computed from the cycle count rather than ticked, so it costs nothing
//! while it runs; it wakes the run loop only at the cycle it wraps.

/// CSR bits.
pub(crate) const ENABLE: u32 = 1 << 0;
pub(crate) const TICKINT: u32 = 1 << 1;
pub(crate) const CLKSOURCE: u32 = 1 << 2;
pub(crate) const COUNTFLAG: u32 = 1 << 16;

/// The timer.
#[derive(Clone, Debug)]
pub(crate) struct SysTick {
    /// ENABLE, TICKINT, CLKSOURCE (COUNTFLAG is kept in `countflag`).
    pub csr: u32,
    pub rvr: u32,
    pub countflag: bool,
    /// Counter value at `base_tick`.
    value_at_base: u32,
    base_tick: u64,
    /// Cycles per tick of the selected clock.
    div: u64,
    /// Absolute tick of the next 1 → 0 transition (`None`: no wrap coming).
    next_fire: Option<u64>,
}

impl SysTick {
    pub fn new() -> Self {
        SysTick {
            csr: 0,
            rvr: 0,
            countflag: false,
            value_at_base: 0,
            base_tick: 0,
            div: 1,
            next_fire: None,
        }
    }

    fn enabled(&self) -> bool {
        self.csr & ENABLE != 0
    }

    fn tick_at(&self, cycles: u64) -> u64 {
        cycles / self.div
    }

    /// The counter value at `cycles`.
    pub fn value(&self, cycles: u64) -> u32 {
        if !self.enabled() {
            return self.value_at_base;
        }
        let t = self.tick_at(cycles).saturating_sub(self.base_tick);
        let v0 = u64::from(self.value_at_base);
        if t <= v0 {
            return (v0 - t) as u32;
        }
        let period = u64::from(self.rvr) + 1;
        (u64::from(self.rvr) - (t - v0 - 1) % period) as u32
    }

    /// Re-anchors the counting at `cycles` (before a register write changes how it counts).
    fn rebase(&mut self, cycles: u64) {
        self.value_at_base = self.value(cycles);
        self.base_tick = self.tick_at(cycles);
    }

    /// The first wrap at or after the anchor.
    fn schedule(&mut self) {
        self.next_fire = if !self.enabled() {
            None
        } else if self.value_at_base > 0 {
            Some(self.base_tick + u64::from(self.value_at_base))
        } else if self.rvr > 0 {
            Some(self.base_tick + u64::from(self.rvr) + 1)
        } else {
            None
        };
    }

    /// The cycle of the next wrap (`u64::MAX`: none).
    pub fn next_fire_cycle(&self) -> u64 {
        self.next_fire
            .map_or(u64::MAX, |t| t.saturating_mul(self.div))
    }

    /// Handles the wraps due by `cycles` (several periods of a long sleep count as one
    /// for the pending bit, as on the silicon); returns whether there was one.
    pub fn fire_due(&mut self, cycles: u64) -> bool {
        let Some(t) = self.next_fire else {
            return false;
        };
        if t.saturating_mul(self.div) > cycles {
            return false;
        }
        self.countflag = true;
        self.next_fire = (self.rvr > 0).then(|| {
            let period = u64::from(self.rvr) + 1;
            let now_tick = self.tick_at(cycles);
            // The first wrap after `now_tick`.
            t + ((now_tick - t) / period + 1) * period
        });
        true
    }

    /// CSR write.
    pub fn write_csr(&mut self, v: u32, cycles: u64, ref_div: Option<u32>) {
        self.rebase(cycles);
        let clk = if ref_div.is_none() {
            CLKSOURCE
        } else {
            v & CLKSOURCE
        };
        self.csr = v & (ENABLE | TICKINT) | clk;
        self.div = if self.csr & CLKSOURCE != 0 {
            1
        } else {
            u64::from(ref_div.unwrap_or(1).max(1))
        };
        self.base_tick = self.tick_at(cycles);
        self.schedule();
    }

    /// CSR read (clears COUNTFLAG).
    pub fn read_csr(&mut self, ref_div: Option<u32>) -> u32 {
        let clk = if ref_div.is_none() { CLKSOURCE } else { 0 };
        let v = self.csr | clk | if self.countflag { COUNTFLAG } else { 0 };
        self.countflag = false;
        v
    }

    pub fn write_rvr(&mut self, v: u32, cycles: u64) {
        self.rebase(cycles);
        self.rvr = v & 0x00FF_FFFF;
        self.schedule();
    }

    /// CVR write: any value clears the counter and COUNTFLAG.
    pub fn write_cvr(&mut self, cycles: u64) {
        self.rebase(cycles);
        self.value_at_base = 0;
        self.countflag = false;
        self.schedule();
    }

    /// The core clock changed: the reference clock is a divider of it, so counting in
    /// cycles stays right; nothing to do but keep the hook for a future fixed reference.
    pub fn clock_changed(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_down_reloads_and_fires_every_period() {
        let mut st = SysTick::new();
        st.write_rvr(99, 0);
        st.write_cvr(0);
        st.write_csr(ENABLE | TICKINT | CLKSOURCE, 1000, None);
        // From 0 the first tick reloads 99; it reaches 0 a hundred ticks later.
        assert_eq!(st.value(1001), 99);
        assert_eq!(st.value(1050), 50);
        assert_eq!(st.next_fire_cycle(), 1100);
        assert!(!st.fire_due(1099));
        assert!(st.fire_due(1100));
        assert_eq!(st.value(1100), 0);
        assert_eq!(st.value(1101), 99);
        assert_eq!(st.next_fire_cycle(), 1200);
        assert_ne!(st.read_csr(None) & COUNTFLAG, 0);
        assert_eq!(st.read_csr(None) & COUNTFLAG, 0);
    }

    #[test]
    fn the_reference_clock_divides_the_core_clock() {
        let mut st = SysTick::new();
        st.write_rvr(9, 0);
        st.write_csr(ENABLE, 0, Some(8));
        // Ten reference ticks of eight cycles, after the reload tick.
        assert_eq!(st.next_fire_cycle(), 80);
        assert_eq!(st.value(8 * 5), 5);
    }

    #[test]
    fn disabled_it_holds_its_value() {
        let mut st = SysTick::new();
        st.write_rvr(1000, 0);
        st.write_csr(ENABLE | CLKSOURCE, 0, None);
        st.write_csr(CLKSOURCE, 301, None);
        assert_eq!(st.value(301), 700);
        assert_eq!(st.value(5000), 700);
        assert_eq!(st.next_fire_cycle(), u64::MAX);
    }
}
