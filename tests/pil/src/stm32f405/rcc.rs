//! Reset and clock control (RM0090 §7) with the power controller's few bits the HAL touches
//! (§5: VOS, DBP): the oscillators and PLLs with their start-up times, the system clock
//! switch, the bus prescalers → the clock tree every other block runs on, the peripheral
//! clock enables and resets, the backup domain and the reset flags.
//!
//! Start-up times are DS8626's typical figures: HSI 2.2 µs ("HSI oscillator
//! characteristics"), HSE 2 ms for an 8 MHz resonator ("HSE 4-26 MHz oscillator
//! characteristics", t_SU(HSE)), LSI 15 µs (t_SU(LSI)), main PLL 100 µs (t_LOCK at a
//! 336 MHz VCO). An HSE can be made to never start (`set_hse_fault`): the "boot hangs on
//! missing clocks" finding.

use super::map::Block;

/// HSI frequency.
pub const HSI_HZ: u32 = 16_000_000;
/// HSI start-up, ns.
const HSI_STARTUP_NS: u64 = 2_200;
/// HSE start-up with an 8 MHz resonator, ns.
const HSE_STARTUP_NS: u64 = 2_000_000;
/// LSI start-up, ns.
const LSI_STARTUP_NS: u64 = 15_000;
/// PLL lock time, ns.
const PLL_LOCK_NS: u64 = 100_000;
/// The LSI's range over process and temperature (DS8626 "LSI oscillator characteristics").
pub const LSI_RANGE_HZ: std::ops::RangeInclusive<u32> = 17_000..=47_000;
/// The LSI's typical frequency.
pub const LSI_TYPICAL_HZ: u32 = 32_000;

// RCC register offsets (RM0090 §7.3.24 register map).
const CR: u32 = 0x00;
const PLLCFGR: u32 = 0x04;
const CFGR: u32 = 0x08;
const CIR: u32 = 0x0C;
const AHB1RSTR: u32 = 0x10;
const APB2RSTR: u32 = 0x24;
const AHB1ENR: u32 = 0x30;
const APB2ENR: u32 = 0x44;
const AHB1LPENR: u32 = 0x50;
const APB2LPENR: u32 = 0x64;
const BDCR: u32 = 0x70;
const CSR: u32 = 0x74;
const SSCGR: u32 = 0x80;
const PLLI2SCFGR: u32 = 0x84;
/// PLLSAICFGR and DCKCFGR: STM32F42x/F446 registers, reserved (read 0) on the F405.
const F42X_ONLY: std::ops::RangeInclusive<u32> = 0x88..=0x8C;

// CR bits.
const HSION: u32 = 1 << 0;
const HSIRDY: u32 = 1 << 1;
const HSEON: u32 = 1 << 16;
const HSERDY: u32 = 1 << 17;
const HSEBYP: u32 = 1 << 18;
const CSSON: u32 = 1 << 19;
const PLLON: u32 = 1 << 24;
const PLLRDY: u32 = 1 << 25;
const PLLI2SON: u32 = 1 << 26;
const PLLI2SRDY: u32 = 1 << 27;
/// The bits software can set in RCC_CR (the ready flags are derived, HSICAL is factory).
const CR_WRITABLE: u32 = HSION | 0xF8 | HSEON | HSEBYP | CSSON | PLLON | PLLI2SON;
/// HSITRIM at its reset value 16 and a plausible factory HSICAL.
const CR_RESET_TRIM_CAL: u32 = 0x0000_4880;

// CSR bits.
const LSION: u32 = 1 << 0;
const LSIRDY: u32 = 1 << 1;
const RMVF: u32 = 1 << 24;
const BORRSTF: u32 = 1 << 25;
const PINRSTF: u32 = 1 << 26;
const PORRSTF: u32 = 1 << 27;
const SFTRSTF: u32 = 1 << 28;
const IWDGRSTF: u32 = 1 << 29;
const RESET_FLAGS: u32 = 0xFE00_0000;

// BDCR bits.
const LSEON: u32 = 1 << 0;
const LSERDY: u32 = 1 << 1;
const BDRST: u32 = 1 << 16;

// PWR.
const PWR_CR: u32 = 0x00;
const PWR_CSR: u32 = 0x04;
const PWR_DBP: u32 = 1 << 8;
const PWR_VOS: u32 = 1 << 14;
const PWR_BRE: u32 = 1 << 9;
const PWR_BRR: u32 = 1 << 3;
const PWR_VOSRDY: u32 = 1 << 14;

/// Why the chip came out of reset, for RCC_CSR's flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResetKind {
    /// Power applied (POR/BOR).
    PowerOn,
    /// The NRST pin pulled low from outside.
    Pin,
    /// The core's SYSRESETREQ.
    Software,
    /// The independent watchdog expired.
    IndependentWatchdog,
}

/// The clock tree as the firmware configured it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clocks {
    /// SYSCLK.
    pub sysclk: u32,
    /// HCLK: the core, AHB, memories, DMA.
    pub hclk: u32,
    /// APB1 peripheral clock.
    pub pclk1: u32,
    /// APB2 peripheral clock.
    pub pclk2: u32,
    /// Timer clock on APB1 (×2 when the APB1 prescaler divides).
    pub tim_apb1: u32,
    /// Timer clock on APB2.
    pub tim_apb2: u32,
    /// PLL48CLK (USB, RNG), 0 while the PLL is not locked.
    pub pll48: u32,
    /// The LSI (IWDG), running or not.
    pub lsi: u32,
}

/// An oscillator or PLL: switched on at some time, ready once its start-up has passed.
#[derive(Clone, Copy, Debug)]
struct Osc {
    on: bool,
    ready_at: u64,
}

impl Osc {
    const OFF: Self = Self {
        on: false,
        ready_at: u64::MAX,
    };

    fn ready(&self, now: u64) -> bool {
        self.on && now >= self.ready_at
    }

    fn switch(&mut self, on: bool, ready_at: u64) {
        if on && !self.on {
            *self = Self { on, ready_at };
        } else if !on {
            *self = Self::OFF;
        }
    }
}

/// RCC and PWR state.
pub struct Rcc {
    cr: u32,
    pllcfgr: u32,
    cfgr: u32,
    cir: u32,
    /// AHB1, AHB2, AHB3, (reserved), APB1, APB2 reset registers at 0x10..0x24.
    rstr: [u32; 6],
    enr: [u32; 6],
    lpenr: [u32; 6],
    bdcr: u32,
    csr: u32,
    sscgr: u32,
    plli2scfgr: u32,
    pwr_cr: u32,
    pwr_csr: u32,
    hsi: Osc,
    hse: Osc,
    lsi: Osc,
    pll: Osc,
    plli2s: Osc,
    /// The clock switch (SWS) in effect; SW may ask for one that is not ready yet.
    sws: u32,
    /// Board facts and injected faults.
    hse_hz: u32,
    hse_fault: bool,
    lsi_hz: u32,
    /// The watchdog forces the LSI on (RM0090 §21.3.1).
    lsi_forced: bool,
}

/// What a register write did beyond storing bits: the SoC reacts to these.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RccEffects {
    /// The clock tree may have changed.
    pub clocks_changed: bool,
    /// Blocks whose reset bit went from 0 to 1.
    pub reset: Vec<Block>,
    /// Rule breaks to record.
    pub violations: Vec<String>,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Rcc {
    /// Power-on state: HSI on and ready, everything else off.
    pub fn new(hse_hz: u32, lsi_hz: u32) -> Self {
        let mut r = Self {
            cr: 0,
            pllcfgr: 0,
            cfgr: 0,
            cir: 0,
            rstr: [0; 6],
            enr: [0; 6],
            lpenr: [0; 6],
            bdcr: 0,
            csr: 0,
            sscgr: 0,
            plli2scfgr: 0,
            pwr_cr: 0,
            pwr_csr: 0,
            hsi: Osc::OFF,
            hse: Osc::OFF,
            lsi: Osc::OFF,
            pll: Osc::OFF,
            plli2s: Osc::OFF,
            sws: 0,
            hse_hz,
            hse_fault: false,
            lsi_hz,
            lsi_forced: false,
        };
        r.reset(ResetKind::PowerOn);
        r
    }

    /// A system reset: registers to their reset values (RM0090 §7.3), the backup domain
    /// (BDCR) kept unless power was lost, CSR's flags per `kind`.
    pub fn reset(&mut self, kind: ResetKind) {
        self.cr = CR_RESET_TRIM_CAL | HSION;
        self.pllcfgr = 0x2400_3010;
        self.cfgr = 0;
        self.cir = 0;
        self.rstr = [0; 6];
        self.enr = [0x0010_0000, 0, 0, 0, 0, 0];
        self.lpenr = [0x7E67_91FF, 0xF1, 1, 0, 0x36FE_C9FF, 0x0007_5F33];
        self.sscgr = 0;
        self.plli2scfgr = 0x2000_3000;
        self.pwr_cr = PWR_VOS;
        self.pwr_csr = 0;
        self.hsi = Osc {
            on: true,
            ready_at: 0,
        };
        self.hse = Osc::OFF;
        self.pll = Osc::OFF;
        self.plli2s = Osc::OFF;
        self.sws = 0;
        self.lsi = Osc::OFF;
        self.lsi_forced = false;
        let flags = match kind {
            ResetKind::PowerOn => {
                self.bdcr = 0;
                self.csr = 0;
                PORRSTF | BORRSTF | PINRSTF
            }
            // Every internal reset source also pulls NRST low through the pulse generator
            // (RM0090 §7.1.2, Figure 13), so PINRSTF is set with its own flag.
            ResetKind::Pin => PINRSTF,
            ResetKind::Software => SFTRSTF | PINRSTF,
            ResetKind::IndependentWatchdog => IWDGRSTF | PINRSTF,
        };
        self.csr = (self.csr & RESET_FLAGS) | flags;
    }

    /// Sets the LSI frequency (the runner's `--lsi-hz`, within DS8626's range).
    pub fn set_lsi_hz(&mut self, hz: u32) {
        self.lsi_hz = hz;
    }

    /// Makes the HSE never start (a broken resonator), or start again.
    pub fn set_hse_fault(&mut self, fault: bool) {
        self.hse_fault = fault;
    }

    /// The watchdog was started: LSI runs whatever LSION says.
    pub fn force_lsi(&mut self, now: u64) {
        if !self.lsi_forced {
            self.lsi_forced = true;
            if !self.lsi.on {
                self.lsi.switch(true, now + LSI_STARTUP_NS);
            }
        }
    }

    /// Whether the LSI oscillates at `now`.
    pub fn lsi_running(&self, now: u64) -> bool {
        self.lsi.ready(now)
    }

    /// PLL48CLK, 0 if not running (RNG clock-error path, USB).
    fn pll_vco(&self) -> u64 {
        let m = u64::from(self.pllcfgr & 0x3F);
        let n = u64::from((self.pllcfgr >> 6) & 0x1FF);
        let src = if self.pllcfgr & (1 << 22) != 0 {
            u64::from(self.hse_hz)
        } else {
            u64::from(HSI_HZ)
        };
        if m < 2 {
            return 0;
        }
        src * n / m
    }

    fn pll_p(&self) -> u32 {
        let p = 2 * (((self.pllcfgr >> 16) & 3) as u64 + 1);
        (self.pll_vco() / p) as u32
    }

    fn pll_q(&self) -> u32 {
        let q = u64::from((self.pllcfgr >> 24) & 0xF);
        if q < 2 {
            return 0;
        }
        (self.pll_vco() / q) as u32
    }

    /// The clock tree at `now`.
    pub fn clocks(&self, now: u64) -> Clocks {
        let sysclk = match self.sws {
            0 => HSI_HZ,
            1 => self.hse_hz,
            _ => self.pll_p(),
        };
        let hpre = (self.cfgr >> 4) & 0xF;
        let hclk = if hpre < 8 {
            sysclk
        } else {
            let div = [2, 4, 8, 16, 64, 128, 256, 512]
                .get((hpre - 8) as usize)
                .copied()
                .unwrap_or(1);
            sysclk / div
        };
        let apb = |ppre: u32| -> (u32, u32) {
            if ppre < 4 {
                (hclk, hclk)
            } else {
                let p = hclk >> (ppre - 3);
                (p, 2 * p)
            }
        };
        let (pclk1, tim_apb1) = apb((self.cfgr >> 10) & 7);
        let (pclk2, tim_apb2) = apb((self.cfgr >> 13) & 7);
        Clocks {
            sysclk,
            hclk,
            pclk1,
            pclk2,
            tim_apb1,
            tim_apb2,
            pll48: if self.pll.ready(now) { self.pll_q() } else { 0 },
            lsi: self.lsi_hz,
        }
    }

    fn source_ready(&self, sw: u32, now: u64) -> bool {
        match sw {
            0 => self.hsi.ready(now),
            1 => self.hse.ready(now),
            2 => self.pll.ready(now),
            _ => false,
        }
    }

    /// The next time the RCC changes state by itself (a pending clock switch completing).
    pub fn next_event(&self) -> u64 {
        let sw = self.cfgr & 3;
        if sw == self.sws {
            return u64::MAX;
        }
        match sw {
            0 if self.hsi.on => self.hsi.ready_at,
            1 if self.hse.on => self.hse.ready_at,
            2 if self.pll.on => self.pll.ready_at,
            _ => u64::MAX,
        }
    }

    /// Completes a pending clock switch whose source became ready; true if the tree changed.
    pub fn process(&mut self, now: u64) -> bool {
        let sw = self.cfgr & 3;
        if sw != self.sws && self.source_ready(sw, now) {
            self.sws = sw;
            return true;
        }
        false
    }

    /// Whether `block`'s bus clock is enabled.
    pub fn clocked(&self, block: Block) -> bool {
        let bit = |reg: usize, b: u32| self.enr.get(reg).is_some_and(|r| r & (1 << b) != 0);
        match block {
            Block::Gpio(n) => bit(0, u32::from(n)),
            Block::Dma(n) => bit(0, 21 + u32::from(n)),
            Block::OtgFs => bit(1, 7),
            Block::Rng => bit(1, 6),
            Block::Tim2 => bit(4, 0),
            Block::Tim3 => bit(4, 1),
            Block::Tim6 => bit(4, 4),
            Block::Spi3 => bit(4, 15),
            Block::I2c1 => bit(4, 21),
            Block::Pwr => bit(4, 28),
            Block::Dac => bit(4, 29),
            Block::Usart1 => bit(5, 4),
            Block::Adc1 | Block::AdcCommon => bit(5, 8),
            Block::Spi1 => bit(5, 12),
            Block::Syscfg => bit(5, 14),
            Block::Tim9 => bit(5, 16),
            Block::Iwdg
            | Block::Exti
            | Block::Rcc
            | Block::FlashIf
            | Block::Dbgmcu
            | Block::Unmodelled(_) => true,
        }
    }

    /// Whether the backup SRAM's clock is enabled (AHB1ENR.BKPSRAMEN).
    pub fn bkpsram_clocked(&self) -> bool {
        self.enr.first().is_some_and(|r| r & (1 << 18) != 0)
    }

    /// Extra CPU cycles an access to `block` costs: one AHB wait for AHB peripherals, two
    /// APB clocks (setup and access phase) for APB peripherals, in HCLK cycles. An
    /// approximation of the AHB/APB bridges (RM0090 §2.1.10 names no figure).
    pub fn access_cycles(&self, block: Block, now: u64) -> u32 {
        let c = self.clocks(now);
        let apb = |pclk: u32| 2 * (c.hclk / pclk.max(1)).max(1);
        match block {
            Block::Tim2
            | Block::Tim3
            | Block::Tim6
            | Block::Iwdg
            | Block::Spi3
            | Block::I2c1
            | Block::Pwr
            | Block::Dac => apb(c.pclk1),
            Block::Usart1
            | Block::Adc1
            | Block::AdcCommon
            | Block::Spi1
            | Block::Syscfg
            | Block::Exti
            | Block::Tim9 => apb(c.pclk2),
            Block::Dbgmcu => 0,
            _ => 1,
        }
    }

    /// RCC register read at `now`.
    pub fn read(&mut self, offset: u32, now: u64) -> Option<u32> {
        Some(match offset {
            CR => {
                let mut v = self.cr & !(HSIRDY | HSERDY | PLLRDY | PLLI2SRDY);
                let flag = |osc: &Osc, bit: u32| if osc.ready(now) { bit } else { 0 };
                v |= flag(&self.hsi, HSIRDY)
                    | flag(&self.hse, HSERDY)
                    | flag(&self.pll, PLLRDY)
                    | flag(&self.plli2s, PLLI2SRDY);
                v
            }
            PLLCFGR => self.pllcfgr,
            CFGR => (self.cfgr & !0xC) | (self.sws << 2),
            CIR => self.cir,
            AHB1RSTR..=APB2RSTR => *self.rstr.get(((offset - AHB1RSTR) / 4) as usize)?,
            AHB1ENR..=APB2ENR => *self.enr.get(((offset - AHB1ENR) / 4) as usize)?,
            AHB1LPENR..=APB2LPENR => *self.lpenr.get(((offset - AHB1LPENR) / 4) as usize)?,
            BDCR => self.bdcr & !LSERDY,
            CSR => {
                let lsi = if self.lsi.ready(now) { LSIRDY } else { 0 };
                (self.csr & !LSIRDY) | lsi
            }
            SSCGR => self.sscgr,
            PLLI2SCFGR => self.plli2scfgr,
            o if F42X_ONLY.contains(&o) => 0,
            _ => return None,
        })
    }

    /// RCC register write at `now`; `None` where no register is.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<RccEffects> {
        let mut fx = RccEffects::default();
        match offset {
            CR => self.write_cr(value, now, &mut fx),
            PLLCFGR => {
                if self.pll.on {
                    fx.violations.push(
                        "RCC_PLLCFGR written while the PLL is on (RM0090 §7.3.2: write only with PLLON = 0); ignored"
                            .into(),
                    );
                } else {
                    self.pllcfgr = value & 0x0F43_7FFF;
                }
            }
            CFGR => {
                self.cfgr = value & !0xC;
                let sw = value & 3;
                if sw == 3 {
                    fx.violations
                        .push("RCC_CFGR.SW = 11 (not allowed, RM0090 §7.3.3)".into());
                } else if self.source_ready(sw, now) {
                    self.sws = sw;
                }
                if value & 0xFFE0_0000 != 0 {
                    fx.unmodelled.push("RCC_CFGR MCO/RTCPRE/I2SSRC");
                }
                fx.clocks_changed = true;
            }
            CIR => {
                if value & 0x3F00 != 0 {
                    fx.unmodelled.push("RCC_CIR ready interrupts");
                }
                self.cir = value & 0x3F00;
            }
            AHB1RSTR..=APB2RSTR => {
                let i = ((offset - AHB1RSTR) / 4) as usize;
                let old = *self.rstr.get(i)?;
                *self.rstr.get_mut(i)? = value;
                fx.reset = reset_blocks(i, value & !old);
            }
            AHB1ENR..=APB2ENR => *self.enr.get_mut(((offset - AHB1ENR) / 4) as usize)? = value,
            AHB1LPENR..=APB2LPENR => {
                *self.lpenr.get_mut(((offset - AHB1LPENR) / 4) as usize)? = value
            }
            BDCR => self.write_bdcr(value, &mut fx),
            CSR => {
                if value & RMVF != 0 {
                    self.csr &= !RESET_FLAGS;
                }
                let on = value & LSION != 0;
                self.csr = (self.csr & !LSION) | (value & LSION);
                if !self.lsi_forced {
                    self.lsi.switch(on, now + LSI_STARTUP_NS);
                }
            }
            SSCGR => {
                if value & (1 << 31) != 0 {
                    fx.unmodelled.push("RCC_SSCGR spread spectrum");
                }
                self.sscgr = value;
            }
            PLLI2SCFGR => self.plli2scfgr = value,
            o if F42X_ONLY.contains(&o) => fx.violations.push(format!(
                "RCC +0x{o:02x} written (PLLSAICFGR/DCKCFGR of the F42x/F446): the F405 has no register there, the write does nothing"
            )),
            _ => return None,
        }
        Some(fx)
    }

    fn write_cr(&mut self, value: u32, now: u64, fx: &mut RccEffects) {
        let mut v = value;
        // The system clock's source (and the PLL's, while it runs) cannot be stopped.
        let pll_src_hse = self.pllcfgr & (1 << 22) != 0;
        if self.sws == 0 || (self.pll.on && !pll_src_hse) {
            v |= HSION;
        }
        if self.sws == 1 || (self.pll.on && pll_src_hse) {
            v |= HSEON;
        }
        if self.sws == 2 {
            v |= PLLON;
        }
        if self.hse.on && (v ^ self.cr) & HSEBYP != 0 {
            fx.violations
                .push("RCC_CR.HSEBYP changed while the HSE is on (RM0090 §7.3.1)".into());
            v = (v & !HSEBYP) | (self.cr & HSEBYP);
        }
        if v & CSSON != 0 {
            fx.unmodelled.push("RCC_CR.CSSON clock security system");
        }
        self.cr = (self.cr & 0xFF00) | (v & CR_WRITABLE);
        self.hsi.switch(v & HSION != 0, now + HSI_STARTUP_NS);
        let hse_ready = if self.hse_fault {
            u64::MAX
        } else {
            now + HSE_STARTUP_NS
        };
        self.hse.switch(v & HSEON != 0, hse_ready);
        let src = if pll_src_hse { self.hse } else { self.hsi };
        let pll_ready = src.ready_at.max(now).saturating_add(PLL_LOCK_NS);
        let pll_ready = if src.on { pll_ready } else { u64::MAX };
        self.pll.switch(v & PLLON != 0, pll_ready);
        self.plli2s.switch(v & PLLI2SON != 0, pll_ready);
        fx.clocks_changed = true;
    }

    fn write_bdcr(&mut self, value: u32, fx: &mut RccEffects) {
        if self.pwr_cr & PWR_DBP == 0 {
            fx.violations.push(
                "RCC_BDCR written with PWR_CR.DBP = 0 (backup domain write-protected, RM0090 §5.1.2); ignored"
                    .into(),
            );
            return;
        }
        if value & BDRST != 0 {
            self.bdcr = BDRST;
            return;
        }
        if value & LSEON != 0 {
            fx.unmodelled
                .push("RCC_BDCR.LSEON (no 32 kHz crystal on these boards: LSERDY stays 0)");
        }
        self.bdcr = value & 0x0000_8305;
    }

    /// PWR register read.
    pub fn pwr_read(&self, offset: u32) -> Option<u32> {
        match offset {
            PWR_CR => Some(self.pwr_cr),
            PWR_CSR => {
                let brr = if self.pwr_csr & PWR_BRE != 0 {
                    PWR_BRR
                } else {
                    0
                };
                Some(self.pwr_csr | PWR_VOSRDY | brr)
            }
            _ => None,
        }
    }

    /// PWR register write.
    pub fn pwr_write(&mut self, offset: u32, value: u32) -> Option<Vec<&'static str>> {
        let mut unmodelled = Vec::new();
        match offset {
            PWR_CR => {
                if value & 0x2F3 != 0 {
                    unmodelled.push("PWR_CR low-power, PVD and wake-up bits");
                }
                self.pwr_cr = value & 0x43FF;
            }
            PWR_CSR => self.pwr_csr = value & (PWR_BRE | (1 << 8)),
            _ => return None,
        }
        Some(unmodelled)
    }

    /// HSE frequency the board provides.
    pub fn hse_hz(&self) -> u32 {
        self.hse_hz
    }
}

/// The blocks a rising reset bit `bits` in reset register `reg` (0 = AHB1RSTR) hits.
fn reset_blocks(reg: usize, bits: u32) -> Vec<Block> {
    let mut out = Vec::new();
    for b in 0..32 {
        if bits & (1 << b) == 0 {
            continue;
        }
        let block = match (reg, b) {
            (0, 0..=8) => Some(Block::Gpio(b as u8)),
            (0, 21) => Some(Block::Dma(0)),
            (0, 22) => Some(Block::Dma(1)),
            (1, 6) => Some(Block::Rng),
            (1, 7) => Some(Block::OtgFs),
            (4, 0) => Some(Block::Tim2),
            (4, 1) => Some(Block::Tim3),
            (4, 4) => Some(Block::Tim6),
            (4, 15) => Some(Block::Spi3),
            (4, 21) => Some(Block::I2c1),
            (4, 28) => Some(Block::Pwr),
            (4, 29) => Some(Block::Dac),
            (5, 4) => Some(Block::Usart1),
            (5, 8) => Some(Block::Adc1),
            (5, 12) => Some(Block::Spi1),
            (5, 14) => Some(Block::Syscfg),
            (5, 16) => Some(Block::Tim9),
            _ => None,
        };
        out.extend(block);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn embassy_168mhz(r: &mut Rcc, mut now: u64) -> u64 {
        // embassy_stm32::rcc::f247::init with board::clocks(): HSE on, PLL M8 N336 P2 Q7,
        // flash latency, then SW = PLL with /1 /4 /2.
        r.write(CR, HSION | HSEON, now);
        while r.read(CR, now).unwrap() & HSERDY == 0 {
            now += 1_000;
        }
        r.write(PLLCFGR, 8 | 336 << 6 | 1 << 22 | 7 << 24, now);
        r.write(CR, HSION | HSEON | PLLON, now);
        while r.read(CR, now).unwrap() & PLLRDY == 0 {
            now += 1_000;
        }
        r.write(CFGR, 2 | 0b101 << 10 | 0b100 << 13, now);
        now
    }

    #[test]
    fn embassy_clock_setup_gives_the_boards_tree_after_the_datasheet_start_up_times() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        assert_eq!(r.clocks(0).hclk, HSI_HZ, "reset runs on the HSI");
        let done = embassy_168mhz(&mut r, 0);
        assert!(done >= HSE_STARTUP_NS + PLL_LOCK_NS);
        assert!(done < HSE_STARTUP_NS + PLL_LOCK_NS + 3_000);
        assert_eq!(r.read(CFGR, done).unwrap() & 0xC, 2 << 2, "SWS follows SW");
        let c = r.clocks(done);
        assert_eq!(
            (
                c.sysclk, c.hclk, c.pclk1, c.pclk2, c.tim_apb1, c.tim_apb2, c.pll48
            ),
            (
                168_000_000,
                168_000_000,
                42_000_000,
                84_000_000,
                84_000_000,
                168_000_000,
                48_000_000
            )
        );
    }

    #[test]
    fn a_dead_hse_never_becomes_ready() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        r.set_hse_fault(true);
        r.write(CR, HSION | HSEON, 0);
        assert_eq!(r.read(CR, 10_000_000_000).unwrap() & HSERDY, 0);
        r.write(PLLCFGR, 8 | 336 << 6 | 1 << 22 | 7 << 24, 0);
        r.write(CR, HSION | HSEON | PLLON, 0);
        assert_eq!(r.read(CR, 10_000_000_000).unwrap() & PLLRDY, 0);
        r.write(CFGR, 2, 0);
        assert_eq!(
            r.clocks(u64::MAX - 1).sysclk,
            HSI_HZ,
            "the switch never happens"
        );
        assert_eq!(r.next_event(), u64::MAX);
    }

    #[test]
    fn reset_flags_follow_the_cause_and_rmvf_clears_them() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        assert_eq!(
            r.read(CSR, 0).unwrap() & RESET_FLAGS,
            PORRSTF | BORRSTF | PINRSTF
        );
        r.write(CSR, RMVF, 0);
        assert_eq!(r.read(CSR, 0).unwrap() & RESET_FLAGS, 0);
        r.reset(ResetKind::IndependentWatchdog);
        assert_eq!(r.read(CSR, 0).unwrap() & RESET_FLAGS, IWDGRSTF | PINRSTF);
        r.reset(ResetKind::Software);
        assert_eq!(
            r.read(CSR, 0).unwrap() & RESET_FLAGS,
            IWDGRSTF | PINRSTF | SFTRSTF,
            "flags accumulate until RMVF"
        );
    }

    #[test]
    fn lsi_and_peripheral_resets() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        r.write(CSR, LSION, 1_000);
        assert_eq!(r.read(CSR, 1_000 + LSI_STARTUP_NS - 1).unwrap() & LSIRDY, 0);
        assert_eq!(
            r.read(CSR, 1_000 + LSI_STARTUP_NS).unwrap() & LSIRDY,
            LSIRDY
        );
        let fx = r.write(APB2RSTR, 1 << 12 | 1 << 14, 0).unwrap();
        assert_eq!(fx.reset, vec![Block::Spi1, Block::Syscfg]);
        let fx = r.write(APB2RSTR, 1 << 12 | 1 << 14, 0).unwrap();
        assert!(fx.reset.is_empty(), "only a rising bit resets");
        r.write(APB2ENR, 1 << 12, 0);
        assert!(r.clocked(Block::Spi1));
        assert!(!r.clocked(Block::Tim9));
    }

    #[test]
    fn the_f42x_clock_mux_register_is_reserved_on_the_f405() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        assert_eq!(r.read(0x8C, 0), Some(0));
        let fx = r.write(0x8C, 1 << 27, 0).unwrap();
        assert_eq!(fx.violations.len(), 1);
        assert_eq!(r.read(0x8C, 0), Some(0));
        assert_eq!(r.read(0x90, 0), None);
    }

    #[test]
    fn backup_domain_needs_dbp() {
        let mut r = Rcc::new(8_000_000, LSI_TYPICAL_HZ);
        let fx = r.write(BDCR, 0x8200, 0).unwrap();
        assert_eq!(fx.violations.len(), 1);
        assert_eq!(r.read(BDCR, 0), Some(0));
        r.pwr_write(PWR_CR, PWR_DBP | PWR_VOS);
        r.write(BDCR, 0x8200, 0);
        assert_eq!(r.read(BDCR, 0), Some(0x8200));
    }
}
