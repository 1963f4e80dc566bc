//! ADC1's regular conversions (RM0090 §13, the v2 ADC embassy-stm32's `adc/v2.rs` drives)
//! and the common registers: CR2 ADON/SWSTART/CONT/DMA/EOCS/ALIGN, CR1 RES/SCAN/EOCIE,
//! SMPR1/2, SQR1–3, SR (EOC, STRT, OVR), DR; ADC_CCR's prescaler and the internal channels.
//!
//! A conversion takes the channel's sample time plus the resolution's bits (12 for 12-bit)
//! ADC clock cycles, ADC clock = PCLK2 / ADCPRE (RM0090 §13.5); the input is sampled at the
//! end of the sampling phase from `Outside::analog_volts` against a 3.3 V reference
//! (code = round(V / 3.3 V · 4096), clamped). Internal channels with TSVREFE/VBATE: the
//! temperature sensor at 25 °C (0.76 V, DS8626), VREFINT 1.21 V, VBAT/2 with VBAT = 3.3 V.
//! Not modelled (recorded): injected conversions, external triggers, the analog watchdog,
//! ADC2/3 and dual/triple modes.

use crate::wire::{Outside, Pin};

const SR: u32 = 0x00;
const CR1: u32 = 0x04;
const CR2: u32 = 0x08;
const SMPR1: u32 = 0x0C;
const SMPR2: u32 = 0x10;
const HTR: u32 = 0x24;
const LTR: u32 = 0x28;
const SQR1: u32 = 0x2C;
const SQR3: u32 = 0x34;
const JSQR: u32 = 0x38;
const JDR1: u32 = 0x3C;
const JDR4: u32 = 0x48;
const DR: u32 = 0x4C;
const JOFR1: u32 = 0x14;
const JOFR4: u32 = 0x20;

// Common block offsets.
const CSR: u32 = 0x00;
const CCR: u32 = 0x04;
const CDR: u32 = 0x08;

const AWD: u32 = 1 << 0;
const EOC: u32 = 1 << 1;
const STRT: u32 = 1 << 4;
const OVR: u32 = 1 << 5;

const EOCIE: u32 = 1 << 5;
const AWDIE: u32 = 1 << 6;
const JEOCIE: u32 = 1 << 7;
const SCAN: u32 = 1 << 8;
const OVRIE: u32 = 1 << 26;

const ADON: u32 = 1 << 0;
const CONT: u32 = 1 << 1;
const DMA: u32 = 1 << 8;
const EOCS: u32 = 1 << 10;
const ALIGN: u32 = 1 << 11;
const JSWSTART: u32 = 1 << 22;
const SWSTART: u32 = 1 << 30;

const TSVREFE: u32 = 1 << 23;
const VBATE: u32 = 1 << 22;

/// The reference voltage on VREF+.
pub const VREF: f32 = 3.3;
/// ADC power-up time t_STAB (DS8626 "ADC characteristics").
const STAB_NS: u64 = 3_000;
/// Sample times by SMP code, ADC cycles.
const SAMPLE_CYCLES: [u64; 8] = [3, 15, 28, 56, 84, 112, 144, 480];

/// The GPIO pin of external channel `ch` (ADC123_IN0–15).
pub fn channel_pin(ch: u8) -> Option<Pin> {
    match ch {
        0..=7 => Some(Pin::new(0, ch)),
        8 | 9 => Some(Pin::new(1, ch - 8)),
        10..=15 => Some(Pin::new(2, ch - 10)),
        _ => None,
    }
}

/// ADC1 and the common registers.
pub struct Adc {
    sr: u32,
    cr1: u32,
    cr2: u32,
    smpr: [u32; 2],
    jofr: [u32; 4],
    htr: u32,
    ltr: u32,
    sqr: [u32; 3],
    jsqr: u32,
    dr: u32,
    ccr: u32,
    powered_at: u64,
    /// The conversion under way: rank in the sequence, when sampling ends, when it ends.
    conversion: Option<(u32, u64, u64)>,
    /// The sampled input of the conversion under way.
    sampled: Option<u32>,
    pclk2: u32,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
    /// Rule breaks to record.
    pub violations: Vec<&'static str>,
}

impl Default for Adc {
    fn default() -> Self {
        Self::new()
    }
}

impl Adc {
    /// Reset state.
    pub fn new() -> Self {
        Self {
            sr: 0,
            cr1: 0,
            cr2: 0,
            smpr: [0; 2],
            jofr: [0; 4],
            htr: 0xFFF,
            ltr: 0,
            sqr: [0; 3],
            jsqr: 0,
            dr: 0,
            ccr: 0,
            powered_at: 0,
            conversion: None,
            sampled: None,
            pclk2: 16_000_000,
            unmodelled: Vec::new(),
            violations: Vec::new(),
        }
    }

    /// Back to reset values (the common block too: one reset bit for all ADCs).
    pub fn reset(&mut self) {
        let pclk2 = self.pclk2;
        let (u, v) = (
            std::mem::take(&mut self.unmodelled),
            std::mem::take(&mut self.violations),
        );
        *self = Self::new();
        self.pclk2 = pclk2;
        self.unmodelled = u;
        self.violations = v;
    }

    /// PCLK2.
    pub fn set_pclk2(&mut self, hz: u32) {
        self.pclk2 = hz;
    }

    /// The ADC clock.
    pub fn adc_hz(&self) -> u32 {
        self.pclk2 / (2 * (((self.ccr >> 16) & 3) + 1))
    }

    fn sequence_channel(&self, rank: u32) -> u8 {
        let (reg, shift) = match rank {
            0..=5 => (2, 5 * rank),
            6..=11 => (1, 5 * (rank - 6)),
            _ => (0, 5 * (rank - 12)),
        };
        ((self.sqr.get(reg).copied().unwrap_or(0) >> shift) & 0x1F) as u8
    }

    fn sequence_len(&self) -> u32 {
        if self.cr1 & SCAN != 0 {
            ((self.sqr[0] >> 20) & 0xF) + 1
        } else {
            1
        }
    }

    fn sample_cycles(&self, ch: u8) -> u64 {
        let (reg, shift) = if ch < 10 {
            (1, 3 * u32::from(ch))
        } else {
            (0, 3 * u32::from(ch.saturating_sub(10)))
        };
        let code = (self.smpr.get(reg).copied().unwrap_or(0) >> shift) & 7;
        SAMPLE_CYCLES.get(code as usize).copied().unwrap_or(3)
    }

    fn resolution_bits(&self) -> u32 {
        [12, 10, 8, 6]
            .get(((self.cr1 >> 24) & 3) as usize)
            .copied()
            .unwrap_or(12)
    }

    fn start(&mut self, rank: u32, now: u64) {
        let ch = self.sequence_channel(rank);
        let hz = u64::from(self.adc_hz().max(1));
        let sample = self.sample_cycles(ch);
        let total = sample + u64::from(self.resolution_bits());
        let sample_end = now + (sample * 1_000_000_000).div_ceil(hz);
        let end = now + (total * 1_000_000_000).div_ceil(hz);
        self.conversion = Some((rank, sample_end, end));
        self.sr |= STRT;
    }

    /// The next time a conversion's sampling or conversion ends.
    pub fn next_event(&self) -> u64 {
        match self.conversion {
            Some((_, s, _)) if self.sampled.is_none() => s,
            Some((_, _, e)) => e,
            None => u64::MAX,
        }
    }

    /// Processes sampling and conversion ends due by `now`.
    pub fn process<O: Outside>(&mut self, now: u64, outside: &mut O) {
        while let Some((rank, sample_end, end)) = self.conversion {
            if self.sampled.is_none() {
                if sample_end > now {
                    return;
                }
                let ch = self.sequence_channel(rank);
                self.sampled = Some(self.convert(ch, outside, sample_end));
            }
            if end > now {
                return;
            }
            self.finish(rank, end);
        }
    }

    fn convert<O: Outside>(&self, ch: u8, outside: &mut O, t: u64) -> u32 {
        let volts = match ch {
            16 | 17 if self.ccr & TSVREFE == 0 => 0.0,
            16 => 0.76,
            17 => 1.21,
            18 if self.ccr & VBATE == 0 => 0.0,
            18 => VREF / 2.0,
            _ => channel_pin(ch).map_or(0.0, |p| outside.analog_volts(p, t)),
        };
        let code = (volts / VREF * 4096.0).round().clamp(0.0, 4095.0) as u32;
        code >> (12 - self.resolution_bits())
    }

    fn finish(&mut self, rank: u32, end: u64) {
        let value = self.sampled.take().unwrap_or(0);
        self.conversion = None;
        let aligned = if self.cr2 & ALIGN != 0 {
            value << (16 - self.resolution_bits())
        } else {
            value
        };
        let each = self.cr2 & EOCS != 0;
        if (each || self.cr2 & DMA != 0) && self.sr & EOC != 0 {
            self.sr |= OVR;
        }
        self.dr = aligned;
        let last = rank + 1 >= self.sequence_len();
        if each || last {
            self.sr |= EOC;
        }
        if !last {
            self.start(rank + 1, end);
        } else if self.cr2 & CONT != 0 {
            self.start(0, end);
        }
    }

    /// The ADC interrupt line.
    pub fn irq(&self) -> bool {
        (self.cr1 & EOCIE != 0 && self.sr & EOC != 0)
            || (self.cr1 & OVRIE != 0 && self.sr & OVR != 0)
            || (self.cr1 & AWDIE != 0 && self.sr & AWD != 0)
    }

    /// The DMA request (each conversion with CR2.DMA).
    pub fn dma_request(&self) -> bool {
        self.cr2 & DMA != 0 && self.sr & EOC != 0
    }

    /// ADC1 register read.
    pub fn read(&mut self, offset: u32) -> Option<u32> {
        Some(match offset {
            SR => self.sr,
            CR1 => self.cr1,
            CR2 => self.cr2,
            SMPR1 => self.smpr[0],
            SMPR2 => self.smpr[1],
            JOFR1..=JOFR4 => *self.jofr.get(((offset - JOFR1) / 4) as usize)?,
            HTR => self.htr,
            LTR => self.ltr,
            SQR1..=SQR3 => *self.sqr.get(((offset - SQR1) / 4) as usize)?,
            JSQR => self.jsqr,
            JDR1..=JDR4 => 0,
            DR => {
                self.sr &= !EOC;
                self.dr
            }
            _ => return None,
        })
    }

    /// ADC1 register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        match offset {
            SR => self.sr &= value | !0x3F,
            CR1 => {
                self.cr1 = value & 0x07C0_FFFF;
                if value & (JEOCIE | AWDIE | 1 << 23 | 1 << 22) != 0 {
                    self.unmodelled
                        .push("ADC injected channels / analog watchdog");
                }
            }
            CR2 => self.write_cr2(value, now),
            SMPR1 => self.smpr[0] = value & 0x07FF_FFFF,
            SMPR2 => self.smpr[1] = value & 0x3FFF_FFFF,
            JOFR1..=JOFR4 => *self.jofr.get_mut(((offset - JOFR1) / 4) as usize)? = value & 0xFFF,
            HTR => self.htr = value & 0xFFF,
            LTR => self.ltr = value & 0xFFF,
            SQR1..=SQR3 => *self.sqr.get_mut(((offset - SQR1) / 4) as usize)? = value,
            JSQR => {
                self.jsqr = value;
                self.unmodelled.push("ADC injected sequence");
            }
            JDR1..=JDR4 | DR => {}
            _ => return None,
        }
        Some(())
    }

    fn write_cr2(&mut self, value: u32, now: u64) {
        let was_on = self.cr2 & ADON != 0;
        self.cr2 = value & !(SWSTART | JSWSTART);
        if value & ADON == 0 {
            self.conversion = None;
            self.sampled = None;
            return;
        }
        if !was_on {
            self.powered_at = now;
        }
        if value & JSWSTART != 0 || value & (3 << 28 | 3 << 20) != 0 {
            self.unmodelled
                .push("ADC injected / externally triggered conversions");
        }
        if value & SWSTART != 0 && self.conversion.is_none() {
            if now < self.powered_at + STAB_NS {
                self.violations
                    .push("ADC conversion started before t_STAB (3 µs) after ADON (DS8626)");
            }
            self.start(0, now);
        }
    }

    /// Common register read (CSR mirrors ADC1's flags).
    pub fn common_read(&self, offset: u32) -> Option<u32> {
        match offset {
            CSR => Some(self.sr & 0x3F),
            CCR => Some(self.ccr),
            CDR => Some(0),
            _ => None,
        }
    }

    /// Common register write.
    pub fn common_write(&mut self, offset: u32, value: u32) -> Option<()> {
        match offset {
            CCR => {
                self.ccr = value & 0x00C3_EF1F;
                if value & 0xEF1F != 0 {
                    self.unmodelled
                        .push("ADC multi-mode / DMA mode of the common block");
                }
            }
            CSR | CDR => {}
            _ => return None,
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stm32f405::testing::Board;

    /// blocking_read(PC3, CYCLES480) as adc/v2.rs does it, 84 MHz PCLK2 → ADCPRE /4.
    #[test]
    fn a_blocking_read_converts_the_pin_voltage_after_sample_plus_12_cycles() {
        let mut a = Adc::new();
        let mut b = Board::default();
        b.volts.insert(Pin::new(2, 3), 1.65);
        a.set_pclk2(84_000_000);
        a.common_write(CCR, 1 << 16);
        assert_eq!(a.adc_hz(), 21_000_000);
        a.write(CR2, ADON, 0);
        a.write(CR2, 0, 3_000);
        a.write(CR2, ADON, 3_000);
        a.write(SQR1, 0, 6_000);
        a.write(SQR3, 13, 6_000);
        a.write(SMPR1, 7 << 9, 6_000);
        a.write(SR, !EOC, 6_000);
        a.write(CR2, ADON | SWSTART, 6_000);
        assert_eq!(a.read(SR).unwrap() & (STRT | EOC), STRT);
        let end = 6_000 + (492u64 * 1_000_000_000).div_ceil(21_000_000);
        assert_eq!(
            a.next_event(),
            6_000 + (480u64 * 1_000_000_000).div_ceil(21_000_000)
        );
        a.process(end - 1, &mut b);
        assert_eq!(a.read(SR).unwrap() & EOC, 0);
        a.process(end, &mut b);
        assert_eq!(a.read(SR).unwrap() & EOC, EOC);
        assert_eq!(a.read(DR), Some(2048));
        assert_eq!(a.read(SR).unwrap() & EOC, 0, "reading DR clears EOC");
        assert!(a.violations.is_empty());
    }

    #[test]
    fn resolution_alignment_internal_channels_and_clamping() {
        let mut a = Adc::new();
        let mut b = Board::default();
        b.volts.insert(Pin::new(0, 0), 5.0);
        a.write(CR2, ADON, 0);
        a.write(CR2, ADON | SWSTART, 10_000);
        a.process(u64::MAX - 1, &mut b);
        assert_eq!(a.read(DR), Some(4095));
        a.write(CR1, 2 << 24, 0);
        a.write(CR2, ADON | ALIGN | SWSTART, 10_000_000);
        a.process(u64::MAX - 1, &mut b);
        assert_eq!(a.read(DR), Some(0xFF << 8));
        a.write(CR1, 0, 0);
        a.write(SQR3, 17, 0);
        a.write(CR2, ADON | SWSTART, 20_000_000);
        a.process(u64::MAX - 1, &mut b);
        assert_eq!(a.read(DR), Some(0), "VREFINT needs TSVREFE");
        a.common_write(CCR, TSVREFE);
        a.write(CR2, ADON | SWSTART, 30_000_000);
        a.process(u64::MAX - 1, &mut b);
        assert_eq!(a.read(DR), Some(1502));
    }

    #[test]
    fn a_conversion_right_after_adon_is_flagged() {
        let mut a = Adc::new();
        a.write(CR2, ADON, 0);
        a.write(CR2, ADON | SWSTART, 1_000);
        assert_eq!(a.violations.len(), 1);
    }
}
