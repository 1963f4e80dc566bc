//! Exception state by exception number (1 Reset … 15 SysTick, 16 + n for IRQ n): pending,
//! active and enabled bits, priorities, and the interrupt lines the NVIC latches.

/// Exception numbers the core uses by name.
pub(crate) mod exc {
    pub const NMI: u16 = 2;
    pub const HARD_FAULT: u16 = 3;
    pub const MEM_MANAGE: u16 = 4;
    pub const BUS_FAULT: u16 = 5;
    pub const USAGE_FAULT: u16 = 6;
    pub const SVCALL: u16 = 11;
    pub const PENDSV: u16 = 14;
    pub const SYSTICK: u16 = 15;
    pub const IRQ0: u16 = 16;
}

/// 256 bits, one per exception number.
pub(crate) type Bits = [u32; 8];

fn get(b: &Bits, n: u16) -> bool {
    b.get(usize::from(n / 32))
        .is_some_and(|w| w >> (n % 32) & 1 != 0)
}

fn put(b: &mut Bits, n: u16, on: bool) {
    if let Some(w) = b.get_mut(usize::from(n / 32)) {
        if on {
            *w |= 1 << (n % 32);
        } else {
            *w &= !(1 << (n % 32));
        }
    }
}

/// Converts 32 IRQ bits of register index `k` (IRQ 32k … 32k+31) from/to exception bits.
fn irq_word(b: &Bits, k: usize) -> u32 {
    let lo = b.get(k).copied().unwrap_or(0) >> 16;
    let hi = b.get(k + 1).copied().unwrap_or(0) << 16;
    lo | hi
}

/// The NVIC and the system-exception state that lives beside it.
#[derive(Clone, Debug)]
pub(crate) struct Nvic {
    pub pending: Bits,
    pub active: Bits,
    /// Enabled: ISER for IRQs; the SHCSR enables for MemManage/BusFault/UsageFault; always
    /// for NMI, HardFault, SVCall, PendSV, SysTick.
    pub enabled: Bits,
    /// Configurable priorities by exception number (already masked to the implemented bits).
    pub prio: [u8; 256],
    /// The interrupt lines as last sampled (by IRQ number).
    pub lines: Bits,
    /// Implemented IRQs (by exception number).
    implemented: Bits,
    prio_mask: u8,
    irqs: u16,
}

const ALWAYS_ENABLED: u32 =
    1 << exc::NMI | 1 << exc::HARD_FAULT | 1 << exc::SVCALL | 1 << exc::PENDSV | 1 << exc::SYSTICK;

impl Nvic {
    pub fn new(irqs: u16, prio_bits: u8) -> Self {
        let irqs = irqs.min(240);
        let mut implemented = [0; 8];
        for n in 0..irqs {
            put(&mut implemented, exc::IRQ0 + n, true);
        }
        let bits = prio_bits.clamp(2, 8);
        let mut nvic = Nvic {
            pending: [0; 8],
            active: [0; 8],
            enabled: [0; 8],
            prio: [0; 256],
            lines: [0; 8],
            implemented,
            prio_mask: (0xFF00u16 >> bits) as u8,
            irqs,
        };
        nvic.reset();
        nvic
    }

    pub fn reset(&mut self) {
        self.pending = [0; 8];
        self.active = [0; 8];
        self.enabled = [ALWAYS_ENABLED, 0, 0, 0, 0, 0, 0, 0];
        self.prio = [0; 256];
    }

    pub fn irqs(&self) -> u16 {
        self.irqs
    }

    pub fn is_pending(&self, n: u16) -> bool {
        get(&self.pending, n)
    }

    pub fn is_active(&self, n: u16) -> bool {
        get(&self.active, n)
    }

    pub fn is_enabled(&self, n: u16) -> bool {
        get(&self.enabled, n)
    }

    pub fn set_pending(&mut self, n: u16, on: bool) {
        put(&mut self.pending, n, on);
    }

    pub fn set_active(&mut self, n: u16, on: bool) {
        put(&mut self.active, n, on);
    }

    pub fn set_enabled(&mut self, n: u16, on: bool) {
        put(&mut self.enabled, n, on);
    }

    /// The priority of exception `n`: negative for Reset, NMI and HardFault.
    pub fn priority(&self, n: u16) -> i16 {
        match n {
            1 => -3,
            exc::NMI => -2,
            exc::HARD_FAULT => -1,
            _ => self.prio.get(usize::from(n)).copied().map_or(0, i16::from),
        }
    }

    /// Writes a priority byte (unimplemented low bits read as zero).
    pub fn set_priority(&mut self, n: u16, value: u8) {
        if let Some(p) = self.prio.get_mut(usize::from(n)) {
            *p = value & self.prio_mask;
        }
    }

    /// The number of active exceptions.
    pub fn active_count(&self) -> u32 {
        self.active.iter().map(|w| w.count_ones()).sum()
    }

    /// The highest-priority pending and enabled exception (lowest priority value, then
    /// lowest number) and its priority.
    pub fn best_pending(&self) -> Option<(u16, i16)> {
        let mut best: Option<(u16, i16)> = None;
        for (w, (&p, &e)) in self.pending.iter().zip(&self.enabled).enumerate() {
            let mut bits = p & e;
            while bits != 0 {
                let n = (w as u16) * 32 + bits.trailing_zeros() as u16;
                bits &= bits - 1;
                let prio = self.priority(n);
                if best.is_none_or(|(_, bp)| prio < bp) {
                    best = Some((n, prio));
                }
            }
        }
        best
    }

    /// The lowest priority value among active exceptions (256 for none).
    pub fn highest_active_priority(&self) -> i16 {
        let mut best = 256;
        for (w, &a) in self.active.iter().enumerate() {
            let mut bits = a;
            while bits != 0 {
                let n = (w as u16) * 32 + bits.trailing_zeros() as u16;
                bits &= bits - 1;
                best = best.min(self.priority(n));
            }
        }
        best
    }

    /// Samples the interrupt lines (by IRQ number): a line that is high sets its interrupt
    /// pending unless it is active, and a rising edge sets it pending even when active (a
    /// new request while the handler runs). Returns whether anything became pending.
    pub fn sample(&mut self, lines: Bits) -> bool {
        if lines == [0; 8] {
            // No level and no rising edge.
            self.lines = lines;
            return false;
        }
        let rising = [0, 1, 2, 3, 4, 5, 6, 7]
            .map(|k| lines.get(k).copied().unwrap_or(0) & !self.lines.get(k).copied().unwrap_or(0));
        self.lines = lines;
        let mut changed = false;
        for k in 0..8 {
            let level = irq_to_exc(&lines, k) & self.implemented.get(k).copied().unwrap_or(0);
            let edge = irq_to_exc(&rising, k) & self.implemented.get(k).copied().unwrap_or(0);
            let active = self.active.get(k).copied().unwrap_or(0);
            if let Some(p) = self.pending.get_mut(k) {
                let add = (level & !active) | edge;
                if add & !*p != 0 {
                    changed = true;
                }
                *p |= add;
            }
        }
        changed
    }

    /// Re-applies the latched levels after pending or active bits changed by software or
    /// by an exception return.
    pub fn relatch(&mut self) -> bool {
        let mut changed = false;
        for k in 0..8 {
            let level = irq_to_exc(&self.lines, k) & self.implemented.get(k).copied().unwrap_or(0);
            let active = self.active.get(k).copied().unwrap_or(0);
            if let Some(p) = self.pending.get_mut(k) {
                let add = level & !active;
                changed |= add & !*p != 0;
                *p |= add;
            }
        }
        changed
    }

    /// 32 IRQ bits of register `k` from a bit set.
    pub fn irq_bits(&self, set: &Bits, k: usize) -> u32 {
        irq_word(set, k)
    }

    /// Whether IRQ `n` exists.
    pub fn irq_implemented(&self, irq: u16) -> bool {
        irq < self.irqs
    }

    /// Any external interrupt pending (ICSR.ISRPENDING).
    pub fn any_irq_pending(&self) -> bool {
        (0..8).any(|k| {
            self.pending.get(k).copied().unwrap_or(0)
                & self.implemented.get(k).copied().unwrap_or(0)
                != 0
        })
    }
}

/// Word `k` (exception numbers 32k … 32k+31) of IRQ-numbered lines.
fn irq_to_exc(lines: &Bits, k: usize) -> u32 {
    let from_this = lines.get(k).copied().unwrap_or(0) << 16;
    let from_prev = if k == 0 {
        0
    } else {
        lines.get(k - 1).copied().unwrap_or(0) >> 16
    };
    from_this | from_prev
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_latch_as_pending_once_and_again_after_the_handler() {
        let mut nvic = Nvic::new(64, 4);
        let mut lines = [0u32; 8];
        lines[1] = 1 << 3; // IRQ 35 = exception 51
        assert!(nvic.sample(lines));
        assert!(nvic.is_pending(51));
        // Taken: active, not pending; the level stays high but does not re-pend.
        nvic.set_pending(51, false);
        nvic.set_active(51, true);
        assert!(!nvic.sample(lines));
        assert!(!nvic.is_pending(51));
        // Handler returns with the line still high: pending again.
        nvic.set_active(51, false);
        assert!(nvic.relatch());
        assert!(nvic.is_pending(51));
    }

    #[test]
    fn a_new_edge_while_active_pends() {
        let mut nvic = Nvic::new(32, 3);
        nvic.set_active(16, true);
        assert!(nvic.sample([1, 0, 0, 0, 0, 0, 0, 0]));
        assert!(nvic.is_pending(16));
    }

    #[test]
    fn unimplemented_irqs_never_pend() {
        let mut nvic = Nvic::new(8, 3);
        assert!(!nvic.sample([1 << 9, 0, 0, 0, 0, 0, 0, 0]));
        assert!(!nvic.is_pending(25));
    }

    #[test]
    fn priorities_keep_the_implemented_bits_and_order_pending() {
        let mut nvic = Nvic::new(32, 3);
        nvic.set_priority(20, 0xFF);
        assert_eq!(nvic.priority(20), 0xE0);
        nvic.set_priority(21, 0x40);
        for n in [20, 21] {
            nvic.set_enabled(n, true);
            nvic.set_pending(n, true);
        }
        assert_eq!(nvic.best_pending(), Some((21, 0x40)));
        nvic.set_pending(exc::HARD_FAULT, true);
        assert_eq!(nvic.best_pending(), Some((exc::HARD_FAULT, -1)));
    }
}
