//! SPIM0–3 (PS "SPIM"): SPI controller with EasyDMA. START latches TXD/RXD PTR and MAXCNT
//! (double-buffered) and raises STARTED; the transfer runs max(TXD.MAXCNT, RXD.MAXCNT)
//! bytes at FREQUENCY (8 clocks a byte, no gap), sending ORC past the TX buffer and dropping
//! bytes past the RX buffer; each byte goes to the board (`Outside::spi_byte`, bus =
//! instance + 1) when its last clock ends; ENDTX/ENDRX when a buffer is done, END when the
//! transfer is. EasyDMA reaches Data RAM only: another pointer is recorded as a DMA fault
//! and transfers zeros. SPIM3 carries anomaly 198 (see `memory`).

use super::events::{Ctx, EventRegs, after_ps};
use super::map::psel;
use super::memory::in_ram;
use crate::wire::Drive;

/// Event indices.
mod ev {
    pub const STOPPED: u32 = 1;
    pub const ENDRX: u32 = 4;
    pub const END: u32 = 6;
    pub const ENDTX: u32 = 8;
    pub const STARTED: u32 = 19;
}
/// SHORTS bit END → START.
const END_START: u32 = 17;
/// ENABLE value selecting the SPIM (other values select SPI/SPIS/TWIM/TWIS).
const ENABLE_SPIM: u32 = 7;

/// Bit period in ps for a FREQUENCY value (PS "SPIM": FREQUENCY; 16 and 32 Mbps on SPIM3).
const fn bit_ps(frequency: u32) -> Option<u64> {
    let hz: u64 = match frequency {
        0x0200_0000 => 125_000,
        0x0400_0000 => 250_000,
        0x0800_0000 => 500_000,
        0x1000_0000 => 1_000_000,
        0x2000_0000 => 2_000_000,
        0x4000_0000 => 4_000_000,
        0x8000_0000 => 8_000_000,
        0x0A00_0000 => 16_000_000,
        0x1400_0000 => 32_000_000,
        _ => return None,
    };
    Some(1_000_000_000_000 / hz)
}

#[derive(Clone, Copy, Debug, Default)]
struct Dma {
    ptr: u32,
    maxcnt: u32,
    amount: u32,
}

#[derive(Clone, Copy, Debug)]
struct Xfer {
    start_ns: u64,
    byte_ps: u64,
    total: u32,
    done: u32,
    tx: Dma,
    rx: Dma,
}

/// One SPIM instance.
pub struct Spim {
    name: &'static str,
    tx_channel: &'static str,
    rx_channel: &'static str,
    bus: u8,
    corrupt_198: bool,
    ev: EventRegs,
    enable: u32,
    psel: [u32; 4],
    frequency: u32,
    config: u32,
    orc: u32,
    other: [u32; 5],
    rx: Dma,
    tx: Dma,
    xfer: Option<Xfer>,
}

/// PSEL slots.
const SCK: usize = 0;
const MOSI: usize = 1;
const MISO: usize = 2;
const CSN: usize = 3;

impl Spim {
    /// Instance `n` (0–3) at `base`; `corrupt_198` applies anomaly 198's corruption on
    /// SPIM3.
    pub const fn new(n: u8, base: u32, corrupt_198: bool) -> Self {
        let (name, tx_channel, rx_channel) = match n {
            0 => ("SPIM0", "SPIM0 TXD", "SPIM0 RXD"),
            1 => ("SPIM1", "SPIM1 TXD", "SPIM1 RXD"),
            2 => ("SPIM2", "SPIM2 TXD", "SPIM2 RXD"),
            _ => ("SPIM3", "SPIM3 TXD", "SPIM3 RXD"),
        };
        Self {
            name,
            tx_channel,
            rx_channel,
            bus: n + 1,
            corrupt_198,
            ev: EventRegs::new(base),
            enable: 0,
            psel: [psel::DISCONNECTED; 4],
            frequency: 0x0400_0000,
            config: 0,
            orc: 0,
            other: [0; 5],
            rx: Dma {
                ptr: 0,
                maxcnt: 0,
                amount: 0,
            },
            tx: Dma {
                ptr: 0,
                maxcnt: 0,
                amount: 0,
            },
            xfer: None,
        }
    }

    const fn is_spim3(&self) -> bool {
        self.bus == 4
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    /// When the byte in progress completes.
    pub fn next_event_ns(&self) -> u64 {
        self.xfer.map_or(u64::MAX, |x| {
            after_ps(x.start_ns, u64::from(x.done) + 1, x.byte_ps)
        })
    }

    fn pins(&self, ctx: &mut Ctx<'_>, on: bool) {
        let idle = if self.config & 4 != 0 {
            Drive::High
        } else {
            Drive::Low
        };
        for (slot, drive) in [(SCK, idle), (MOSI, Drive::Low), (CSN, Drive::High)] {
            let Some(pin) = self.psel.get(slot).and_then(|&p| psel::pin(p)) else {
                continue;
            };
            if on {
                ctx.pins.claim(pin, self.name, drive, ctx.outside, ctx.now);
            } else {
                ctx.pins.release(pin, self.name, ctx.outside, ctx.now);
            }
        }
    }

    fn csn(&self, ctx: &mut Ctx<'_>, active: bool) {
        if let Some(pin) = self.psel.get(CSN).and_then(|&p| psel::pin(p)) {
            let high = active == (self.other.get(2).copied().unwrap_or(0) & 1 != 0);
            let drive = if high { Drive::High } else { Drive::Low };
            ctx.pins.claim(pin, self.name, drive, ctx.outside, ctx.now);
        }
    }

    fn start(&mut self, ctx: &mut Ctx<'_>) {
        if self.enable != ENABLE_SPIM {
            ctx.records
                .note(self.name, "START while not enabled as SPIM", ctx.now);
            return;
        }
        let Some(bit) = bit_ps(self.frequency) else {
            ctx.records
                .note(self.name, "FREQUENCY value not in the PS table", ctx.now);
            return;
        };
        self.ev.raise(ev::STARTED, ctx.fired);
        for (dma, channel) in [(self.tx, self.tx_channel), (self.rx, self.rx_channel)] {
            if dma.maxcnt > 0 && !in_ram(dma.ptr, dma.maxcnt) {
                ctx.records.dma_fault(channel, dma.ptr, dma.maxcnt, ctx.now);
            }
        }
        self.tx.amount = 0;
        self.rx.amount = 0;
        let x = Xfer {
            start_ns: ctx.now,
            byte_ps: 8 * bit,
            total: self.tx.maxcnt.max(self.rx.maxcnt),
            done: 0,
            tx: self.tx,
            rx: self.rx,
        };
        if self.is_spim3() && x.tx.maxcnt > 0 {
            ctx.ram.watch_spim3(x.tx.ptr, x.tx.maxcnt);
        }
        self.xfer = Some(x);
        self.csn(ctx, true);
        if x.total == 0 {
            self.finish(ctx);
        }
    }

    fn finish(&mut self, ctx: &mut Ctx<'_>) {
        if let Some(x) = self.xfer.take() {
            if x.tx.maxcnt == 0 {
                self.ev.raise(ev::ENDTX, ctx.fired);
            }
            if x.rx.maxcnt == 0 {
                self.ev.raise(ev::ENDRX, ctx.fired);
            }
        }
        if self.is_spim3() {
            ctx.ram.unwatch_spim3();
        }
        self.csn(ctx, false);
        self.ev.raise(ev::END, ctx.fired);
        if self.ev.short(END_START) {
            self.start(ctx);
        }
    }

    /// Completes the bytes due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        while let Some(mut x) = self.xfer {
            let at = after_ps(x.start_ns, u64::from(x.done) + 1, x.byte_ps);
            if at > ctx.now {
                break;
            }
            let k = x.done;
            let mut mosi = [self.orc as u8];
            if k < x.tx.maxcnt {
                ctx.ram
                    .dma_read(self.tx_channel, x.tx.ptr.wrapping_add(k), &mut mosi, at);
            }
            if self.is_spim3() && ctx.ram.take_spim3_hit() && self.corrupt_198 {
                mosi = [0];
                ctx.ram.anomaly.corrupted_bytes += 1;
            }
            let clocked = self.psel.get(SCK).is_some_and(|&p| psel::pin(p).is_some());
            let miso = if clocked {
                ctx.outside.spi_byte(self.bus, mosi[0], at)
            } else {
                0
            };
            let miso = if self.psel.get(MISO).is_some_and(|&p| psel::pin(p).is_some()) {
                miso
            } else {
                0
            };
            if k < x.rx.maxcnt {
                ctx.ram
                    .dma_write(self.rx_channel, x.rx.ptr.wrapping_add(k), &[miso], at);
            }
            x.done += 1;
            self.tx.amount = x.done.min(x.tx.maxcnt);
            self.rx.amount = x.done.min(x.rx.maxcnt);
            self.xfer = Some(x);
            if x.done == x.tx.maxcnt {
                self.ev.raise(ev::ENDTX, ctx.fired);
            }
            if x.done == x.rx.maxcnt {
                self.ev.raise(ev::ENDRX, ctx.fired);
            }
            if x.done >= x.total {
                let now = ctx.now;
                ctx.now = at;
                self.finish(ctx);
                ctx.now = now;
            }
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x400 => 0,
            0x500 => self.enable,
            0x508..0x518 => *self.psel.get(((offset - 0x508) / 4) as usize)?,
            0x524 => self.frequency,
            0x534 => self.rx.ptr,
            0x538 => self.rx.maxcnt,
            0x53C => self.rx.amount,
            0x544 => self.tx.ptr,
            0x548 => self.tx.maxcnt,
            0x54C => self.tx.amount,
            0x554 => self.config,
            0x560..0x574 if self.is_spim3() => *self.other.get(((offset - 0x560) / 4) as usize)?,
            0x5C0 => self.orc,
            _ => return None,
        })
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        let task = value & 1 != 0;
        match offset {
            0x010 if task => self.start(ctx),
            0x014 if task => {
                if self.xfer.take().is_some() && self.is_spim3() {
                    ctx.ram.unwatch_spim3();
                }
                self.ev.raise(ev::STOPPED, ctx.fired);
            }
            0x010 | 0x014 => {}
            0x500 => {
                let was = self.enable == ENABLE_SPIM;
                self.enable = value & 0xF;
                let is = self.enable == ENABLE_SPIM;
                if self.enable != 0 && !is {
                    ctx.records
                        .note(self.name, "enabled as SPI/SPIS/TWI (not modelled)", ctx.now);
                }
                if was != is {
                    if !is {
                        self.xfer = None;
                        if self.is_spim3() {
                            ctx.ram.unwatch_spim3();
                        }
                    }
                    self.pins(ctx, is);
                }
            }
            0x508..0x518 => {
                let enabled = self.enable == ENABLE_SPIM;
                if enabled {
                    self.pins(ctx, false);
                }
                if let Some(p) = self.psel.get_mut(((offset - 0x508) / 4) as usize) {
                    *p = value;
                }
                if enabled {
                    self.pins(ctx, true);
                }
            }
            0x524 => self.frequency = value,
            0x534 => self.rx.ptr = value,
            0x538 => self.rx.maxcnt = value & 0xFFFF,
            0x544 => self.tx.ptr = value,
            0x548 => self.tx.maxcnt = value & 0xFFFF,
            0x540 | 0x550 if value == 0 => {}
            0x554 => self.config = value & 7,
            0x560..0x574 if self.is_spim3() => {
                if let Some(o) = self.other.get_mut(((offset - 0x560) / 4) as usize) {
                    *o = value;
                }
            }
            0x5C0 => self.orc = value & 0xFF,
            _ => return false,
        }
        true
    }

    /// Reset: disabled, pins back to GPIO.
    pub fn reset(&mut self, ctx: &mut Ctx<'_>) {
        if self.enable == ENABLE_SPIM {
            self.pins(ctx, false);
        }
        if self.is_spim3() {
            ctx.ram.unwatch_spim3();
        }
        *self = Self::new(self.bus - 1, self.ev.base(), self.corrupt_198);
    }
}
