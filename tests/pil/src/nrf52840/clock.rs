//! CLOCK and POWER, one peripheral slot and one interrupt (ID 0): the 64 MHz crystal
//! (HFXO) and the 32.768 kHz clock (LFCLK) with their start-up times and an injectable
//! crystal that never starts, reset reasons, the DC/DC enables, the retained registers,
//! the supply mode, and the two registers next to them the image writes (APPROTECT.DISABLE,
//! and the undocumented anomaly-198 register at 0xE00).
//!
//! Start-up times (PS "Electrical specification", also quoted in embassy-nrf's `init`):
//! HFXO 0.36 ms typical, LFXO 0.25 s typical, LFRC 0.6 ms, LFSYNT 0.1 ms.

use super::events::{Ctx, EventRegs};

/// HFXO start-up time, ns.
pub const HFXO_START_NS: u64 = 360_000;
/// LFXO start-up time, ns.
pub const LFXO_START_NS: u64 = 250_000_000;
/// LFRC start-up time, ns.
pub const LFRC_START_NS: u64 = 600_000;
/// LFSYNT start-up time, ns.
pub const LFSYNT_START_NS: u64 = 100_000;

/// The nominal LFCLK period in femtoseconds (1 / 32 768 Hz).
pub const LF_PERIOD_FS: u64 = 30_517_578_125;

/// Event indices (offset 0x100 + 4·n).
mod ev {
    pub const HFCLKSTARTED: u32 = 0;
    pub const LFCLKSTARTED: u32 = 1;
}

/// Where the LFCLK ticks: tick k at `origin_ns + k · period`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LfTiming {
    /// The time of tick 0, ns.
    pub origin_ns: u64,
    /// The period, femtoseconds.
    pub period_fs: u64,
}

impl LfTiming {
    /// Ticks completed at `t` (0 before the origin).
    pub fn ticks_at(&self, t: u64) -> u64 {
        let elapsed = u128::from(t.saturating_sub(self.origin_ns));
        (elapsed * 1_000_000 / u128::from(self.period_fs.max(1))) as u64
    }

    /// The time of tick `k`, rounded up to the ns.
    pub fn tick_time(&self, k: u64) -> u64 {
        let fs = u128::from(k) * u128::from(self.period_fs);
        self.origin_ns
            .saturating_add(fs.div_ceil(1_000_000).min(u128::from(u64::MAX)) as u64)
    }
}

/// LFCLKSRC.SRC values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LfSource {
    Rc = 0,
    Xtal = 1,
    Synth = 2,
}

impl LfSource {
    const fn from_reg(v: u32) -> Self {
        match v & 3 {
            1 => LfSource::Xtal,
            2 => LfSource::Synth,
            _ => LfSource::Rc,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Osc {
    Stopped,
    Starting { done_ns: u64 },
    Running,
}

/// Crystals that never start (issue 29: "boot hangs on missing clocks").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClockFaults {
    /// The 32 MHz crystal never oscillates: HFCLKSTARTED never comes.
    pub hfxo_dead: bool,
    /// The 32.768 kHz crystal never oscillates: LFCLKSTARTED never comes with SRC = Xtal.
    pub lfxo_dead: bool,
}

/// How the chip is supplied (PS "POWER": supply modes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Supply {
    /// High-voltage mode: VDDH supplied, REG0 makes VDD (and the GPIO level) at the voltage
    /// UICR.REGOUT0 selects, 1.8 V when it is erased. The nice!nano powers the nRF52840
    /// this way from its B+/RAW pin (shared/reference/hardware.md §5: its 3V3 pin "comes
    /// from the nRF's internal regulator").
    Vddh {
        /// The VDDH voltage, V.
        volts: f32,
    },
    /// Normal mode: VDD supplied directly; the GPIO level is VDD.
    Vdd {
        /// The VDD voltage, V.
        volts: f32,
    },
}

/// RESETREAS bits (PS "POWER").
pub mod resetreas {
    /// Reset pin.
    pub const RESETPIN: u32 = 1 << 0;
    /// Watchdog.
    pub const DOG: u32 = 1 << 1;
    /// Soft reset (AIRCR.SYSRESETREQ).
    pub const SREQ: u32 = 1 << 2;
    /// CPU lock-up.
    pub const LOCKUP: u32 = 1 << 3;
}

/// CLOCK and POWER.
pub struct ClockPower {
    ev: EventRegs,
    faults: ClockFaults,
    supply: Supply,
    lf_period_fs: u64,
    hfxo: Osc,
    hfclk_run: bool,
    lf: Osc,
    lf_src: LfSource,
    lfclksrc: u32,
    lfclk_run: bool,
    lf_timing: Option<LfTiming>,
    resetreas: u32,
    gpregret: [u32; 2],
    dcdcen: u32,
    dcdcen0: u32,
    pofcon: u32,
    ctiv: u32,
    traceconfig: u32,
    lfrcmode: u32,
    ram_power: [u32; 9],
    approtect_disable: u32,
    approtect_force: u32,
    /// The anomaly-198 register (0xE00).
    pub anomaly_198: u32,
}

impl ClockPower {
    /// Power-on state.
    pub fn new(faults: ClockFaults, supply: Supply, lf_ppm: f64) -> Self {
        let period = LF_PERIOD_FS as f64 / (1.0 + lf_ppm * 1e-6);
        Self {
            ev: EventRegs::new(super::map::base::CLOCK_POWER),
            faults,
            supply,
            lf_period_fs: period.round() as u64,
            hfxo: Osc::Stopped,
            hfclk_run: false,
            lf: Osc::Stopped,
            lf_src: LfSource::Rc,
            lfclksrc: 0,
            lfclk_run: false,
            lf_timing: None,
            resetreas: 0,
            gpregret: [0; 2],
            dcdcen: 0,
            dcdcen0: 0,
            pofcon: 0,
            ctiv: 0,
            traceconfig: 0,
            lfrcmode: 0,
            ram_power: [0xFFFF; 9],
            approtect_disable: 0,
            approtect_force: 0,
            anomaly_198: 0,
        }
    }

    /// The LFCLK's ticks while it runs.
    pub const fn lf_timing(&self) -> Option<LfTiming> {
        self.lf_timing
    }

    /// The LFCLK period the chip's 32.768 kHz sources run at (femtoseconds).
    pub const fn lf_period_fs(&self) -> u64 {
        self.lf_period_fs
    }

    /// Whether the HFXO runs (the radio-grade clock; the CPU runs at 64 MHz either way).
    pub const fn hfxo_running(&self) -> bool {
        matches!(self.hfxo, Osc::Running)
    }

    /// RESETREAS as the image reads it.
    pub const fn reset_reason(&self) -> u32 {
        self.resetreas
    }

    /// The interrupt line (POWER_CLOCK, IRQ 0).
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    /// The next oscillator start-up completion.
    pub fn next_event_ns(&self) -> u64 {
        let done = |o: Osc| match o {
            Osc::Starting { done_ns } => done_ns,
            _ => u64::MAX,
        };
        done(self.hfxo).min(done(self.lf))
    }

    /// Completes the start-ups due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        if let Osc::Starting { done_ns } = self.hfxo
            && done_ns <= ctx.now
        {
            self.hfxo = Osc::Running;
            self.ev.raise(ev::HFCLKSTARTED, ctx.fired);
        }
        if let Osc::Starting { done_ns } = self.lf
            && done_ns <= ctx.now
        {
            self.lf = Osc::Running;
            self.lf_timing = Some(LfTiming {
                origin_ns: done_ns,
                period_fs: self.lf_period_fs,
            });
            self.ev.raise(ev::LFCLKSTARTED, ctx.fired);
        }
    }

    fn start_hfxo(&mut self, now: u64) {
        self.hfclk_run = true;
        if self.hfxo == Osc::Stopped {
            self.hfxo = if self.faults.hfxo_dead {
                // Oscillating never: the start-up never completes.
                Osc::Starting { done_ns: u64::MAX }
            } else {
                Osc::Starting {
                    done_ns: now + HFXO_START_NS,
                }
            };
        }
    }

    fn start_lfclk(&mut self, now: u64) {
        self.lfclk_run = true;
        if self.lf != Osc::Stopped {
            return;
        }
        self.lf_src = LfSource::from_reg(self.lfclksrc);
        let start = match self.lf_src {
            LfSource::Xtal if self.faults.lfxo_dead => u64::MAX - now,
            LfSource::Xtal => LFXO_START_NS,
            LfSource::Rc => LFRC_START_NS,
            LfSource::Synth => LFSYNT_START_NS,
        };
        self.lf = Osc::Starting {
            done_ns: now.saturating_add(start),
        };
    }

    /// A register read; `None` for offsets the model does not implement.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        let running = |o: Osc| u32::from(o == Osc::Running);
        Some(match offset {
            0x400 => self.resetreas,
            0x408 => u32::from(self.hfclk_run),
            0x40C => running(self.hfxo) | (running(self.hfxo) << 16),
            0x414 => u32::from(self.lfclk_run),
            0x418 => self.lf_src as u32 | (running(self.lf) << 16),
            0x41C => self.lf_src as u32,
            0x438 => 0,
            0x510 => self.pofcon,
            0x518 => self.lfclksrc,
            0x51C => self.gpregret[0],
            0x520 => self.gpregret[1],
            0x538 => self.ctiv,
            0x550 => self.approtect_force,
            0x558 => self.approtect_disable,
            0x55C => self.traceconfig,
            0x578 => self.dcdcen,
            0x580 => self.dcdcen0,
            0x5B4 => self.lfrcmode,
            0x640 => u32::from(matches!(self.supply, Supply::Vddh { .. })),
            0xE00 => self.anomaly_198,
            o if (0x900..0x990).contains(&o) && o % 16 < 12 => {
                *self.ram_power.get(((o - 0x900) / 16) as usize)?
            }
            _ => return None,
        })
    }

    /// A register write; false for offsets the model does not implement.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        let now = ctx.now;
        match offset {
            0x000 if value & 1 != 0 => self.start_hfxo(now),
            0x004 if value & 1 != 0 => {
                self.hfclk_run = false;
                self.hfxo = Osc::Stopped;
            }
            0x008 if value & 1 != 0 => self.start_lfclk(now),
            0x00C if value & 1 != 0 => {
                self.lfclk_run = false;
                self.lf = Osc::Stopped;
                self.lf_timing = None;
            }
            0x000..=0x00C => {}
            // Constant latency / low power sub-modes: timing not modelled.
            0x078 | 0x07C => {}
            0x400 => self.resetreas &= !value,
            0x500 if value & 1 != 0 => ctx.records.note("POWER", "SYSTEMOFF entered", now),
            0x500 => {}
            0x510 => self.pofcon = value,
            0x518 => self.lfclksrc = value & 0x0003_0003,
            0x51C => self.gpregret[0] = value & 0xFF,
            0x520 => self.gpregret[1] = value & 0xFF,
            0x538 => self.ctiv = value & 0x7F,
            0x550 => self.approtect_force = value,
            0x558 => self.approtect_disable = value,
            0x55C => self.traceconfig = value,
            0x578 => self.dcdcen = value & 1,
            0x580 => self.dcdcen0 = value & 1,
            0x5B4 => self.lfrcmode = value & 1,
            0xE00 => self.anomaly_198 = value,
            o if (0x900..0x990).contains(&o) && o % 16 < 12 => {
                let Some(p) = self.ram_power.get_mut(((o - 0x900) / 16) as usize) else {
                    return false;
                };
                match o % 16 {
                    0 => *p = value,
                    4 => *p |= value,
                    _ => *p &= !value,
                }
            }
            _ => return false,
        }
        true
    }

    /// A reset. The oscillators stop and the registers return to their reset values except
    /// RESETREAS (cumulative until a power-on reset or software clears it) and GPREGRET
    /// (retained through every reset but power-on), as the PS "Reset behavior" table says.
    pub fn reset(&mut self, reason: u32, power_on: bool) {
        let mut fresh = Self::new(self.faults, self.supply, 0.0);
        fresh.lf_period_fs = self.lf_period_fs;
        if !power_on {
            fresh.resetreas = self.resetreas | reason;
            fresh.gpregret = self.gpregret;
        }
        *self = fresh;
    }
}
