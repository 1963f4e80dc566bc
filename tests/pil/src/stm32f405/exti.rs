//! SYSCFG (RM0090 §9: MEMRMP, EXTICR1–4, CMPCR) and the EXTI controller (§12.3: IMR, EMR,
//! RTSR, FTSR, SWIER, PR) for the 16 GPIO lines. An edge on the pin SYSCFG selects for a
//! line sets the line pending when its trigger is enabled and the line unmasked (Figure 27:
//! the mask gates the edge before the pending register); pending lines drive the NVIC's
//! EXTI0–4, EXTI9_5 and EXTI15_10 inputs until software clears PR.

use super::map::irq;

// SYSCFG offsets.
const MEMRMP: u32 = 0x00;
const PMC: u32 = 0x04;
const EXTICR1: u32 = 0x08;
const EXTICR4: u32 = 0x14;
const CMPCR: u32 = 0x20;

// EXTI offsets.
const IMR: u32 = 0x00;
const EMR: u32 = 0x04;
const RTSR: u32 = 0x08;
const FTSR: u32 = 0x0C;
const SWIER: u32 = 0x10;
const PR: u32 = 0x14;

/// EXTI lines 0–22 exist on the F405.
const LINES: u32 = 0x7F_FFFF;
/// The GPIO lines this model drives.
const GPIO_LINES: u32 = 0xFFFF;

/// SYSCFG and EXTI state.
#[derive(Clone, Debug, Default)]
pub struct Exti {
    memrmp: u32,
    pmc: u32,
    exticr: [u32; 4],
    cmpcr: u32,
    imr: u32,
    emr: u32,
    rtsr: u32,
    ftsr: u32,
    swier: u32,
    pr: u32,
}

impl Exti {
    /// Reset state (BOOT0 low: main flash at 0).
    pub fn new() -> Self {
        Self::default()
    }

    /// SYSCFG alone back to reset (RCC_APB2RSTR.SYSCFGRST).
    pub fn reset_syscfg(&mut self) {
        self.memrmp = 0;
        self.pmc = 0;
        self.exticr = [0; 4];
        self.cmpcr = 0;
    }

    /// What 0x0000_0000 aliases: 0 main flash, 1 system memory, 3 SRAM (MEMRMP.MEM_MODE).
    pub fn mem_mode(&self) -> u32 {
        self.memrmp & 3
    }

    /// The port SYSCFG routes to EXTI `line`.
    pub fn port_of(&self, line: u8) -> u8 {
        let reg = self.exticr.get(usize::from(line / 4)).copied().unwrap_or(0);
        ((reg >> (4 * (line % 4))) & 0xF) as u8
    }

    /// The input of EXTI `line` changed to `level` (from the pin SYSCFG selects).
    pub fn edge(&mut self, line: u8, level: bool) {
        let bit = 1u32 << line;
        let armed = if level { self.rtsr } else { self.ftsr };
        if armed & bit != 0 && self.imr & bit != 0 {
            self.pr |= bit;
        }
    }

    /// The NVIC inputs the pending lines drive, as (IRQ number) list.
    pub fn irqs(&self) -> impl Iterator<Item = u32> + '_ {
        (0..16u8).filter(|l| self.pr & (1 << l) != 0).map(irq::exti)
    }

    /// SYSCFG register read.
    pub fn syscfg_read(&self, offset: u32) -> Option<u32> {
        Some(match offset {
            MEMRMP => self.memrmp,
            PMC => self.pmc,
            EXTICR1..=EXTICR4 => *self.exticr.get(((offset - EXTICR1) / 4) as usize)?,
            // The compensation cell is ready as soon as it is powered.
            CMPCR => self.cmpcr | if self.cmpcr & 1 != 0 { 1 << 8 } else { 0 },
            _ => return None,
        })
    }

    /// SYSCFG register write; `Some(Some(what))` names a setting the model ignores.
    pub fn syscfg_write(&mut self, offset: u32, value: u32) -> Option<Option<&'static str>> {
        match offset {
            MEMRMP => self.memrmp = value & 3,
            PMC => {
                self.pmc = value & (1 << 23);
                return Some((value != 0).then_some("SYSCFG_PMC Ethernet PHY interface"));
            }
            EXTICR1..=EXTICR4 => {
                *self.exticr.get_mut(((offset - EXTICR1) / 4) as usize)? = value & 0xFFFF
            }
            CMPCR => self.cmpcr = value & 1,
            _ => return None,
        }
        Some(None)
    }

    /// EXTI register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        Some(match offset {
            IMR => self.imr,
            EMR => self.emr,
            RTSR => self.rtsr,
            FTSR => self.ftsr,
            SWIER => self.swier,
            PR => self.pr,
            _ => return None,
        })
    }

    /// EXTI register write; `Some(Some(what))` names a setting the model ignores.
    pub fn write(&mut self, offset: u32, value: u32) -> Option<Option<&'static str>> {
        let v = value & LINES;
        let mut unmodelled = None;
        match offset {
            IMR => {
                self.imr = v;
                if v & !GPIO_LINES != 0 {
                    unmodelled = Some("EXTI lines 16–22 (PVD, RTC, USB wake-up)");
                }
            }
            EMR => {
                self.emr = v;
                if v != 0 {
                    unmodelled = Some("EXTI event mask (WFE wake-up events)");
                }
            }
            RTSR => self.rtsr = v,
            FTSR => self.ftsr = v,
            SWIER => {
                // A 0→1 write sets the pending bit of an unmasked line (RM0090 §12.3.5).
                let rising = v & !self.swier;
                self.swier |= v;
                self.pr |= rising & self.imr;
            }
            PR => {
                self.pr &= !v;
                self.swier &= !v;
            }
            _ => return None,
        }
        Some(unmodelled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_armed_unmasked_edge_on_the_selected_line_pends_its_irq() {
        let mut e = Exti::new();
        // ExtiInput on PD2: EXTICR1 line 2 = port D, rising edge, unmasked.
        e.syscfg_write(EXTICR1, 3 << 8);
        assert_eq!(e.port_of(2), 3);
        e.write(FTSR, 1 << 2);
        e.edge(2, false);
        assert_eq!(e.read(PR), Some(0), "masked");
        e.write(IMR, 1 << 2);
        e.edge(2, true);
        assert_eq!(e.read(PR), Some(0), "rising edge not armed");
        e.edge(2, false);
        assert_eq!(e.read(PR), Some(1 << 2));
        assert_eq!(e.irqs().collect::<Vec<_>>(), vec![irq::EXTI2]);
        // Masking afterwards does not withdraw the request; writing 1 to PR does.
        e.write(IMR, 0);
        assert_eq!(e.irqs().count(), 1);
        e.write(PR, 1 << 2);
        assert_eq!(e.irqs().count(), 0);
    }

    #[test]
    fn lines_5_to_9_share_one_irq_and_swier_pends_unmasked_lines() {
        let mut e = Exti::new();
        e.write(IMR, 1 << 5 | 1 << 7);
        e.write(SWIER, 1 << 5 | 1 << 6);
        assert_eq!(e.read(PR), Some(1 << 5));
        e.write(RTSR, 1 << 7);
        e.edge(7, true);
        assert_eq!(
            e.irqs().collect::<Vec<_>>(),
            vec![irq::EXTI9_5, irq::EXTI9_5]
        );
        e.write(PR, 1 << 5);
        assert_eq!(e.read(SWIER), Some(1 << 6));
    }
}
