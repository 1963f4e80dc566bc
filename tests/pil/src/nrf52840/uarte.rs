//! UARTE0/1 (PS "UARTE"): UART with EasyDMA, no flow control modelled. Bytes sent reach the
//! board at the end of their stop bit (`Outside::uart_sent`, uart = instance + 1); bytes the
//! board queues (`uart_receive`, their stop bit ending at the given time) are received while
//! the receiver runs.
//!
//! Transmit: STARTTX raises TXSTARTED and EasyDMA reads each byte as the previous one
//! leaves the shift register; ENDTX comes when the last byte has been read (the firmware's
//! JR-line code waits two byte times after it for that reason), TXDRDY after each byte.
//! STOPTX lets the byte in progress finish, then TXSTOPPED. Disabling the UARTE mid-byte
//! cuts that byte (noted, not delivered).
//!
//! Receive: STARTRX raises RXSTARTED and takes the RXD buffer (first draining the RX FIFO
//! into it); each byte raises RXDRDY and goes to the buffer, ENDRX when it is full
//! (shortcuts ENDRX→STARTRX/STOPRX). With no buffer, bytes wait in the 4-byte RX FIFO
//! (embassy-nrf's docs: "up to 4 bytes"); a fifth is an overrun (ERROR, ERRORSRC.OVERRUN).
//! STOPRX ends the buffer (ENDRX with AMOUNT so far) and raises RXTO at once (the silicon's
//! receiver time-out is not modelled). FLUSHRX moves the FIFO into the buffer (ENDRX).
//!
//! A byte the board queues with its own baud rate is sampled against the receiver's bit
//! times ([`resample`]): a few percent apart it arrives intact, further apart it arrives
//! changed and, when the stop bit is sampled low, with a framing error (ERRORSRC.FRAMING).
//!
//! Baud rate: the UARTE times a bit as a whole number of 16 MHz cycles,
//! floor(2^32 / BAUDRATE): that reproduces every "actual rate" in the PS's UARTE BAUDRATE
//! table (115 200 → 115 108 Bd = 16 MHz / 139, 921 600 → 941 176 Bd = 16 MHz / 17, 9600 →
//! 9598 Bd) and the 940 kBd measured with BAUDRATE 0x0EBEDFA4 (Nordic DevZone 69571).

use std::collections::VecDeque;

use super::events::{Ctx, EventRegs, after_ps};
use super::map::psel;
use super::memory::in_ram;
use crate::wire::Drive;

/// Event indices.
mod ev {
    pub const RXDRDY: u32 = 2;
    pub const ENDRX: u32 = 4;
    pub const TXDRDY: u32 = 7;
    pub const ENDTX: u32 = 8;
    pub const ERROR: u32 = 9;
    pub const RXTO: u32 = 17;
    pub const RXSTARTED: u32 = 19;
    pub const TXSTARTED: u32 = 20;
    pub const TXSTOPPED: u32 = 22;
}
/// SHORTS bits.
const ENDRX_STARTRX: u32 = 5;
const ENDRX_STOPRX: u32 = 6;
/// ENABLE value selecting the UARTE.
const ENABLE_UARTE: u32 = 8;
/// RX FIFO depth.
const FIFO: usize = 4;
/// ERRORSRC.OVERRUN.
const OVERRUN: u32 = 1;
/// ERRORSRC.FRAMING.
const FRAMING: u32 = 1 << 2;

/// PSEL slots (RTS, TXD, CTS, RXD).
const TXD: usize = 1;

/// The duration of one bit for a BAUDRATE value, ps (`None` for 0).
pub const fn bit_ps(baudrate: u32) -> Option<u64> {
    if baudrate == 0 {
        return None;
    }
    let cycles = (1u64 << 32) / baudrate as u64;
    Some(cycles * 62_500)
}

#[derive(Clone, Copy, Debug, Default)]
struct Dma {
    ptr: u32,
    maxcnt: u32,
    amount: u32,
}

#[derive(Clone, Copy, Debug)]
struct Tx {
    start_ns: u64,
    frame_ps: u64,
    buf: Dma,
    /// Bytes fully sent.
    sent: u32,
    /// The byte in the shift register.
    shifting: u8,
    stop: bool,
}

/// One UARTE instance.
pub struct Uarte {
    name: &'static str,
    tx_channel: &'static str,
    rx_channel: &'static str,
    uart: u8,
    ev: EventRegs,
    enable: u32,
    psel: [u32; 4],
    baudrate: u32,
    config: u32,
    errorsrc: u32,
    rxd: Dma,
    txd: Dma,
    rx_running: bool,
    rx_buf: Option<Dma>,
    fifo: VecDeque<u8>,
    tx: Option<Tx>,
    queue: VecDeque<(u64, u8, Option<f64>)>,
}

/// What a receiver with bits of `rx_ps` makes of `byte` sent 8N1 at `tx_baud`: it samples
/// each bit in the middle of its own bit time against the sender's waveform (idle after
/// the stop bit); the stop bit sampled low is a framing error.
pub fn resample(byte: u8, tx_baud: f64, rx_ps: u64) -> (u8, bool) {
    let tx_ps = 1e12 / tx_baud;
    let level = |t_ps: f64| match (t_ps / tx_ps).floor() as i64 {
        0 => false,
        k @ 1..=8 => byte & (1 << (k - 1)) != 0,
        _ => true,
    };
    let at = |bit: u32| level((f64::from(bit) + 0.5) * rx_ps as f64);
    let value = (1..=8).fold(0u8, |v, k| v | (u8::from(at(k)) << (k - 1)));
    (value, at(9))
}

impl Uarte {
    /// Instance `n` (0 or 1) at `base`.
    pub const fn new(n: u8, base: u32) -> Self {
        let (name, tx_channel, rx_channel) = match n {
            0 => ("UARTE0", "UARTE0 TXD", "UARTE0 RXD"),
            _ => ("UARTE1", "UARTE1 TXD", "UARTE1 RXD"),
        };
        Self {
            name,
            tx_channel,
            rx_channel,
            uart: n + 1,
            ev: EventRegs::new(base),
            enable: 0,
            psel: [psel::DISCONNECTED; 4],
            baudrate: 0x0400_0000,
            config: 0,
            errorsrc: 0,
            rxd: Dma {
                ptr: 0,
                maxcnt: 0,
                amount: 0,
            },
            txd: Dma {
                ptr: 0,
                maxcnt: 0,
                amount: 0,
            },
            rx_running: false,
            rx_buf: None,
            fifo: VecDeque::new(),
            tx: None,
            queue: VecDeque::new(),
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    const fn enabled(&self) -> bool {
        self.enable == ENABLE_UARTE
    }

    /// The BAUDRATE register.
    pub const fn baudrate(&self) -> u32 {
        self.baudrate
    }

    /// The baud rate the receiver listens at, when it runs.
    pub fn rx_baud(&self) -> Option<f64> {
        if !self.enabled() || !self.rx_running {
            return None;
        }
        bit_ps(self.baudrate).map(|ps| 1e12 / ps as f64)
    }

    fn frame_bits(&self) -> u64 {
        let parity = u64::from((self.config >> 1) & 7 == 7);
        let stop = 1 + u64::from(self.config & 0x10 != 0);
        1 + 8 + parity + stop
    }

    /// The board queues a byte whose stop bit ends at `at_ns`, sent at `baud` (`None`:
    /// at the receiver's own rate).
    pub fn receive(&mut self, byte: u8, baud: Option<f64>, at_ns: u64) {
        let at = self.queue.partition_point(|&(t, ..)| t <= at_ns);
        self.queue.insert(at, (at_ns, byte, baud));
    }

    fn tx_next_ns(&self) -> u64 {
        self.tx.map_or(u64::MAX, |t| {
            after_ps(t.start_ns, u64::from(t.sent) + 1, t.frame_ps)
        })
    }

    /// The next byte boundary (sent or received).
    pub fn next_event_ns(&self) -> u64 {
        let rx = self.queue.front().map_or(u64::MAX, |&(t, ..)| t);
        rx.min(self.tx_next_ns())
    }

    fn read_tx_byte(&self, buf: Dma, k: u32, ctx: &mut Ctx<'_>, at: u64) -> u8 {
        let mut byte = [0];
        ctx.ram
            .dma_read(self.tx_channel, buf.ptr.wrapping_add(k), &mut byte, at);
        byte[0]
    }

    fn start_tx(&mut self, ctx: &mut Ctx<'_>) {
        if !self.enabled() {
            ctx.records
                .note(self.name, "STARTTX while not enabled", ctx.now);
            return;
        }
        self.ev.raise(ev::TXSTARTED, ctx.fired);
        let buf = self.txd;
        self.txd.amount = 0;
        if buf.maxcnt == 0 {
            self.ev.raise(ev::ENDTX, ctx.fired);
            return;
        }
        if !in_ram(buf.ptr, buf.maxcnt) {
            ctx.records
                .dma_fault(self.tx_channel, buf.ptr, buf.maxcnt, ctx.now);
        }
        let Some(bit) = bit_ps(self.baudrate) else {
            ctx.records
                .note(self.name, "STARTTX with BAUDRATE 0", ctx.now);
            return;
        };
        let shifting = self.read_tx_byte(buf, 0, ctx, ctx.now);
        if buf.maxcnt == 1 {
            self.txd.amount = 1;
            self.ev.raise(ev::ENDTX, ctx.fired);
        }
        self.tx = Some(Tx {
            start_ns: ctx.now,
            frame_ps: self.frame_bits() * bit,
            buf,
            sent: 0,
            shifting,
            stop: false,
        });
    }

    fn tx_step(&mut self, ctx: &mut Ctx<'_>) {
        while let Some(mut t) = self.tx {
            let at = after_ps(t.start_ns, u64::from(t.sent) + 1, t.frame_ps);
            if at > ctx.now {
                break;
            }
            ctx.outside.uart_sent(self.uart, t.shifting, at);
            self.ev.raise(ev::TXDRDY, ctx.fired);
            t.sent += 1;
            let more = t.sent < t.buf.maxcnt;
            if more && !t.stop {
                t.shifting = self.read_tx_byte(t.buf, t.sent, ctx, at);
                if t.sent + 1 == t.buf.maxcnt {
                    self.txd.amount = t.buf.maxcnt;
                    self.ev.raise(ev::ENDTX, ctx.fired);
                }
                self.tx = Some(t);
            } else {
                self.tx = None;
                if t.stop {
                    if more {
                        self.txd.amount = t.sent;
                        self.ev.raise(ev::ENDTX, ctx.fired);
                    }
                    self.ev.raise(ev::TXSTOPPED, ctx.fired);
                }
            }
        }
    }

    fn start_rx(&mut self, ctx: &mut Ctx<'_>) {
        if !self.enabled() {
            ctx.records
                .note(self.name, "STARTRX while not enabled", ctx.now);
            return;
        }
        self.rx_running = true;
        let mut buf = self.rxd;
        buf.amount = 0;
        if buf.maxcnt > 0 && !in_ram(buf.ptr, buf.maxcnt) {
            ctx.records
                .dma_fault(self.rx_channel, buf.ptr, buf.maxcnt, ctx.now);
        }
        self.rx_buf = Some(buf);
        self.rxd.amount = 0;
        self.ev.raise(ev::RXSTARTED, ctx.fired);
        while self.rx_buf.is_some() {
            let Some(byte) = self.fifo.pop_front() else {
                break;
            };
            self.store(byte, ctx);
        }
    }

    /// Puts a received byte into the buffer or the FIFO.
    fn store(&mut self, byte: u8, ctx: &mut Ctx<'_>) {
        let Some(mut buf) = self.rx_buf else {
            if self.fifo.len() < FIFO {
                self.fifo.push_back(byte);
            } else {
                self.errorsrc |= OVERRUN;
                self.ev.raise(ev::ERROR, ctx.fired);
            }
            return;
        };
        if buf.amount < buf.maxcnt {
            ctx.ram.dma_write(
                self.rx_channel,
                buf.ptr.wrapping_add(buf.amount),
                &[byte],
                ctx.now,
            );
            buf.amount += 1;
        }
        self.rxd.amount = buf.amount;
        self.rx_buf = Some(buf);
        if buf.amount >= buf.maxcnt {
            self.end_rx(ctx);
        }
    }

    fn end_rx(&mut self, ctx: &mut Ctx<'_>) {
        self.rx_buf = None;
        self.ev.raise(ev::ENDRX, ctx.fired);
        if self.ev.short(ENDRX_STARTRX) {
            self.start_rx(ctx);
        }
        if self.ev.short(ENDRX_STOPRX) {
            self.stop_rx(ctx);
        }
    }

    fn stop_rx(&mut self, ctx: &mut Ctx<'_>) {
        if self.rx_buf.take().is_some() {
            self.ev.raise(ev::ENDRX, ctx.fired);
        }
        self.rx_running = false;
        self.ev.raise(ev::RXTO, ctx.fired);
    }

    /// Sends and receives the bytes due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        self.tx_step(ctx);
        while let Some(&(t, byte, baud)) = self.queue.front() {
            if t > ctx.now {
                break;
            }
            self.queue.pop_front();
            if !self.enabled() || !self.rx_running {
                continue;
            }
            let (byte, framed) = match (baud, bit_ps(self.baudrate)) {
                (Some(baud), Some(rx_ps)) => resample(byte, baud, rx_ps),
                _ => (byte, true),
            };
            self.ev.raise(ev::RXDRDY, ctx.fired);
            if !framed {
                self.errorsrc |= FRAMING;
                self.ev.raise(ev::ERROR, ctx.fired);
            }
            self.store(byte, ctx);
        }
    }

    fn pins(&self, ctx: &mut Ctx<'_>, on: bool) {
        let Some(pin) = self.psel.get(TXD).and_then(|&p| psel::pin(p)) else {
            return;
        };
        if on {
            ctx.pins
                .claim(pin, self.name, Drive::High, ctx.outside, ctx.now);
        } else {
            ctx.pins.release(pin, self.name, ctx.outside, ctx.now);
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x480 => self.errorsrc,
            0x500 => self.enable,
            0x508..0x518 => *self.psel.get(((offset - 0x508) / 4) as usize)?,
            0x524 => self.baudrate,
            0x534 => self.rxd.ptr,
            0x538 => self.rxd.maxcnt,
            0x53C => self.rxd.amount,
            0x544 => self.txd.ptr,
            0x548 => self.txd.maxcnt,
            0x54C => self.txd.amount,
            0x56C => self.config,
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
            0x000 if task => self.start_rx(ctx),
            0x004 if task => self.stop_rx(ctx),
            0x008 if task => self.start_tx(ctx),
            0x00C if task => match self.tx.as_mut() {
                Some(t) => t.stop = true,
                None => self.ev.raise(ev::TXSTOPPED, ctx.fired),
            },
            0x02C if task => {
                let mut buf = self.rxd;
                buf.amount = 0;
                self.rx_buf = Some(buf);
                while let Some(byte) = self.fifo.pop_front() {
                    self.store(byte, ctx);
                }
                if self.rx_buf.is_some() {
                    self.end_rx(ctx);
                }
            }
            0x000..=0x00C | 0x02C => {}
            0x480 => self.errorsrc &= !value,
            0x500 => {
                let was = self.enabled();
                self.enable = value & 0xF;
                if self.enable != 0 && !self.enabled() {
                    ctx.records
                        .note(self.name, "enabled as legacy UART (not modelled)", ctx.now);
                }
                if was && !self.enabled() {
                    if self.tx.take().is_some() {
                        ctx.records
                            .note(self.name, "disabled mid-byte: the byte is cut", ctx.now);
                    }
                    self.rx_running = false;
                    self.rx_buf = None;
                    self.pins(ctx, false);
                } else if !was && self.enabled() {
                    self.pins(ctx, true);
                }
            }
            0x508..0x518 => {
                let enabled = self.enabled();
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
            0x524 => self.baudrate = value,
            0x534 => self.rxd.ptr = value,
            0x538 => self.rxd.maxcnt = value & 0xFFFF,
            0x544 => self.txd.ptr = value,
            0x548 => self.txd.maxcnt = value & 0xFFFF,
            0x56C => {
                if value & 1 != 0 {
                    ctx.records
                        .note(self.name, "hardware flow control (not modelled)", ctx.now);
                }
                self.config = value & 0x11F;
            }
            _ => return false,
        }
        true
    }

    /// Reset: disabled, pins back to GPIO, nothing in flight. The board's queue stays.
    pub fn reset(&mut self, ctx: &mut Ctx<'_>) {
        if self.enabled() {
            self.pins(ctx, false);
        }
        let queue = core::mem::take(&mut self.queue);
        *self = Self::new(self.uart - 1, self.ev.base());
        self.queue = queue;
    }
}
