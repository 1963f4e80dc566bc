//! The DAC (RM0090 §14), channel 1 on PA4 in full and channel 2's registers: CR (EN, BOFF,
//! TEN, TSEL, DMAEN, DMAUDRIE), SWTRIGR, the data holding registers (12-bit right/left,
//! 8-bit, dual), DOR, SR.DMAUDR.
//!
//! Without TEN the holding register reaches the output at once (one APB1 clock); with TEN
//! only a trigger of the selected source moves it — and only a trigger raises the DMA
//! request that refills it (§14.3.7); a trigger finding the previous request unserved is a
//! DMA underrun. Output = VREF+ · DOR / 4096 while enabled; its history (time, volts or
//! `None` when disabled) is kept for the board (the "tones start with a click" finding).
//! Not modelled (recorded): noise/triangle waves, channel 2's output.

/// The reference on VREF+.
const VREF: f32 = 3.3;
/// Kept history entries before the oldest are dropped.
const HISTORY_CAP: usize = 1 << 20;

const CR: u32 = 0x00;
const SWTRIGR: u32 = 0x04;
const DHR12R1: u32 = 0x08;
const DHR12L1: u32 = 0x0C;
const DHR8R1: u32 = 0x10;
const DHR12R2: u32 = 0x14;
const DHR12L2: u32 = 0x18;
const DHR8R2: u32 = 0x1C;
const DHR12RD: u32 = 0x20;
const DHR12LD: u32 = 0x24;
const DHR8RD: u32 = 0x28;
const DOR1: u32 = 0x2C;
const DOR2: u32 = 0x30;
const SR: u32 = 0x34;

const EN1: u32 = 1 << 0;
const TEN1: u32 = 1 << 2;
const DMAEN1: u32 = 1 << 12;
const DMAUDRIE1: u32 = 1 << 13;
const DMAUDR1: u32 = 1 << 13;

/// Trigger sources by TSEL code (RM0090 §14.5.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trigger {
    /// TIM6 TRGO (TSEL 000).
    Tim6,
    /// TIM8 TRGO (001).
    Tim8,
    /// TIM7 TRGO (010).
    Tim7,
    /// TIM5 TRGO (011).
    Tim5,
    /// TIM2 TRGO (100).
    Tim2,
    /// TIM4 TRGO (101).
    Tim4,
    /// EXTI line 9 (110).
    Exti9,
    /// SWTRIGR (111).
    Software,
}

impl Trigger {
    fn from_tsel(tsel: u32) -> Self {
        match tsel & 7 {
            0 => Self::Tim6,
            1 => Self::Tim8,
            2 => Self::Tim7,
            3 => Self::Tim5,
            4 => Self::Tim2,
            5 => Self::Tim4,
            6 => Self::Exti9,
            _ => Self::Software,
        }
    }
}

/// One sample of channel 1's output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DacSample {
    /// When the output changed.
    pub at_ns: u64,
    /// The voltage, `None` while the channel is disabled (PA4 not driven by the DAC).
    pub volts: Option<f32>,
}

/// The DAC.
pub struct Dac {
    cr: u32,
    dhr: [u16; 2],
    dor: [u16; 2],
    sr: u32,
    /// Channel 1's DMA request raised by a trigger and not yet served.
    request: bool,
    history: Vec<DacSample>,
    last: Option<f32>,
    /// History entries dropped because nobody took them.
    pub dropped: u64,
    /// Triggers that moved data to the output.
    pub conversions: u64,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Default for Dac {
    fn default() -> Self {
        Self::new()
    }
}

impl Dac {
    /// Reset state.
    pub fn new() -> Self {
        Self {
            cr: 0,
            dhr: [0; 2],
            dor: [0; 2],
            sr: 0,
            request: false,
            history: Vec::new(),
            last: None,
            dropped: 0,
            conversions: 0,
            unmodelled: Vec::new(),
        }
    }

    /// Back to reset values at `now` (the output goes off).
    pub fn reset(&mut self, now: u64) {
        let (history, last, dropped) = (std::mem::take(&mut self.history), self.last, self.dropped);
        let u = std::mem::take(&mut self.unmodelled);
        *self = Self::new();
        self.history = history;
        self.last = last;
        self.dropped = dropped;
        self.unmodelled = u;
        self.record(now);
    }

    /// The trigger channel 1 listens to, if TEN1 is set.
    pub fn trigger_source(&self) -> Option<Trigger> {
        (self.cr & TEN1 != 0).then(|| Trigger::from_tsel(self.cr >> 3))
    }

    /// Whether a timer's TRGO reaches the DAC with a DMA refill behind it.
    pub fn listens_with_dma(&self, source: Trigger) -> bool {
        self.trigger_source() == Some(source) && self.cr & DMAEN1 != 0
    }

    /// A trigger pulse from `source` at `t`.
    pub fn trigger(&mut self, source: Trigger, t: u64) {
        if self.trigger_source() != Some(source) || self.cr & EN1 == 0 {
            return;
        }
        self.dor[0] = self.dhr[0];
        self.conversions += 1;
        self.record(t);
        if self.cr & DMAEN1 != 0 && self.sr & DMAUDR1 == 0 {
            if self.request {
                // RM0090 §14.3.9: the previous request was not served.
                self.sr |= DMAUDR1;
                self.request = false;
            } else {
                self.request = true;
            }
        }
    }

    /// Channel 1's DMA request.
    pub fn dma_request(&self) -> bool {
        self.request
    }

    /// The DAC underrun interrupt (shares TIM6_DAC).
    pub fn irq(&self) -> bool {
        self.sr & DMAUDR1 != 0 && self.cr & DMAUDRIE1 != 0
    }

    fn volts(&self) -> Option<f32> {
        (self.cr & EN1 != 0).then(|| VREF * f32::from(self.dor[0]) / 4096.0)
    }

    fn record(&mut self, t: u64) {
        let v = self.volts();
        if v == self.last {
            return;
        }
        self.last = v;
        if self.history.len() >= HISTORY_CAP {
            self.history.remove(0);
            self.dropped += 1;
        }
        self.history.push(DacSample { at_ns: t, volts: v });
    }

    /// Channel 1's output now.
    pub fn output(&self) -> Option<f32> {
        self.volts()
    }

    /// Takes the output history recorded so far.
    pub fn take_history(&mut self) -> Vec<DacSample> {
        std::mem::take(&mut self.history)
    }

    fn set_dhr(&mut self, ch: usize, value: u16, now: u64, dma: bool) {
        if let Some(d) = self.dhr.get_mut(ch) {
            *d = value & 0xFFF;
        }
        if ch == 0 {
            if dma {
                self.request = false;
            }
            if self.cr & TEN1 == 0 {
                self.dor[0] = self.dhr[0];
                self.record(now);
            }
        } else if self.cr & (1 << 18) == 0 {
            self.dor[1] = self.dhr[1];
        }
    }

    /// Register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        Some(match offset {
            CR => self.cr,
            SWTRIGR => 0,
            DHR12R1 => u32::from(self.dhr[0]),
            DHR12L1 => u32::from(self.dhr[0]) << 4,
            DHR8R1 => u32::from(self.dhr[0] >> 4),
            DHR12R2 => u32::from(self.dhr[1]),
            DHR12L2 => u32::from(self.dhr[1]) << 4,
            DHR8R2 => u32::from(self.dhr[1] >> 4),
            DHR12RD => u32::from(self.dhr[0]) | u32::from(self.dhr[1]) << 16,
            DHR12LD => u32::from(self.dhr[0]) << 4 | u32::from(self.dhr[1]) << 20,
            DHR8RD => u32::from(self.dhr[0] >> 4) | u32::from(self.dhr[1] >> 4) << 8,
            DOR1 => u32::from(self.dor[0]),
            DOR2 => u32::from(self.dor[1]),
            SR => self.sr,
            _ => return None,
        })
    }

    /// Register write at `now`; `dma`: the DMA controller is the writer (it serves the
    /// request).
    pub fn write(&mut self, offset: u32, value: u32, now: u64, dma: bool) -> Option<()> {
        match offset {
            CR => {
                self.cr = value & 0x3FFF_3FFF;
                if value & (0xFC0 | 0xFC0 << 16) != 0 {
                    self.unmodelled.push("DAC noise/triangle wave generation");
                }
                if value & EN1 == 0 || value & DMAEN1 == 0 {
                    self.request = false;
                }
                if value & TEN1 == 0 {
                    self.dor[0] = self.dhr[0];
                }
                self.record(now);
            }
            SWTRIGR => {
                if value & 1 != 0 {
                    self.trigger(Trigger::Software, now);
                }
                if value & 2 != 0 && self.cr & (7 << 19) == 7 << 19 {
                    self.dor[1] = self.dhr[1];
                }
            }
            DHR12R1 => self.set_dhr(0, value as u16, now, dma),
            DHR12L1 => self.set_dhr(0, (value >> 4) as u16, now, dma),
            DHR8R1 => self.set_dhr(0, ((value & 0xFF) << 4) as u16, now, dma),
            DHR12R2 => self.set_dhr(1, value as u16, now, dma),
            DHR12L2 => self.set_dhr(1, (value >> 4) as u16, now, dma),
            DHR8R2 => self.set_dhr(1, ((value & 0xFF) << 4) as u16, now, dma),
            DHR12RD => {
                self.set_dhr(0, value as u16, now, dma);
                self.set_dhr(1, (value >> 16) as u16, now, dma);
            }
            DHR12LD => {
                self.set_dhr(0, (value >> 4) as u16, now, dma);
                self.set_dhr(1, (value >> 20) as u16, now, dma);
            }
            DHR8RD => {
                self.set_dhr(0, ((value & 0xFF) << 4) as u16, now, dma);
                self.set_dhr(1, ((value >> 8 & 0xFF) << 4) as u16, now, dma);
            }
            DOR1 | DOR2 => {}
            SR => self.sr &= !(value & (DMAUDR1 | DMAUDR1 << 16)),
            _ => return None,
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_ten_the_holding_register_is_the_output() {
        let mut d = Dac::new();
        d.write(CR, EN1, 100, false);
        assert_eq!(d.output(), Some(0.0));
        d.write(DHR12R1, 620, 200, false);
        let v = d.output().unwrap();
        assert!((v - 0.4995).abs() < 1e-3, "{v}");
        let h = d.take_history();
        assert_eq!(h.len(), 2);
        assert_eq!(h[1].at_ns, 200);
    }

    /// The firmware's speaker: TSEL = TIM6, DMA, EN — but TEN never set. TIM6's updates
    /// then neither trigger nor request: the DMA never moves a sample and the output stays
    /// at 0 V until `set(CENTRE_COUNTS)` writes 0.5 V.
    #[test]
    fn triggers_need_ten_so_the_firmwares_tone_never_plays() {
        let mut d = Dac::new();
        d.write(CR, EN1, 0, false);
        d.write(CR, EN1 | DMAEN1, 10, false);
        for t in 0..100 {
            d.trigger(Trigger::Tim6, 1_000 + t * 7_692);
        }
        assert!(!d.dma_request());
        assert_eq!(d.conversions, 0);
        assert_eq!(d.output(), Some(0.0));
        assert!(!d.listens_with_dma(Trigger::Tim6));
    }

    #[test]
    fn with_ten_each_trigger_outputs_and_requests_the_next_sample() {
        let mut d = Dac::new();
        d.write(CR, EN1 | TEN1 | DMAEN1 | DMAUDRIE1, 0, false);
        assert!(d.listens_with_dma(Trigger::Tim6));
        d.write(DHR12R1, 1000, 5, true);
        d.trigger(Trigger::Tim6, 10);
        assert_eq!(d.read(DOR1), Some(1000));
        assert!(d.dma_request());
        d.write(DHR12R1, 2000, 10, true);
        assert!(!d.dma_request());
        d.trigger(Trigger::Tim2, 20);
        assert_eq!(d.read(DOR1), Some(1000), "another timer's TRGO is ignored");
        d.trigger(Trigger::Tim6, 30);
        assert_eq!(d.read(DOR1), Some(2000));
        // Not served before the next trigger: underrun, requests stop.
        d.trigger(Trigger::Tim6, 40);
        assert_eq!(d.read(SR), Some(DMAUDR1));
        assert!(d.irq());
        assert!(!d.dma_request());
    }
}
