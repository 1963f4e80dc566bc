//! SAADC (PS "SAADC"): one-shot sampling of up to eight channels with gain, reference,
//! acquisition time and resolution, results to RAM by EasyDMA, offset calibration. The
//! voltage is the board's (`Outside::analog_volts`) at the end of the acquisition window.
//!
//! RESULT = V · GAIN / REFERENCE · 2^RESOLUTION (single-ended, PS "SAADC": digital output),
//! truncated and clamped to the 16-bit signed range the PS gives for the resolution.
//! A conversion takes tACQ + tCONV, tCONV = 2 µs (PS: "< 2 µs"). The PS gives no duration
//! for offset calibration; the model completes it after one 40 µs conversion. Oversampling,
//! burst, scan with SAMPLERATE, limits and differential mode are not modelled (noted).

use super::events::{Ctx, EventRegs};
use super::memory::in_ram;
use crate::wire::Pin;

/// Event indices.
mod ev {
    pub const STARTED: u32 = 0;
    pub const END: u32 = 1;
    pub const DONE: u32 = 2;
    pub const RESULTDONE: u32 = 3;
    pub const CALIBRATEDONE: u32 = 4;
    pub const STOPPED: u32 = 5;
}
/// Conversion time, ns.
const TCONV_NS: u64 = 2_000;
/// Calibration time, ns (one conversion at the longest acquisition time).
const CALIBRATION_NS: u64 = 42_000;
/// Acquisition times for CONFIG.TACQ 0–5, µs.
const TACQ_US: [u64; 6] = [3, 5, 10, 15, 20, 40];
/// Gains for CONFIG.GAIN 0–7.
const GAIN: [f32; 8] = [1.0 / 6.0, 0.2, 0.25, 1.0 / 3.0, 0.5, 1.0, 2.0, 4.0];
/// The internal reference, V.
const VREF: f32 = 0.6;
/// PSELP values: AIN0–7 are 1–8 on these pins; 9 is VDD, 0x0D is VDDH/5.
const AIN_PINS: [(u8, u8); 8] = [
    (0, 2),
    (0, 3),
    (0, 4),
    (0, 5),
    (0, 28),
    (0, 29),
    (0, 30),
    (0, 31),
];

#[derive(Clone, Copy, Debug, Default)]
struct Channel {
    pselp: u32,
    pseln: u32,
    config: u32,
    limit: u32,
}

#[derive(Clone, Copy, Debug)]
enum Busy {
    Idle,
    /// Converting channel `ch`, done at `at`.
    Sampling {
        ch: usize,
        at: u64,
    },
    Calibrating {
        at: u64,
    },
}

/// The SAADC.
pub struct Saadc {
    ev: EventRegs,
    enable: u32,
    ch: [Channel; 8],
    resolution: u32,
    oversample: u32,
    samplerate: u32,
    ptr: u32,
    maxcnt: u32,
    amount: u32,
    started: bool,
    busy: Busy,
    /// VDD (the GPIO supply) and VDDH, V, for the internal inputs and VDD/4 reference.
    pub supplies: (f32, f32),
}

impl Saadc {
    /// Reset state.
    pub const fn new() -> Self {
        Self {
            ev: EventRegs::new(super::map::base::SAADC),
            enable: 0,
            ch: [Channel {
                pselp: 0,
                pseln: 0,
                config: 0x0002_0000,
                limit: 0x7FFF_8000,
            }; 8],
            resolution: 1,
            oversample: 0,
            samplerate: 0,
            ptr: 0,
            maxcnt: 0,
            amount: 0,
            started: false,
            busy: Busy::Idle,
            supplies: (3.3, 5.0),
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    /// When the conversion or calibration in progress ends.
    pub const fn next_event_ns(&self) -> u64 {
        match self.busy {
            Busy::Idle => u64::MAX,
            Busy::Sampling { at, .. } | Busy::Calibrating { at } => at,
        }
    }

    fn next_channel(&self, from: usize) -> Option<usize> {
        (from..8).find(|&i| self.ch.get(i).is_some_and(|c| c.pselp != 0))
    }

    fn conversion_ns(&self, ch: usize) -> u64 {
        let tacq = self.ch.get(ch).map_or(0, |c| (c.config >> 16) & 7);
        TACQ_US.get(tacq as usize).copied().unwrap_or(40) * 1000 + TCONV_NS
    }

    fn convert(&mut self, ch: usize, from: u64) {
        self.busy = Busy::Sampling {
            ch,
            at: from + self.conversion_ns(ch),
        };
    }

    fn volts(&self, pselp: u32, ctx: &mut Ctx<'_>, at: u64) -> f32 {
        match pselp {
            1..=8 => match AIN_PINS.get(pselp as usize - 1) {
                Some(&(port, pin)) => ctx.outside.analog_volts(Pin::new(port, pin), at),
                None => 0.0,
            },
            9 => self.supplies.0,
            0x0D => self.supplies.1 / 5.0,
            _ => 0.0,
        }
    }

    fn result(&self, c: Channel, volts: f32) -> i16 {
        let gain = GAIN
            .get(((c.config >> 8) & 7) as usize)
            .copied()
            .unwrap_or(1.0);
        let reference = if c.config & (1 << 12) != 0 {
            self.supplies.0 / 4.0
        } else {
            VREF
        };
        let bits = 8 + 2 * (self.resolution & 3);
        let full = (1u32 << bits) as f32;
        let raw = (volts * gain / reference * full).trunc();
        raw.clamp(-full, full - 1.0) as i16
    }

    /// Completes the conversion or calibration due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        match self.busy {
            Busy::Calibrating { at } if at <= ctx.now => {
                self.busy = Busy::Idle;
                self.ev.raise(ev::CALIBRATEDONE, ctx.fired);
            }
            Busy::Sampling { ch, at } if at <= ctx.now => {
                let Some(c) = self.ch.get(ch).copied() else {
                    self.busy = Busy::Idle;
                    return;
                };
                let v = self.volts(c.pselp, ctx, at - TCONV_NS);
                let value = self.result(c, v);
                self.ev.raise(ev::DONE, ctx.fired);
                if self.started && self.amount < self.maxcnt {
                    let addr = self.ptr.wrapping_add(2 * self.amount);
                    if !in_ram(addr, 2) {
                        ctx.records.dma_fault("SAADC RESULT", addr, 2, at);
                    }
                    ctx.ram
                        .dma_write("SAADC RESULT", addr, &value.to_le_bytes(), at);
                    self.amount += 1;
                    self.ev.raise(ev::RESULTDONE, ctx.fired);
                }
                match self.next_channel(ch + 1) {
                    Some(next) => self.convert(next, at),
                    None => self.busy = Busy::Idle,
                }
                if matches!(self.busy, Busy::Idle) && self.started && self.amount >= self.maxcnt {
                    self.started = false;
                    self.ev.raise(ev::END, ctx.fired);
                }
            }
            _ => {}
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x400 => u32::from(!matches!(self.busy, Busy::Idle)),
            0x500 => self.enable,
            0x510..0x590 => {
                let c = self.ch.get(((offset - 0x510) / 16) as usize)?;
                match offset % 16 {
                    0 => c.pselp,
                    4 => c.pseln,
                    8 => c.config,
                    _ => c.limit,
                }
            }
            0x5F0 => self.resolution,
            0x5F4 => self.oversample,
            0x5F8 => self.samplerate,
            0x62C => self.ptr,
            0x630 => self.maxcnt,
            0x634 => self.amount,
            _ => return None,
        })
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        let task = value & 1 != 0;
        let now = ctx.now;
        match offset {
            0x000 if task => {
                self.started = true;
                self.amount = 0;
                self.ev.raise(ev::STARTED, ctx.fired);
            }
            0x004 if task => {
                if self.enable == 0 {
                    ctx.records.note("SAADC", "SAMPLE while disabled", now);
                } else if matches!(self.busy, Busy::Idle) {
                    match self.next_channel(0) {
                        Some(ch) => self.convert(ch, now),
                        None => ctx.records.note("SAADC", "SAMPLE with no channel", now),
                    }
                }
            }
            0x008 if task => {
                self.busy = Busy::Idle;
                self.started = false;
                self.ev.raise(ev::STOPPED, ctx.fired);
            }
            0x00C if task => {
                self.busy = Busy::Calibrating {
                    at: now + CALIBRATION_NS,
                }
            }
            0x000..=0x00C => {}
            0x500 => self.enable = value & 1,
            0x510..0x590 => {
                let Some(c) = self.ch.get_mut(((offset - 0x510) / 16) as usize) else {
                    return false;
                };
                match offset % 16 {
                    0 => c.pselp = value & 0x1F,
                    4 => c.pseln = value & 0x1F,
                    8 => c.config = value,
                    _ => c.limit = value,
                }
                if offset % 16 == 8 && value & ((1 << 20) | (1 << 24)) != 0 {
                    ctx.records
                        .note("SAADC", "differential or burst mode (not modelled)", now);
                }
            }
            0x5F0 => self.resolution = value & 7,
            0x5F4 => {
                if value != 0 {
                    ctx.records
                        .note("SAADC", "oversampling (not modelled)", now);
                }
                self.oversample = value & 0xF;
            }
            0x5F8 => {
                if value & (1 << 12) != 0 {
                    ctx.records
                        .note("SAADC", "SAMPLERATE timer mode (not modelled)", now);
                }
                self.samplerate = value;
            }
            0x62C => self.ptr = value,
            0x630 => self.maxcnt = value & 0x7FFF,
            _ => return false,
        }
        true
    }

    /// Reset state (the supplies are the board's, kept).
    pub fn reset(&mut self) {
        let supplies = self.supplies;
        *self = Self::new();
        self.supplies = supplies;
    }
}
