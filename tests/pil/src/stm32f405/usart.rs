//! USART1 in asynchronous mode (RM0090 §30): SR (PE, FE, ORE, IDLE, RXNE, TC, TXE), DR,
//! BRR, CR1 (UE, M, PCE, TE, RE and the interrupt enables), CR2.STOP, CR3 (DMAR, DMAT, EIE).
//!
//! Baud rate from BRR and the APB2 clock (RM0090 §30.3.4: fCK / BRR with OVER8 = 0,
//! fCK / (8·mantissa + fraction) with OVER8 = 1); a frame is start + 8 or 9 bits + stop
//! bits. Sent bytes reach the board at the end of their stop bit. Received bytes come from
//! a queue the board fills, each at the end of its stop bit: a byte that arrives while
//! RXNE is still set is lost and sets ORE (the GPS overrun finding); the line going idle
//! for a frame after a reception sets IDLE. A byte sent at another baud rate is sampled as
//! the receiver would (bit centres from the start edge), so a baud mismatch gives garbage
//! and framing errors. Not modelled (recorded): synchronous, LIN, IrDA, smartcard,
//! half-duplex and hardware flow control.

use std::collections::VecDeque;

use crate::wire::Outside;

const SR: u32 = 0x00;
const DR: u32 = 0x04;
const BRR: u32 = 0x08;
const CR1: u32 = 0x0C;
const CR2: u32 = 0x10;
const CR3: u32 = 0x14;
const GTPR: u32 = 0x18;

const PE: u32 = 1 << 0;
const FE: u32 = 1 << 1;
const ORE: u32 = 1 << 3;
const IDLE: u32 = 1 << 4;
const RXNE: u32 = 1 << 5;
const TC: u32 = 1 << 6;
const TXE: u32 = 1 << 7;

const RE: u32 = 1 << 2;
const TE: u32 = 1 << 3;
const IDLEIE: u32 = 1 << 4;
const RXNEIE: u32 = 1 << 5;
const TCIE: u32 = 1 << 6;
const TXEIE: u32 = 1 << 7;
const PEIE: u32 = 1 << 8;
const PCE: u32 = 1 << 10;
const M: u32 = 1 << 12;
const UE: u32 = 1 << 13;
const OVER8: u32 = 1 << 15;

const EIE: u32 = 1 << 0;
const DMAR: u32 = 1 << 6;
const DMAT: u32 = 1 << 7;

/// A byte on its way in.
#[derive(Clone, Copy, Debug)]
struct Incoming {
    /// End of its stop bit (when RXNE would set).
    at_ns: u64,
    data: u16,
    framing_error: bool,
}

/// The USART.
pub struct Usart {
    /// USARTx number (the board's UART number).
    pub number: u8,
    sr: u32,
    brr: u32,
    cr1: u32,
    cr2: u32,
    cr3: u32,
    gtpr: u32,
    rdr: u16,
    tdr: Option<u16>,
    /// The frame on the TX line and when its stop bit ends.
    tx_shift: Option<(u16, u64)>,
    rx_queue: VecDeque<Incoming>,
    /// When the line goes idle after the last reception (IDLE detection).
    idle_at: Option<u64>,
    /// SR read with error/idle flags set: a DR read then clears them.
    sr_read: u32,
    pclk: u32,
    /// Bytes lost to overrun.
    pub overruns: u64,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Usart {
    /// USARTx in its reset state.
    pub fn new(number: u8) -> Self {
        Self {
            number,
            sr: TXE | TC,
            brr: 0,
            cr1: 0,
            cr2: 0,
            cr3: 0,
            gtpr: 0,
            rdr: 0,
            tdr: None,
            tx_shift: None,
            rx_queue: VecDeque::new(),
            idle_at: None,
            sr_read: 0,
            pclk: 16_000_000,
            overruns: 0,
            unmodelled: Vec::new(),
        }
    }

    /// Back to reset values (the board's queued bytes stay on the line).
    pub fn reset(&mut self) {
        let queue = std::mem::take(&mut self.rx_queue);
        let (n, pclk, overruns) = (self.number, self.pclk, self.overruns);
        *self = Self::new(n);
        self.rx_queue = queue;
        self.pclk = pclk;
        self.overruns = overruns;
    }

    /// The APB clock.
    pub fn set_pclk(&mut self, hz: u32) {
        self.pclk = hz;
    }

    /// The configured baud rate (0 if BRR is 0).
    pub fn baud(&self) -> u32 {
        // fCK / (8 · (2 − OVER8) · USARTDIV), USARTDIV = mantissa + fraction / (8 · (2 − OVER8)).
        let div = if self.cr1 & OVER8 != 0 {
            8 * (self.brr >> 4) + (self.brr & 7)
        } else {
            self.brr & 0xFFFF
        };
        if div == 0 {
            return 0;
        }
        self.pclk / div
    }

    /// Bits in a frame: start, data (8 or 9), stop.
    fn frame_bits(&self) -> f64 {
        let data = if self.cr1 & M != 0 { 9.0 } else { 8.0 };
        let stop = match (self.cr2 >> 12) & 3 {
            1 => 0.5,
            2 => 2.0,
            3 => 1.5,
            _ => 1.0,
        };
        1.0 + data + stop
    }

    fn bit_ns(&self) -> f64 {
        1e9 / f64::from(self.baud().max(1))
    }

    fn frame_ns(&self) -> u64 {
        (self.frame_bits() * self.bit_ns()).ceil() as u64
    }

    /// A byte arriving at the configured baud rate, its stop bit ending at `at_ns`.
    pub fn receive(&mut self, byte: u8, at_ns: u64) {
        self.push_incoming(Incoming {
            at_ns,
            data: u16::from(byte),
            framing_error: false,
        });
    }

    /// A byte sent at `sender_baud`, its stop bit ending at `end_ns`: sampled at this
    /// receiver's bit centres from the start edge (16× oversampling's centre sample).
    pub fn receive_at_baud(&mut self, byte: u8, sender_baud: u32, end_ns: u64) {
        let tx_bit = 1e9 / f64::from(sender_baud.max(1));
        let start = end_ns as f64 - 10.0 * tx_bit;
        // The sender's line: start bit 0, data LSB first, stop bit and idle 1.
        let line = |t: f64| -> bool {
            let k = ((t - start) / tx_bit).floor();
            if k < 1.0 {
                false
            } else if k <= 8.0 {
                byte >> (k as u32 - 1) & 1 != 0
            } else {
                true
            }
        };
        let rx_bit = self.bit_ns();
        let mut data = 0u16;
        for i in 0..8u32 {
            if line(start + (f64::from(i) + 1.5) * rx_bit) {
                data |= 1 << i;
            }
        }
        let stop_sample = start + 9.5 * rx_bit;
        self.push_incoming(Incoming {
            at_ns: stop_sample.max(0.0) as u64,
            data,
            framing_error: !line(stop_sample),
        });
    }

    fn push_incoming(&mut self, ev: Incoming) {
        let pos = self
            .rx_queue
            .iter()
            .rposition(|e| e.at_ns <= ev.at_ns)
            .map_or(0, |i| i + 1);
        self.rx_queue.insert(pos, ev);
    }

    /// The next time the USART changes by itself.
    pub fn next_event(&self) -> u64 {
        let rx = self.rx_queue.front().map_or(u64::MAX, |e| e.at_ns);
        let tx = self.tx_shift.map_or(u64::MAX, |s| s.1);
        let idle = self.idle_at.unwrap_or(u64::MAX);
        rx.min(tx).min(idle)
    }

    /// Processes everything due by `now`.
    pub fn process<O: Outside>(&mut self, now: u64, outside: &mut O) {
        loop {
            let t = self.next_event();
            if t > now {
                return;
            }
            if let Some((data, end)) = self.tx_shift.filter(|s| s.1 == t) {
                outside.uart_sent(self.number, data as u8, end);
                self.tx_shift = None;
                self.start_tx(end);
                if self.tx_shift.is_none() {
                    self.sr |= TC;
                }
            } else if self.idle_at == Some(t) {
                self.idle_at = None;
                self.sr |= IDLE;
            } else if let Some(ev) = self.rx_queue.pop_front() {
                self.receive_frame(ev);
            }
        }
    }

    fn receive_frame(&mut self, ev: Incoming) {
        if self.cr1 & (UE | RE) != UE | RE {
            return;
        }
        if self.sr & RXNE != 0 {
            // RM0090 §30.3.3: RDR keeps its byte, the shift register's is lost.
            self.sr |= ORE;
            self.overruns += 1;
        } else {
            self.rdr = ev.data;
            self.sr |= RXNE;
            if ev.framing_error {
                self.sr |= FE;
            }
        }
        self.idle_at = Some(ev.at_ns + self.frame_ns());
    }

    fn start_tx(&mut self, now: u64) {
        if self.tx_shift.is_none()
            && self.cr1 & (UE | TE) == UE | TE
            && let Some(d) = self.tdr.take()
        {
            self.tx_shift = Some((d, now + self.frame_ns()));
            self.sr |= TXE;
            self.sr &= !TC;
        }
    }

    /// The USARTx interrupt line.
    pub fn irq(&self) -> bool {
        let sr = self.sr;
        (self.cr1 & TXEIE != 0 && sr & TXE != 0)
            || (self.cr1 & TCIE != 0 && sr & TC != 0)
            || (self.cr1 & RXNEIE != 0 && sr & (RXNE | ORE) != 0)
            || (self.cr1 & IDLEIE != 0 && sr & IDLE != 0)
            || (self.cr1 & PEIE != 0 && sr & PE != 0)
            || (self.cr3 & EIE != 0 && self.cr3 & DMAR != 0 && sr & (FE | ORE) != 0)
    }

    /// Whether the transmitter holds TX at its idle (high) level.
    pub fn tx_enabled(&self) -> bool {
        self.cr1 & (UE | TE) == UE | TE
    }

    /// Transmit DMA request.
    pub fn tx_request(&self) -> bool {
        self.cr3 & DMAT != 0 && self.sr & TXE != 0 && self.cr1 & (UE | TE) == UE | TE
    }

    /// Receive DMA request.
    pub fn rx_request(&self) -> bool {
        self.cr3 & DMAR != 0 && self.sr & RXNE != 0
    }

    /// Register read.
    pub fn read(&mut self, offset: u32) -> Option<u32> {
        Some(match offset {
            SR => {
                self.sr_read = self.sr & (PE | FE | 1 << 2 | ORE | IDLE);
                self.sr
            }
            DR => {
                // RM0090 §30.6.1: reading DR clears RXNE, and after an SR read the error
                // and idle flags SR showed.
                self.sr &= !(RXNE | self.sr_read);
                self.sr_read = 0;
                u32::from(self.rdr)
            }
            BRR => self.brr,
            CR1 => self.cr1,
            CR2 => self.cr2,
            CR3 => self.cr3,
            GTPR => self.gtpr,
            _ => return None,
        })
    }

    /// Register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        match offset {
            SR => {
                // RXNE and TC are rc_w0.
                self.sr &= value | !(RXNE | TC | 1 << 8 | 1 << 9);
            }
            DR => {
                let data = (value & if self.cr1 & M != 0 { 0x1FF } else { 0xFF }) as u16;
                self.tdr = Some(data);
                self.sr &= !(TXE | TC);
                self.start_tx(now);
            }
            BRR => self.brr = value & 0xFFFF,
            CR1 => {
                let was_te = self.cr1 & TE != 0;
                self.cr1 = value & 0xBFFF;
                if value & PCE != 0 {
                    self.unmodelled.push("USART parity");
                }
                if value & UE == 0 {
                    self.tx_shift = None;
                }
                if !was_te && value & TE != 0 && self.tdr.is_none() {
                    // Enabling the transmitter sends an idle frame (RM0090 §30.3.2).
                    self.sr |= TXE;
                }
                self.start_tx(now);
            }
            CR2 => {
                self.cr2 = value & 0x7F7F;
                if value & 0x4F00 != 0 {
                    self.unmodelled.push("USART synchronous clock / LIN");
                }
            }
            CR3 => {
                self.cr3 = value & 0xFFF;
                if value & 0x33E != 0 {
                    self.unmodelled
                        .push("USART IrDA / half-duplex / smartcard / flow control");
                }
            }
            GTPR => self.gtpr = value & 0xFFFF,
            _ => return None,
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stm32f405::testing::Board;

    /// BufferedUart at 9600 Bd from an 84 MHz APB2: BRR 8750, UE TE RE RXNEIE.
    fn gps() -> Usart {
        let mut u = Usart::new(1);
        u.set_pclk(84_000_000);
        u.write(BRR, 8750, 0);
        u.write(CR1, UE | TE | RE | RXNEIE, 0);
        u
    }

    #[test]
    fn baud_rate_and_frame_time_follow_brr() {
        let u = gps();
        assert_eq!(u.baud(), 9_600);
        assert_eq!(u.frame_ns(), 1_041_667);
    }

    #[test]
    fn a_byte_sent_reaches_the_board_at_the_end_of_its_stop_bit() {
        let mut u = gps();
        let mut b = Board::default();
        u.write(DR, 0xB5, 1_000);
        assert_eq!(u.read(SR).unwrap() & (TXE | TC), TXE);
        u.write(DR, 0x62, 2_000);
        assert_eq!(u.read(SR).unwrap() & TXE, 0);
        u.process(10_000_000, &mut b);
        assert_eq!(b.uart, vec![(1, 0xB5, 1_042_667), (1, 0x62, 2_084_334)]);
        assert_eq!(u.read(SR).unwrap() & (TXE | TC), TXE | TC);
    }

    #[test]
    fn a_byte_arriving_while_rxne_is_set_is_lost_with_ore() {
        let mut u = gps();
        let mut b = Board::default();
        u.receive(0x01, 1_000_000);
        u.receive(0x02, 2_100_000);
        u.process(1_000_000, &mut b);
        assert!(u.irq());
        u.process(3_000_000, &mut b);
        assert_eq!(u.read(SR).unwrap() & (RXNE | ORE), RXNE | ORE);
        assert_eq!(u.read(DR), Some(0x01));
        assert_eq!(
            u.read(SR).unwrap() & (RXNE | ORE),
            0,
            "SR then DR cleared ORE"
        );
        assert_eq!(u.overruns, 1);
        // The line idles one frame after the last byte.
        u.process(2_100_000 + 1_041_667, &mut b);
        assert_eq!(u.read(SR).unwrap() & IDLE, IDLE);
    }

    #[test]
    fn a_byte_at_the_wrong_baud_is_garbage() {
        let mut u = gps();
        let mut b = Board::default();
        u.receive_at_baud(0x55, 9_600, 5_000_000);
        u.process(6_000_000, &mut b);
        assert_eq!(u.read(SR).unwrap() & FE, 0);
        assert_eq!(u.read(DR), Some(0x55));
        // The GPS already at 115 200 Bd while the port listens at 9 600.
        u.receive_at_baud(0xB5, 115_200, 10_000_000);
        u.process(20_000_000, &mut b);
        let sr = u.read(SR).unwrap();
        let d = u.read(DR).unwrap();
        assert!(d != 0xB5 || sr & FE != 0);
    }
}
