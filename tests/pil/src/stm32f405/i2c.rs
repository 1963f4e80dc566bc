//! I2C1 as a master (RM0090 §27, the v1 peripheral embassy-stm32's `i2c/v1.rs` drives):
//! CR1 (PE, START, STOP, ACK, POS, SWRST), CR2 (FREQ, ITEVTEN, ITBUFEN, ITERREN, DMAEN,
//! LAST), SR1 (SB, ADDR, BTF, TXE, RXNE, BERR, ARLO, AF, OVR) and SR2 (MSL, BUSY, TRA) with
//! their clearing sequences (SB: read SR1 then write DR; ADDR: read SR1 then SR2; BTF: read
//! SR1 then access DR), CCR/TRISE timing, DMA requests and the event/error interrupts.
//!
//! Each bus step goes to the board (`Outside::i2c_step`) when it ends on the wire: START
//! and STOP take one SCL period, a byte nine (8 data bits + acknowledge); SCL period from
//! CCR: standard mode 2·CCR, fast mode 3·CCR (DUTY 0) or 25·CCR (DUTY 1) PCLK1 cycles.
//! With LAST and DMA the byte the DMA stream will take last is not acknowledged.
//!
//! **The stuck bus.** BUSY follows the lines (RM0090 §27.6.7): set whenever SDA or SCL is
//! seen low, cleared only by a STOP condition on the lines, SWRST or a peripheral reset —
//! also while the pins are GPIOs (their input stage still feeds the peripheral). A START
//! requested on a busy bus waits for it to become free, so with a target holding SDA low it
//! never completes; clocking SCL from GPIO until the target lets go, then a STOP, frees it.
//! A board answering `Stuck` to a step means SDA is held low: a START does not happen, an
//! address or data byte with a 1 in it loses arbitration (ARLO), read data are 0x00.

use crate::wire::{I2cReply, I2cStep, Outside};

const CR1: u32 = 0x00;
const CR2: u32 = 0x04;
const OAR1: u32 = 0x08;
const OAR2: u32 = 0x0C;
const DR: u32 = 0x10;
const SR1: u32 = 0x14;
const SR2: u32 = 0x18;
const CCR: u32 = 0x1C;
const TRISE: u32 = 0x20;
const FLTR: u32 = 0x24;

const PE: u32 = 1 << 0;
const START: u32 = 1 << 8;
const STOP: u32 = 1 << 9;
const ACK: u32 = 1 << 10;
const POS: u32 = 1 << 11;
const SWRST: u32 = 1 << 15;

const ITERREN: u32 = 1 << 8;
const ITEVTEN: u32 = 1 << 9;
const ITBUFEN: u32 = 1 << 10;
const DMAEN: u32 = 1 << 11;
const LAST: u32 = 1 << 12;

const SB: u32 = 1 << 0;
const ADDR: u32 = 1 << 1;
const BTF: u32 = 1 << 2;
const STOPF: u32 = 1 << 4;
const RXNE: u32 = 1 << 6;
const TXE: u32 = 1 << 7;
const ARLO: u32 = 1 << 9;
const AF: u32 = 1 << 10;
/// The rc_w0 error flags (BERR, ARLO, AF, OVR, PECERR, TIMEOUT, SMBALERT).
const ERRORS: u32 = 0xDF00;

const MSL: u32 = 1 << 0;
const BUSY: u32 = 1 << 1;
const TRA: u32 = 1 << 2;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Not the master.
    Idle,
    /// Generating a (repeated) START, done at `.0`.
    Start(u64),
    /// SB set: waiting for the address in DR.
    WaitAddress,
    /// Address byte on the wire until `at`.
    Address { byte: u8, at: u64 },
    /// ADDR set: waiting for SR1 + SR2 reads.
    AddressDone,
    /// Master transmitter; the byte in the shift register and when it ends.
    Transmit(Option<(u8, u64)>),
    /// Master receiver; when the byte being received ends.
    Receive(Option<u64>),
    /// Master of the bus, not transferring (after a NACK or a NACKed last read).
    Hold,
    /// Generating STOP, done at `.0`.
    Stop(u64),
}

/// The I2C controller.
pub struct I2c {
    /// I2Cx number (the bus number the board sees).
    pub bus: u8,
    cr1: u32,
    cr2: u32,
    oar1: u32,
    oar2: u32,
    ccr: u32,
    trise: u32,
    fltr: u32,
    /// SR1 event flags (SB, ADDR, BTF, RXNE, TXE) and errors.
    sr1: u32,
    msl: bool,
    tra: bool,
    busy: bool,
    phase: Phase,
    dr_tx: Option<u8>,
    dr_rx: Option<u8>,
    /// A received byte waiting in the shift register while DR is full (BTF).
    rx_hold: Option<u8>,
    /// The last received byte was acknowledged: reception goes on.
    rx_more: bool,
    sr1_read: bool,
    start_pending: bool,
    stop_pending: bool,
    /// Last levels seen on SCL and SDA.
    lines: (bool, bool),
    pclk: u32,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
    /// Rule breaks to record.
    pub violations: Vec<String>,
}

impl I2c {
    /// I2Cx in its reset state.
    pub fn new(bus: u8) -> Self {
        Self {
            bus,
            cr1: 0,
            cr2: 0,
            oar1: 0,
            oar2: 0,
            ccr: 0,
            trise: 2,
            fltr: 0,
            sr1: 0,
            msl: false,
            tra: false,
            busy: false,
            phase: Phase::Idle,
            dr_tx: None,
            dr_rx: None,
            rx_hold: None,
            rx_more: false,
            sr1_read: false,
            start_pending: false,
            stop_pending: false,
            lines: (true, true),
            pclk: 16_000_000,
            unmodelled: Vec::new(),
            violations: Vec::new(),
        }
    }

    /// Back to reset values (RCC reset, SWRST).
    pub fn reset(&mut self) {
        let (bus, pclk, lines) = (self.bus, self.pclk, self.lines);
        let (u, v) = (
            std::mem::take(&mut self.unmodelled),
            std::mem::take(&mut self.violations),
        );
        *self = Self::new(bus);
        self.pclk = pclk;
        self.lines = lines;
        self.unmodelled = u;
        self.violations = v;
    }

    /// PCLK1.
    pub fn set_pclk(&mut self, hz: u32) {
        self.pclk = hz;
    }

    /// One SCL period, ns.
    pub fn scl_period_ns(&self) -> u64 {
        let ccr = u64::from(self.ccr & 0xFFF).max(1);
        let cycles = if self.ccr & (1 << 15) == 0 {
            2 * ccr
        } else if self.ccr & (1 << 14) == 0 {
            3 * ccr
        } else {
            25 * ccr
        };
        (cycles * 1_000_000_000).div_ceil(u64::from(self.pclk.max(1)))
    }

    fn byte_ns(&self) -> u64 {
        9 * self.scl_period_ns()
    }

    /// The next time a bus step ends.
    pub fn next_event(&self) -> u64 {
        match self.phase {
            Phase::Start(at) | Phase::Stop(at) | Phase::Address { at, .. } => at,
            Phase::Transmit(Some((_, at))) | Phase::Receive(Some(at)) => at,
            _ => u64::MAX,
        }
    }

    fn begin_start(&mut self, now: u64) {
        self.sr1 &= !(TXE | BTF);
        self.start_pending = false;
        self.phase = Phase::Start(now + self.scl_period_ns());
    }

    fn begin_stop(&mut self, now: u64) {
        self.stop_pending = false;
        self.phase = Phase::Stop(now + self.scl_period_ns());
    }

    /// Ends the bus steps due by `now`. `dma_rx_left`: items left on the DMA stream that
    /// serves this controller's receive request, if one is enabled.
    pub fn process<O: Outside>(&mut self, now: u64, outside: &mut O, dma_rx_left: Option<u32>) {
        loop {
            let at = self.next_event();
            if at > now {
                return;
            }
            self.step(at, outside, dma_rx_left);
        }
    }

    fn step<O: Outside>(&mut self, at: u64, outside: &mut O, dma_rx_left: Option<u32>) {
        match self.phase {
            Phase::Start(_) => {
                if outside.i2c_step(self.bus, I2cStep::Start, at) == I2cReply::Stuck {
                    self.busy = true;
                    self.start_pending = true;
                    self.phase = Phase::Idle;
                    self.msl = false;
                    return;
                }
                self.sr1 |= SB;
                self.msl = true;
                self.busy = true;
                self.tra = false;
                self.cr1 &= !START;
                self.phase = Phase::WaitAddress;
            }
            Phase::Address { byte, .. } => {
                let read = byte & 1 != 0;
                let step = I2cStep::Address {
                    addr: byte >> 1,
                    read,
                };
                match outside.i2c_step(self.bus, step, at) {
                    I2cReply::Nack => {
                        self.sr1 |= AF;
                        self.phase = Phase::Hold;
                    }
                    I2cReply::Stuck => self.lose_arbitration(),
                    _ => {
                        self.sr1 |= ADDR;
                        self.tra = !read;
                        self.phase = Phase::AddressDone;
                    }
                }
            }
            Phase::Transmit(Some((byte, _))) => {
                match outside.i2c_step(self.bus, I2cStep::Write(byte), at) {
                    I2cReply::Nack => {
                        self.sr1 |= AF;
                        self.phase = Phase::Hold;
                    }
                    I2cReply::Stuck if byte != 0 => self.lose_arbitration(),
                    _ => {
                        self.phase = Phase::Transmit(None);
                        if let Some(next) = self.dr_tx.take() {
                            self.phase = Phase::Transmit(Some((next, at + self.byte_ns())));
                            self.sr1 |= TXE;
                        } else {
                            self.sr1 |= BTF;
                        }
                    }
                }
                self.after_byte(at);
            }
            Phase::Receive(Some(_)) => {
                let last_for_dma =
                    self.cr2 & (DMAEN | LAST) == DMAEN | LAST && dma_rx_left == Some(1);
                let ack = self.cr1 & ACK != 0 && !last_for_dma;
                let byte = match outside.i2c_step(self.bus, I2cStep::Read { ack }, at) {
                    I2cReply::Data(b) => b,
                    I2cReply::Stuck => 0x00,
                    _ => 0xFF,
                };
                self.rx_more = ack;
                self.phase = Phase::Receive(None);
                if self.dr_rx.is_some() {
                    self.rx_hold = Some(byte);
                    self.sr1 |= BTF;
                } else {
                    self.dr_rx = Some(byte);
                    self.sr1 |= RXNE;
                    self.continue_receive(at);
                }
                self.after_byte(at);
            }
            Phase::Stop(_) => {
                let stuck = outside.i2c_step(self.bus, I2cStep::Stop, at) == I2cReply::Stuck;
                self.cr1 &= !STOP;
                self.msl = false;
                self.tra = false;
                self.sr1 &= !(TXE | BTF);
                self.phase = Phase::Idle;
                // SDA held low: no STOP condition on the wire, the bus stays busy.
                self.busy = stuck;
                if self.start_pending && !self.busy {
                    self.begin_start(at);
                }
            }
            _ => {}
        }
    }

    fn lose_arbitration(&mut self) {
        self.sr1 |= ARLO;
        self.msl = false;
        self.busy = true;
        self.phase = Phase::Idle;
    }

    /// A pending START or STOP follows the byte that just ended.
    fn after_byte(&mut self, at: u64) {
        let between_bytes = matches!(
            self.phase,
            Phase::Transmit(None) | Phase::Receive(None) | Phase::Hold
        );
        if !between_bytes {
            return;
        }
        if self.stop_pending {
            self.begin_stop(at);
        } else if self.start_pending {
            self.begin_start(at);
        }
    }

    fn continue_receive(&mut self, at: u64) {
        if self.rx_more && !self.stop_pending && !self.start_pending && self.rx_hold.is_none() {
            self.phase = Phase::Receive(Some(at + self.byte_ns()));
        } else if !self.rx_more {
            self.phase = Phase::Hold;
        }
    }

    /// The levels of SCL and SDA changed (or were looked at): BUSY follows the lines and a
    /// STOP condition (SDA rising while SCL is high) frees the bus.
    pub fn observe_lines(&mut self, scl: bool, sda: bool, now: u64) {
        let (was_scl, was_sda) = self.lines;
        self.lines = (scl, sda);
        if self.phase != Phase::Idle {
            return;
        }
        if !scl || !sda {
            self.busy = true;
        } else if was_scl && scl && !was_sda && sda {
            self.busy = false;
            if self.start_pending && self.cr1 & PE != 0 {
                self.begin_start(now);
            }
        }
    }

    fn sr1_value(&self) -> u32 {
        let mut v = self.sr1;
        if self.dr_rx.is_some() {
            v |= RXNE;
        } else {
            v &= !RXNE;
        }
        v
    }

    /// The event interrupt line.
    pub fn ev_irq(&self) -> bool {
        let sr1 = self.sr1_value();
        self.cr2 & ITEVTEN != 0
            && (sr1 & (SB | ADDR | BTF | STOPF) != 0
                || (self.cr2 & ITBUFEN != 0 && sr1 & (TXE | RXNE) != 0))
    }

    /// The error interrupt line.
    pub fn er_irq(&self) -> bool {
        self.cr2 & ITERREN != 0 && self.sr1 & ERRORS != 0
    }

    /// The transmit DMA request.
    pub fn tx_request(&self) -> bool {
        self.cr2 & DMAEN != 0
            && matches!(self.phase, Phase::Transmit(_))
            && self.sr1 & TXE != 0
            && self.dr_tx.is_none()
    }

    /// The receive DMA request.
    pub fn rx_request(&self) -> bool {
        self.cr2 & DMAEN != 0 && self.dr_rx.is_some()
    }

    /// Register read at `now`.
    pub fn read(&mut self, offset: u32, now: u64) -> Option<u32> {
        Some(match offset {
            CR1 => self.cr1,
            CR2 => self.cr2,
            OAR1 => self.oar1,
            OAR2 => self.oar2,
            DR => {
                self.clear_btf_after_sr1();
                let b = self.dr_rx.take();
                if let Some(h) = self.rx_hold.take() {
                    self.dr_rx = Some(h);
                    self.sr1 &= !BTF;
                    self.continue_receive(now);
                }
                u32::from(b.unwrap_or(0))
            }
            SR1 => {
                let v = self.sr1_value();
                self.sr1_read = v & (SB | ADDR | BTF) != 0;
                v
            }
            SR2 => {
                if self.sr1_read && self.sr1 & ADDR != 0 {
                    self.sr1 &= !ADDR;
                    self.sr1_read = false;
                    self.begin_data(now);
                }
                let mut v = 0;
                if self.msl {
                    v |= MSL;
                }
                if self.busy || self.phase != Phase::Idle {
                    v |= BUSY;
                }
                if self.tra {
                    v |= TRA;
                }
                v
            }
            CCR => self.ccr,
            TRISE => self.trise,
            FLTR => self.fltr,
            _ => return None,
        })
    }

    fn clear_btf_after_sr1(&mut self) {
        if self.sr1_read && self.sr1 & BTF != 0 && self.rx_hold.is_none() {
            self.sr1 &= !BTF;
        }
        self.sr1_read = false;
    }

    /// ADDR cleared: the data phase starts.
    fn begin_data(&mut self, now: u64) {
        if self.tra {
            self.sr1 |= TXE;
            self.phase = Phase::Transmit(None);
            if let Some(b) = self.dr_tx.take() {
                self.phase = Phase::Transmit(Some((b, now + self.byte_ns())));
            }
            if self.stop_pending {
                self.after_byte(now);
            }
        } else {
            self.rx_more = true;
            self.phase = Phase::Receive(Some(now + self.byte_ns()));
        }
    }

    /// Register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        match offset {
            CR1 => self.write_cr1(value, now),
            CR2 => {
                self.cr2 = value & 0x1F3F;
                let mhz = self.pclk / 1_000_000;
                if value & 0x3F != mhz && value & 0x3F != 0 {
                    self.violations.push(format!(
                        "I2C{} CR2.FREQ = {} MHz but PCLK1 is {} MHz (RM0090 §27.6.2)",
                        self.bus,
                        value & 0x3F,
                        mhz
                    ));
                }
            }
            OAR1 => self.oar1 = value,
            OAR2 => self.oar2 = value,
            DR => self.write_dr(value as u8, now),
            SR1 => self.sr1 &= value | !ERRORS,
            SR2 => {}
            CCR => self.ccr = value & 0xCFFF,
            TRISE => self.trise = value & 0x3F,
            FLTR => self.fltr = value & 0x1F,
            _ => return None,
        }
        Some(())
    }

    fn write_dr(&mut self, byte: u8, now: u64) {
        if self.phase == Phase::WaitAddress && self.sr1 & SB != 0 {
            if self.sr1_read {
                self.sr1 &= !SB;
                self.sr1_read = false;
                self.phase = Phase::Address {
                    byte,
                    at: now + self.byte_ns(),
                };
            } else {
                self.violations.push(format!(
                    "I2C{} address written to DR without reading SR1 after SB (RM0090 §27.3.3 EV5)",
                    self.bus
                ));
            }
            return;
        }
        self.clear_btf_after_sr1();
        match self.phase {
            Phase::Transmit(None) => {
                self.sr1 &= !BTF;
                self.phase = Phase::Transmit(Some((byte, now + self.byte_ns())));
                self.sr1 |= TXE;
            }
            Phase::Transmit(Some(_)) => {
                self.dr_tx = Some(byte);
                self.sr1 &= !TXE;
            }
            _ => self.dr_tx = Some(byte),
        }
    }

    fn write_cr1(&mut self, value: u32, now: u64) {
        if value & SWRST != 0 {
            self.reset();
            self.cr1 = SWRST;
            return;
        }
        let old = self.cr1;
        self.cr1 = value & 0xBFFB;
        if value & 0x3A != 0 {
            self.unmodelled
                .push("I2C SMBus / PEC / general call / no-stretch");
        }
        if value & POS != 0 {
            self.unmodelled.push("I2C CR1.POS (two-byte reception)");
        }
        if value & PE == 0 {
            // Disabled: the controller lets go of the bus; BUSY still follows the lines.
            self.phase = Phase::Idle;
            self.sr1 = 0;
            self.msl = false;
            self.tra = false;
            self.dr_rx = None;
            self.rx_hold = None;
            self.dr_tx = None;
            self.start_pending = false;
            self.stop_pending = false;
            self.cr1 &= !(START | STOP | ACK);
            return;
        }
        if value & START != 0 && old & START == 0 {
            self.request_start(now);
        }
        if value & STOP != 0 && old & STOP == 0 {
            self.request_stop(now);
        }
    }

    fn request_start(&mut self, now: u64) {
        match self.phase {
            Phase::Idle if self.busy => self.start_pending = true,
            Phase::Idle | Phase::Hold | Phase::AddressDone | Phase::WaitAddress => {
                self.begin_start(now)
            }
            Phase::Transmit(None) | Phase::Receive(None) => self.begin_start(now),
            _ => self.start_pending = true,
        }
    }

    fn request_stop(&mut self, now: u64) {
        match self.phase {
            Phase::Idle => self.cr1 &= !STOP,
            Phase::Transmit(None) | Phase::Hold | Phase::WaitAddress => self.begin_stop(now),
            Phase::Receive(None) if self.rx_hold.is_none() => self.begin_stop(now),
            _ => self.stop_pending = true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stm32f405::testing::Board;

    /// embassy's init at 400 kHz from a 42 MHz PCLK1: PE off, SWRST pulse, FREQ 42,
    /// CCR fast mode 35, TRISE 13, PE on.
    fn init() -> I2c {
        let mut i = I2c::new(1);
        i.set_pclk(42_000_000);
        i.write(CR1, 0, 0);
        i.write(CR1, SWRST, 0);
        i.write(CR1, 0, 0);
        i.write(CR2, 42, 0);
        i.write(CCR, 1 << 15 | 35, 0);
        i.write(TRISE, 13, 0);
        i.write(CR1, PE, 0);
        i
    }

    fn run(i: &mut I2c, b: &mut Board, until: u64) {
        i.process(until, b, None);
    }

    #[test]
    fn a_byte_is_nine_scl_periods_at_400_khz() {
        let i = init();
        assert_eq!(i.scl_period_ns(), 2_500);
        assert_eq!(i.byte_ns(), 22_500);
        assert!(i.violations.is_empty());
    }

    #[test]
    fn master_write_follows_the_reference_manual_events() {
        let mut i = init();
        let mut b = Board::default();
        i.write(CR2, 42 | ITEVTEN | ITERREN, 0);
        i.write(CR1, PE | START, 1_000);
        assert!(!i.ev_irq());
        run(&mut i, &mut b, 3_500);
        assert_eq!(i.read(SR1, 3_500), Some(SB));
        assert!(i.ev_irq());
        assert_eq!(
            i.read(CR1, 3_500).unwrap() & START,
            0,
            "START cleared by hardware"
        );
        assert_eq!(i.read(SR2, 3_500), Some(MSL | BUSY));
        i.write(DR, 0x77 << 1, 3_600);
        assert!(!i.ev_irq(), "SB cleared by SR1 read + DR write");
        run(&mut i, &mut b, 3_600 + 22_500);
        assert_eq!(i.read(SR1, 26_100), Some(ADDR));
        assert_eq!(i.read(SR2, 26_100), Some(MSL | BUSY | TRA));
        assert_eq!(i.read(SR1, 26_100), Some(TXE));
        i.write(DR, 0x1E, 26_200);
        assert_eq!(
            i.read(SR1, 26_200),
            Some(TXE),
            "straight into the shift register"
        );
        run(&mut i, &mut b, 26_200 + 22_500);
        assert_eq!(i.read(SR1, 48_700), Some(TXE | BTF));
        i.write(CR1, PE | STOP, 48_800);
        run(&mut i, &mut b, 60_000);
        assert_eq!(i.read(SR2, 60_000), Some(0));
        assert_eq!(
            b.i2c.iter().map(|s| s.1).collect::<Vec<_>>(),
            vec![
                I2cStep::Start,
                I2cStep::Address {
                    addr: 0x77,
                    read: false
                },
                I2cStep::Write(0x1E),
                I2cStep::Stop
            ]
        );
        assert_eq!(b.i2c[1].2, 26_100);
    }

    #[test]
    fn a_nacked_address_sets_af_and_raises_the_error_line() {
        let mut i = init();
        let mut b = Board::default();
        b.i2c_replies.extend([I2cReply::Ack, I2cReply::Nack]);
        i.write(CR2, 42 | ITERREN, 0);
        i.write(CR1, PE | START, 0);
        run(&mut i, &mut b, 10_000);
        i.read(SR1, 10_000);
        i.write(DR, 0x76 << 1, 10_000);
        run(&mut i, &mut b, 40_000);
        assert_eq!(i.read(SR1, 40_000), Some(AF));
        assert!(i.er_irq());
        i.write(SR1, !AF, 40_000);
        assert!(!i.er_irq());
    }

    /// embassy read_frame of 3 bytes with DMA and LAST: the third byte is NACKed.
    #[test]
    fn a_dma_read_with_last_nacks_the_final_byte() {
        let mut i = init();
        let mut b = Board::default();
        b.i2c_replies.extend([
            I2cReply::Ack,
            I2cReply::Ack,
            I2cReply::Data(0x11),
            I2cReply::Data(0x22),
            I2cReply::Data(0x33),
        ]);
        i.write(CR2, 42 | DMAEN | LAST, 0);
        i.write(CR1, PE | START | ACK, 0);
        run(&mut i, &mut b, 10_000);
        i.read(SR1, 10_000);
        i.write(DR, 0x77 << 1 | 1, 10_000);
        run(&mut i, &mut b, 40_000);
        i.read(SR1, 40_000);
        i.read(SR2, 40_000);
        let mut got = vec![];
        let mut left = 3;
        let mut t = 40_000;
        while left > 0 {
            t += 1_000;
            i.process(t, &mut b, Some(left));
            if i.rx_request() {
                got.push(i.read(DR, t).unwrap() as u8);
                left -= 1;
            }
        }
        assert_eq!(got, vec![0x11, 0x22, 0x33]);
        let acks: Vec<_> = b
            .i2c
            .iter()
            .filter_map(|s| match s.1 {
                I2cStep::Read { ack } => Some(ack),
                _ => None,
            })
            .collect();
        assert_eq!(acks, vec![true, true, false]);
        // The firmware sets STOP after the DMA's transfer-complete.
        i.write(CR1, PE | ACK | STOP, t);
        run(&mut i, &mut b, t + 10_000);
        assert_eq!(b.i2c.last().unwrap().1, I2cStep::Stop);
        assert_eq!(i.read(SR2, t + 10_000), Some(0));
    }

    #[test]
    fn a_reader_too_slow_for_the_bus_sees_btf_and_the_bus_stretched() {
        let mut i = init();
        let mut b = Board::default();
        b.i2c_replies.extend([I2cReply::Ack, I2cReply::Ack]);
        i.write(CR1, PE | START | ACK, 0);
        run(&mut i, &mut b, 10_000);
        i.read(SR1, 10_000);
        i.write(DR, 0x77 << 1 | 1, 10_000);
        run(&mut i, &mut b, 40_000);
        i.read(SR1, 40_000);
        i.read(SR2, 40_000);
        run(&mut i, &mut b, 200_000);
        let reads = b
            .i2c
            .iter()
            .filter(|s| matches!(s.1, I2cStep::Read { .. }))
            .count();
        assert_eq!(
            reads, 2,
            "second byte held in the shift register, SCL stretched"
        );
        assert_eq!(i.read(SR1, 200_000).unwrap() & (BTF | RXNE), BTF | RXNE);
    }

    #[test]
    fn a_held_sda_keeps_busy_and_a_start_never_completes_until_a_stop_frees_the_bus() {
        let mut i = init();
        let mut b = Board::default();
        // The target holds SDA low: the peripheral sees it and latches BUSY.
        i.observe_lines(true, false, 0);
        assert_eq!(i.read(SR2, 0).unwrap() & BUSY, BUSY);
        i.write(CR2, 42 | ITEVTEN, 0);
        i.write(CR1, PE | START, 0);
        run(&mut i, &mut b, 1_000_000_000);
        assert!(b.i2c.is_empty(), "no START on a busy bus");
        assert_eq!(i.read(SR1, 1_000_000_000), Some(0));
        assert!(!i.ev_irq());
        // GPIO recovery: SCL pulses (SDA still low), SDA released, then a STOP.
        for k in 0..9 {
            i.observe_lines(false, false, 1_000_000_000 + k * 10);
            i.observe_lines(true, false, 1_000_000_005 + k * 10);
        }
        i.observe_lines(true, true, 1_000_000_200);
        assert_eq!(
            i.read(SR1, 1_000_000_200),
            Some(0),
            "the START waits for the bus to be free"
        );
        run(&mut i, &mut b, 1_000_010_000);
        assert_eq!(b.i2c.len(), 1);
        assert_eq!(i.read(SR1, 1_000_010_000), Some(SB));
    }

    #[test]
    fn a_target_holding_sda_mid_read_turns_the_stop_into_a_busy_bus() {
        let mut i = init();
        let mut b = Board::default();
        b.i2c_replies.extend([
            I2cReply::Ack,
            I2cReply::Ack,
            I2cReply::Stuck,
            I2cReply::Stuck,
        ]);
        i.write(CR1, PE | START, 0);
        run(&mut i, &mut b, 10_000);
        i.read(SR1, 10_000);
        i.write(DR, 0x77 << 1 | 1, 10_000);
        run(&mut i, &mut b, 40_000);
        i.read(SR1, 40_000);
        i.read(SR2, 40_000);
        i.write(CR1, PE | STOP, 40_000);
        run(&mut i, &mut b, 100_000);
        assert_eq!(i.read(DR, 100_000), Some(0), "SDA held low reads as zeros");
        assert_eq!(b.i2c.last().unwrap().1, I2cStep::Stop);
        assert_eq!(
            i.read(SR2, 100_000).unwrap() & BUSY,
            BUSY,
            "no STOP condition happened"
        );
        i.write(CR1, PE | START, 100_000);
        run(&mut i, &mut b, 10_000_000);
        assert_eq!(i.read(SR1, 10_000_000), Some(0));
        // SWRST clears the latch; the next START goes out.
        i.write(CR1, SWRST, 10_000_000);
        i.write(CR1, 0, 10_000_000);
        i.write(CR2, 42, 10_000_000);
        i.write(CCR, 1 << 15 | 35, 10_000_000);
        i.write(CR1, PE | START, 10_000_000);
        run(&mut i, &mut b, 10_010_000);
        assert_eq!(i.read(SR1, 10_010_000), Some(SB));
    }
}
