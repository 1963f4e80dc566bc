//! PWM0 (PS "PWM"): up counter at 16 MHz / 2^PRESCALER, sequences of duty values read from
//! RAM by EasyDMA (DECODER.LOAD common, grouped, individual or waveform — the last with
//! COUNTERTOP per step), REFRESH repeats, ENDDELAY, LOOP and the shortcuts, with every
//! output edge at its exact time on the board (`pin_driven`).
//!
//! Each value's bit 15 is its polarity: set (FallingEdge), the output starts the period high
//! and falls when the counter reaches COMPARE; clear (RisingEdge), it starts low and rises.
//! COMPARE 0 flips it at the start of the period (the whole period at the second level);
//! COMPARE ≥ COUNTERTOP never flips it. After a sequence with no loop to follow, the last
//! values keep playing (the PS: "the last value is repeated"). The PWM holds its pins while
//! it plays; STOP (at the end of the current period) or disabling hands them back to GPIO,
//! whose OUT then gives the idle level. Not modelled (noted if used): up-and-down counting,
//! NextStep decoding.

use super::events::{Ctx, EventRegs, after_ps};
use super::map::psel;
use super::memory::in_ram;
use crate::wire::Drive;

/// Event indices.
mod ev {
    pub const STOPPED: u32 = 1;
    pub const SEQSTARTED0: u32 = 2;
    pub const SEQEND0: u32 = 4;
    pub const PWMPERIODEND: u32 = 6;
    pub const LOOPSDONE: u32 = 7;
}
/// SHORTS bits.
mod short {
    pub const SEQEND0_STOP: u32 = 0;
    pub const LOOPSDONE_SEQSTART0: u32 = 2;
    pub const LOOPSDONE_STOP: u32 = 4;
}

#[derive(Clone, Copy, Debug, Default)]
struct Seq {
    ptr: u32,
    cnt: u32,
    refresh: u32,
    enddelay: u32,
}

#[derive(Clone, Copy, Debug)]
struct Play {
    seq: usize,
    /// The next step (value set) to load.
    step: u32,
    /// Periods the current values still play (REFRESH repeats, then ENDDELAY).
    left: u32,
    in_enddelay: bool,
    /// The sequence ended with nothing to follow: the values repeat.
    holding: bool,
    period_start: u64,
    compare: [u16; 4],
    top: u16,
    /// Channels whose flip this period is still to come.
    flip_pending: [bool; 4],
    stop: bool,
}

/// The PWM instance.
pub struct Pwm {
    name: &'static str,
    channel: &'static str,
    ev: EventRegs,
    enable: u32,
    mode: u32,
    countertop: u32,
    prescaler: u32,
    decoder: u32,
    loop_cnt: u32,
    loops_left: u32,
    seq: [Seq; 2],
    psel: [u32; 4],
    play: Option<Play>,
}

impl Pwm {
    /// PWM0.
    pub const fn new() -> Self {
        Self {
            name: "PWM0",
            channel: "PWM0 SEQ",
            ev: EventRegs::new(super::map::base::PWM0),
            enable: 0,
            mode: 0,
            countertop: 0x3FF,
            prescaler: 0,
            decoder: 0,
            loop_cnt: 0,
            loops_left: 0,
            seq: [Seq {
                ptr: 0,
                cnt: 0,
                refresh: 1,
                enddelay: 0,
            }; 2],
            psel: [psel::DISCONNECTED; 4],
            play: None,
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    fn tick_ps(&self) -> u64 {
        62_500 << self.prescaler.min(7)
    }

    fn period_end(&self, p: &Play) -> u64 {
        after_ps(p.period_start, u64::from(p.top.max(1)), self.tick_ps())
    }

    fn flip_at(&self, p: &Play, ch: usize) -> u64 {
        let compare = p.compare.get(ch).map_or(0, |c| c & 0x7FFF);
        after_ps(p.period_start, u64::from(compare), self.tick_ps())
    }

    /// The next edge or period end.
    pub fn next_event_ns(&self) -> u64 {
        let Some(p) = self.play.as_ref() else {
            return u64::MAX;
        };
        let mut next = u64::MAX;
        for ch in 0..4 {
            if p.flip_pending.get(ch).copied().unwrap_or(false) {
                next = next.min(self.flip_at(p, ch));
            }
        }
        // A held, edgeless output needs no more periods (nothing observes PWMPERIODEND).
        let constant = p.holding && !p.flip_pending.iter().any(|&f| f) && !self.edges(p) && !p.stop;
        if !constant {
            next = next.min(self.period_end(p));
        }
        next
    }

    /// Whether the loaded values make edges in a period (COMPARE 0 or ≥ COUNTERTOP keep
    /// one level all along).
    fn edges(&self, p: &Play) -> bool {
        (0..4).any(|ch| {
            let c = p.compare.get(ch).map_or(0, |c| c & 0x7FFF);
            self.pin(ch).is_some() && c != 0 && c < p.top
        })
    }

    fn pin(&self, ch: usize) -> Option<crate::wire::Pin> {
        self.psel.get(ch).and_then(|&v| psel::pin(v))
    }

    fn set_out(&self, ch: usize, high: bool, ctx: &mut Ctx<'_>, at: u64) {
        if let Some(pin) = self.pin(ch) {
            let drive = if high { Drive::High } else { Drive::Low };
            ctx.pins.claim(pin, self.name, drive, ctx.outside, at);
        }
    }

    fn words_per_step(&self) -> u32 {
        match self.decoder & 3 {
            0 => 1,
            1 => 2,
            _ => 4,
        }
    }

    fn steps(&self, seq: usize) -> u32 {
        self.seq
            .get(seq)
            .map_or(0, |s| s.cnt / self.words_per_step())
    }

    /// Loads step `p.step` of `p.seq` from RAM.
    fn load(&self, p: &mut Play, ctx: &mut Ctx<'_>, at: u64) {
        let Some(s) = self.seq.get(p.seq).copied() else {
            return;
        };
        let n = self.words_per_step();
        let addr = s.ptr.wrapping_add(2 * n * p.step);
        let mut bytes = [0u8; 8];
        let len = (2 * n) as usize;
        if let Some(buf) = bytes.get_mut(..len) {
            if !in_ram(addr, len as u32) {
                ctx.records.dma_fault(self.channel, addr, len as u32, at);
            }
            ctx.ram.dma_read(self.channel, addr, buf, at);
        }
        let w = |i: usize| {
            u16::from_le_bytes([
                bytes.get(2 * i).copied().unwrap_or(0),
                bytes.get(2 * i + 1).copied().unwrap_or(0),
            ])
        };
        p.compare = match self.decoder & 3 {
            0 => [w(0); 4],
            1 => [w(0), w(0), w(1), w(1)],
            2 => [w(0), w(1), w(2), w(3)],
            _ => [w(0), w(1), w(2), 0x7FFF],
        };
        p.top = if self.decoder & 3 == 3 {
            w(3) & 0x7FFF
        } else {
            (self.countertop & 0x7FFF) as u16
        };
        p.left = s.refresh + 1;
        p.step += 1;
    }

    /// Starts a PWM period at `at` with the loaded values.
    fn begin_period(&self, p: &mut Play, ctx: &mut Ctx<'_>, at: u64) {
        p.period_start = at;
        for ch in 0..4 {
            let c = p.compare.get(ch).copied().unwrap_or(0);
            let falling = c & 0x8000 != 0;
            let compare = c & 0x7FFF;
            if let Some(f) = p.flip_pending.get_mut(ch) {
                *f = false;
            }
            if compare == 0 {
                self.set_out(ch, !falling, ctx, at);
            } else {
                self.set_out(ch, falling, ctx, at);
                if compare < p.top
                    && let Some(f) = p.flip_pending.get_mut(ch)
                {
                    *f = true;
                }
            }
        }
    }

    fn start_seq(&mut self, seq: usize, ctx: &mut Ctx<'_>, at: u64) {
        if self.enable == 0 {
            ctx.records.note(self.name, "SEQSTART while disabled", at);
            return;
        }
        if self.mode & 1 != 0 {
            ctx.records
                .note(self.name, "up-and-down counter (played as up)", at);
        }
        if self.decoder & 0x100 != 0 {
            ctx.records
                .note(self.name, "NextStep decoding (not modelled)", at);
        }
        if self.play.is_none() {
            self.loops_left = self.loop_cnt;
        }
        self.ev.raise(ev::SEQSTARTED0 + seq as u32, ctx.fired);
        let mut p = Play {
            seq,
            step: 0,
            left: 0,
            in_enddelay: false,
            holding: false,
            period_start: at,
            compare: [0; 4],
            top: 1,
            flip_pending: [false; 4],
            stop: false,
        };
        if self.steps(seq) == 0 {
            self.ev.raise(ev::SEQEND0 + seq as u32, ctx.fired);
            return;
        }
        self.load(&mut p, ctx, at);
        self.begin_period(&mut p, ctx, at);
        self.play = Some(p);
    }

    /// What follows the end of sequence `seq` at `at`.
    fn seq_end(&mut self, mut p: Play, ctx: &mut Ctx<'_>, at: u64) {
        let seq = p.seq;
        self.ev.raise(ev::SEQEND0 + seq as u32, ctx.fired);
        if self.ev.short(short::SEQEND0_STOP + seq as u32) {
            self.stop_now(ctx, at);
            return;
        }
        let mut next = None;
        if self.loop_cnt > 0 {
            if seq == 1 {
                self.loops_left = self.loops_left.saturating_sub(1);
                if self.loops_left == 0 {
                    self.ev.raise(ev::LOOPSDONE, ctx.fired);
                    if self.ev.short(short::LOOPSDONE_STOP) {
                        self.stop_now(ctx, at);
                        return;
                    }
                    for s in 0..2 {
                        if self.ev.short(short::LOOPSDONE_SEQSTART0 + s) {
                            self.loops_left = self.loop_cnt;
                            next = Some(s as usize);
                        }
                    }
                } else {
                    next = Some(0);
                }
            } else {
                next = Some(1);
            }
        }
        match next {
            Some(s) => {
                self.play = None;
                self.ev.raise(ev::SEQSTARTED0 + s as u32, ctx.fired);
                p.seq = s;
                p.step = 0;
                p.in_enddelay = false;
                if self.steps(s) == 0 {
                    self.play = Some(p);
                    self.seq_end(p, ctx, at);
                    return;
                }
                self.load(&mut p, ctx, at);
                self.begin_period(&mut p, ctx, at);
                self.play = Some(p);
            }
            None => {
                p.holding = true;
                p.left = u32::MAX;
                self.begin_period(&mut p, ctx, at);
                self.play = Some(p);
            }
        }
    }

    fn stop_now(&mut self, ctx: &mut Ctx<'_>, at: u64) {
        self.play = None;
        for ch in 0..4 {
            if let Some(pin) = self.pin(ch) {
                ctx.pins.release(pin, self.name, ctx.outside, at);
            }
        }
        self.ev.raise(ev::STOPPED, ctx.fired);
    }

    /// Generates the edges and period ends due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        loop {
            let Some(mut p) = self.play else {
                return;
            };
            let mut flip: Option<(usize, u64)> = None;
            for ch in 0..4 {
                if p.flip_pending.get(ch).copied().unwrap_or(false) {
                    let at = self.flip_at(&p, ch);
                    if flip.is_none_or(|(_, t)| at < t) {
                        flip = Some((ch, at));
                    }
                }
            }
            let end = self.period_end(&p);
            match flip {
                Some((ch, at)) if at <= ctx.now && at <= end => {
                    let falling = p.compare.get(ch).is_some_and(|c| c & 0x8000 != 0);
                    self.set_out(ch, !falling, ctx, at);
                    if let Some(f) = p.flip_pending.get_mut(ch) {
                        *f = false;
                    }
                    self.play = Some(p);
                }
                _ if end <= ctx.now && self.next_event_ns() <= ctx.now => {
                    self.ev.raise(ev::PWMPERIODEND, ctx.fired);
                    if p.stop {
                        self.stop_now(ctx, end);
                        return;
                    }
                    p.left = p.left.saturating_sub(1);
                    if p.left > 0 {
                        self.begin_period(&mut p, ctx, end);
                        self.play = Some(p);
                    } else if p.step < self.steps(p.seq) {
                        self.load(&mut p, ctx, end);
                        self.begin_period(&mut p, ctx, end);
                        self.play = Some(p);
                    } else if !p.in_enddelay && self.seq.get(p.seq).is_some_and(|s| s.enddelay > 0)
                    {
                        p.in_enddelay = true;
                        p.left = self.seq.get(p.seq).map_or(0, |s| s.enddelay);
                        self.begin_period(&mut p, ctx, end);
                        self.play = Some(p);
                    } else {
                        self.seq_end(p, ctx, end);
                    }
                }
                _ => return,
            }
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x500 => self.enable,
            0x504 => self.mode,
            0x508 => self.countertop,
            0x50C => self.prescaler,
            0x510 => self.decoder,
            0x514 => self.loop_cnt,
            0x520..0x560 => {
                let s = self.seq.get(((offset - 0x520) / 0x20) as usize)?;
                match offset % 0x20 {
                    0x0 => s.ptr,
                    0x4 => s.cnt,
                    0x8 => s.refresh,
                    0xC => s.enddelay,
                    _ => return None,
                }
            }
            0x560..0x570 => *self.psel.get(((offset - 0x560) / 4) as usize)?,
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
            0x004 if task => match self.play.as_mut() {
                Some(p) => {
                    p.stop = true;
                    p.holding = false;
                }
                None => self.ev.raise(ev::STOPPED, ctx.fired),
            },
            0x008 | 0x00C if task => {
                self.play = None;
                self.start_seq(((offset - 0x008) / 4) as usize, ctx, now);
            }
            0x010 if task => ctx.records.note(self.name, "NEXTSTEP (not modelled)", now),
            0x004..=0x010 => {}
            0x500 => {
                self.enable = value & 1;
                if self.enable == 0 && self.play.is_some() {
                    self.play = None;
                    for ch in 0..4 {
                        if let Some(pin) = self.pin(ch) {
                            ctx.pins.release(pin, self.name, ctx.outside, now);
                        }
                    }
                }
            }
            0x504 => self.mode = value & 1,
            0x508 => self.countertop = value & 0x7FFF,
            0x50C => self.prescaler = value & 7,
            0x510 => self.decoder = value & 0x103,
            0x514 => self.loop_cnt = value & 0xFFFF,
            0x520..0x560 => {
                let Some(s) = self.seq.get_mut(((offset - 0x520) / 0x20) as usize) else {
                    return false;
                };
                match offset % 0x20 {
                    0x0 => s.ptr = value,
                    0x4 => s.cnt = value & 0x7FFF,
                    0x8 => s.refresh = value & 0xFF_FFFF,
                    0xC => s.enddelay = value & 0xFF_FFFF,
                    _ => return false,
                }
            }
            0x560..0x570 => {
                let Some(p) = self.psel.get_mut(((offset - 0x560) / 4) as usize) else {
                    return false;
                };
                *p = value;
            }
            _ => return false,
        }
        true
    }

    /// Reset: stopped, pins back to GPIO.
    pub fn reset(&mut self, ctx: &mut Ctx<'_>) {
        if self.play.is_some() {
            for ch in 0..4 {
                if let Some(pin) = self.pin(ch) {
                    ctx.pins.release(pin, self.name, ctx.outside, ctx.now);
                }
            }
        }
        *self = Self::new();
    }
}
