//! SPI1 and SPI3 in master mode (RM0090 §28): CR1 (CPHA, CPOL, MSTR, BR, SPE, LSBFIRST,
//! SSI, SSM, DFF), CR2 (DMA enables, interrupt enables), SR (RXNE, TXE, MODF, OVR, BSY) and
//! DR with its transmit and receive buffers.
//!
//! A frame starts when data reaches an empty shift register of an enabled master and ends
//! 8 (or 16) SCK periods later, SCK = PCLK / 2^(BR+1); at that instant the board is given
//! the byte (`Outside::spi_byte`, MSB first on the wire: LSBFIRST reverses it) and answers
//! MISO. A frame waiting in the transmit buffer follows without a gap. A received frame
//! that finds RXNE still set is lost and sets OVR (cleared by reading DR, then SR). Not
//! modelled (recorded): CRC, bidirectional and receive-only modes, slave mode, I²S.

use crate::wire::Outside;

const CR1: u32 = 0x00;
const CR2: u32 = 0x04;
const SR: u32 = 0x08;
const DR: u32 = 0x0C;
const CRCPR: u32 = 0x10;
const RXCRCR: u32 = 0x14;
const TXCRCR: u32 = 0x18;
const I2SCFGR: u32 = 0x1C;
const I2SPR: u32 = 0x20;

const CPHA: u32 = 1 << 0;
const CPOL: u32 = 1 << 1;
const MSTR: u32 = 1 << 2;
const SPE: u32 = 1 << 6;
const LSBFIRST: u32 = 1 << 7;
const SSI: u32 = 1 << 8;
const SSM: u32 = 1 << 9;
const RXONLY: u32 = 1 << 10;
const DFF: u32 = 1 << 11;
const CRCEN: u32 = 1 << 13;
const BIDIMODE: u32 = 1 << 15;

const RXDMAEN: u32 = 1 << 0;
const TXDMAEN: u32 = 1 << 1;
const ERRIE: u32 = 1 << 5;
const RXNEIE: u32 = 1 << 6;
const TXEIE: u32 = 1 << 7;

const RXNE: u32 = 1 << 0;
const TXE: u32 = 1 << 1;
const MODF: u32 = 1 << 5;
const OVR: u32 = 1 << 6;
const BSY: u32 = 1 << 7;

/// The bus configuration, for a board that checks its chips' SPI mode and speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiConfig {
    /// Clock polarity (SCK idle high).
    pub cpol: bool,
    /// Clock phase (data captured on the second edge).
    pub cpha: bool,
    /// SCK frequency, Hz.
    pub sck_hz: u32,
    /// Least significant bit first.
    pub lsb_first: bool,
    /// 16-bit frames.
    pub frame16: bool,
}

#[derive(Clone, Copy, Debug)]
struct Shift {
    data: u16,
    ends_at: u64,
}

/// One SPI controller.
pub struct Spi {
    /// SPIx number (1 or 3): the bus number the board sees.
    pub bus: u8,
    cr1: u32,
    cr2: u32,
    crcpr: u32,
    i2scfgr: u32,
    i2spr: u32,
    tx: Option<u16>,
    rx: Option<u16>,
    shift: Option<Shift>,
    modf: bool,
    /// SR was read with MODF set: the next CR1 write clears it.
    modf_sr_read: bool,
    ovr: bool,
    /// DR was read while OVR was set: the next SR read clears it.
    ovr_dr_read: bool,
    pclk: u32,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
    /// Rule breaks to record.
    pub violations: Vec<&'static str>,
    /// Frames exchanged.
    pub frames: u64,
}

impl Spi {
    /// SPIx in its reset state.
    pub fn new(bus: u8) -> Self {
        Self {
            bus,
            cr1: 0,
            cr2: 0,
            crcpr: 7,
            i2scfgr: 0,
            i2spr: 2,
            tx: None,
            rx: None,
            shift: None,
            modf: false,
            modf_sr_read: false,
            ovr: false,
            ovr_dr_read: false,
            pclk: 16_000_000,
            unmodelled: Vec::new(),
            violations: Vec::new(),
            frames: 0,
        }
    }

    /// Back to reset values.
    pub fn reset(&mut self) {
        let (bus, pclk, frames) = (self.bus, self.pclk, self.frames);
        *self = Self::new(bus);
        self.pclk = pclk;
        self.frames = frames;
    }

    /// The APB clock feeding the baud-rate generator.
    pub fn set_pclk(&mut self, hz: u32) {
        self.pclk = hz;
    }

    fn master_enabled(&self) -> bool {
        self.cr1 & (SPE | MSTR) == SPE | MSTR
    }

    /// SCK frequency.
    pub fn sck_hz(&self) -> u32 {
        let br = (self.cr1 >> 3) & 7;
        self.pclk >> (br + 1)
    }

    /// The current configuration.
    pub fn config(&self) -> SpiConfig {
        SpiConfig {
            cpol: self.cr1 & CPOL != 0,
            cpha: self.cr1 & CPHA != 0,
            sck_hz: self.sck_hz(),
            lsb_first: self.cr1 & LSBFIRST != 0,
            frame16: self.cr1 & DFF != 0,
        }
    }

    /// SCK's idle level while the master is enabled (None: not driven).
    pub fn sck_idle(&self) -> Option<bool> {
        self.master_enabled().then_some(self.cr1 & CPOL != 0)
    }

    fn frame_ns(&self) -> u64 {
        let bits: u64 = if self.cr1 & DFF != 0 { 16 } else { 8 };
        let div = 2u64 << ((self.cr1 >> 3) & 7);
        (bits * div * 1_000_000_000).div_ceil(u64::from(self.pclk.max(1)))
    }

    fn try_start(&mut self, now: u64) {
        if self.shift.is_none()
            && self.master_enabled()
            && let Some(data) = self.tx.take()
        {
            self.shift = Some(Shift {
                data,
                ends_at: now + self.frame_ns(),
            });
        }
    }

    /// The next frame end.
    pub fn next_event(&self) -> u64 {
        self.shift.map_or(u64::MAX, |s| s.ends_at)
    }

    /// Ends the frames due by `now`, exchanging them with the board.
    pub fn process<O: Outside>(&mut self, now: u64, outside: &mut O) {
        while let Some(s) = self.shift {
            if s.ends_at > now {
                break;
            }
            self.shift = None;
            let t = s.ends_at;
            let miso = self.exchange(s.data, t, outside);
            self.frames += 1;
            if self.ovr {
                // Everything after an overrun is lost until OVR is cleared.
            } else if self.rx.is_some() {
                self.ovr = true;
            } else {
                self.rx = Some(miso);
            }
            self.try_start(t);
        }
    }

    fn exchange<O: Outside>(&self, data: u16, t: u64, outside: &mut O) -> u16 {
        let lsb = self.cr1 & LSBFIRST != 0;
        let wire = |b: u8| if lsb { b.reverse_bits() } else { b };
        if self.cr1 & DFF != 0 {
            // 16-bit frame: two bytes on the wire, the first ends half-way.
            let half = self.frame_ns() / 2;
            let (first, second) = if lsb {
                (data as u8, (data >> 8) as u8)
            } else {
                ((data >> 8) as u8, data as u8)
            };
            let a = wire(outside.spi_byte(self.bus, wire(first), t.saturating_sub(half)));
            let b = wire(outside.spi_byte(self.bus, wire(second), t));
            if lsb {
                u16::from(a) | u16::from(b) << 8
            } else {
                u16::from(a) << 8 | u16::from(b)
            }
        } else {
            u16::from(wire(outside.spi_byte(self.bus, wire(data as u8), t)))
        }
    }

    fn sr(&self) -> u32 {
        let mut sr = 0;
        if self.rx.is_some() {
            sr |= RXNE;
        }
        if self.tx.is_none() {
            sr |= TXE;
        }
        if self.modf {
            sr |= MODF;
        }
        if self.ovr {
            sr |= OVR;
        }
        if self.shift.is_some() || (self.tx.is_some() && self.master_enabled()) {
            sr |= BSY;
        }
        sr
    }

    /// The SPIx interrupt line.
    pub fn irq(&self) -> bool {
        let sr = self.sr();
        (self.cr2 & TXEIE != 0 && sr & TXE != 0)
            || (self.cr2 & RXNEIE != 0 && sr & RXNE != 0)
            || (self.cr2 & ERRIE != 0 && sr & (OVR | MODF) != 0)
    }

    /// The transmit DMA request (TXE with TXDMAEN).
    pub fn tx_request(&self) -> bool {
        self.cr2 & TXDMAEN != 0 && self.tx.is_none()
    }

    /// The receive DMA request (RXNE with RXDMAEN).
    pub fn rx_request(&self) -> bool {
        self.cr2 & RXDMAEN != 0 && self.rx.is_some()
    }

    /// Register read (reading DR takes the received frame).
    pub fn read(&mut self, offset: u32) -> Option<u32> {
        Some(match offset {
            CR1 => self.cr1,
            CR2 => self.cr2,
            SR => {
                let sr = self.sr();
                self.modf_sr_read = self.modf;
                if self.ovr_dr_read {
                    self.ovr = false;
                    self.ovr_dr_read = false;
                }
                sr
            }
            DR => {
                if self.ovr {
                    self.ovr_dr_read = true;
                }
                u32::from(self.rx.take().unwrap_or(0))
            }
            CRCPR => self.crcpr,
            RXCRCR | TXCRCR => 0,
            I2SCFGR => self.i2scfgr,
            I2SPR => self.i2spr,
            _ => return None,
        })
    }

    /// Register write at `now`.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> Option<()> {
        match offset {
            CR1 => self.write_cr1(value, now),
            CR2 => {
                self.cr2 = value & 0xF7;
                if value & (1 << 4) != 0 {
                    self.unmodelled.push("SPI TI frame format");
                }
            }
            SR => {
                // CRCERR is the only writable flag (rc_w0); CRC is not modelled.
            }
            DR => {
                let data = if self.cr1 & DFF != 0 {
                    value as u16
                } else {
                    u16::from(value as u8)
                };
                if self.tx.is_some() {
                    self.violations
                        .push("SPI DR written with TXE clear: the waiting frame is overwritten");
                }
                self.tx = Some(data);
                self.try_start(now);
            }
            CRCPR => self.crcpr = value & 0xFFFF,
            RXCRCR | TXCRCR => {}
            I2SCFGR => {
                self.i2scfgr = value & 0xFBF;
                if value & (1 << 11) != 0 {
                    self.unmodelled.push("SPI I2S mode");
                }
            }
            I2SPR => self.i2spr = value & 0x3FF,
            _ => return None,
        }
        Some(())
    }

    fn write_cr1(&mut self, value: u32, now: u64) {
        if self.modf_sr_read {
            self.modf = false;
            self.modf_sr_read = false;
        }
        if self.cr1 & SPE != 0 && value & SPE == 0 && self.shift.is_some() {
            // RM0090 §28.3.8: wait for TXE = 1 and BSY = 0 before clearing SPE.
            self.violations
                .push("SPI disabled (SPE = 0) while BSY: the frame in flight is cut");
            self.shift = None;
        }
        self.cr1 = value & 0xFFFF;
        if value & CRCEN != 0 {
            self.unmodelled.push("SPI hardware CRC");
        }
        if value & (BIDIMODE | RXONLY) != 0 {
            self.unmodelled
                .push("SPI bidirectional / receive-only mode");
        }
        if value & (SPE | MSTR) == SPE {
            self.unmodelled.push("SPI slave mode");
        }
        if value & MSTR != 0 && value & SSM != 0 && value & SSI == 0 {
            // RM0090 §28.3.10: master with the internal NSS low is a mode fault.
            self.modf = true;
            self.cr1 &= !(SPE | MSTR);
        }
        self.try_start(now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stm32f405::testing::Board;

    /// Spi::new for the RFM22B: mode 0, 42 MHz / 8 = 5.25 MHz (BR = 2), SSM, SSI, SPE.
    fn rfm_spi() -> Spi {
        let mut s = Spi::new(3);
        s.set_pclk(42_000_000);
        s.write(CR2, 1 << 2, 0);
        s.write(CR1, MSTR | 2 << 3 | SPE | SSI | SSM, 0);
        s
    }

    #[test]
    fn a_byte_takes_eight_sck_periods_and_reaches_the_board_at_its_end() {
        let mut s = rfm_spi();
        let mut b = Board::default();
        b.miso.push_back(0x08);
        assert_eq!(s.sck_hz(), 5_250_000);
        assert_eq!(s.read(SR), Some(TXE));
        s.write(DR, 0x07, 1_000);
        assert_eq!(s.read(SR), Some(TXE | BSY), "moved to the shifter at once");
        let end = 1_000 + (8u64 * 8 * 1_000_000_000).div_ceil(42_000_000);
        assert_eq!(s.next_event(), end);
        s.process(end - 1, &mut b);
        assert!(b.spi.is_empty());
        s.process(end, &mut b);
        assert_eq!(b.spi, vec![(3, 0x07, end)]);
        assert_eq!(s.read(SR), Some(TXE | RXNE));
        assert_eq!(s.read(DR), Some(0x08));
        assert_eq!(s.read(SR), Some(TXE));
    }

    #[test]
    fn back_to_back_frames_and_overrun() {
        let mut s = rfm_spi();
        let mut b = Board::default();
        b.miso.extend([1, 2, 3]);
        s.write(DR, 0xA1, 0);
        s.write(DR, 0xA2, 0);
        assert_eq!(s.read(SR).unwrap() & TXE, 0);
        s.process(10_000, &mut b);
        let t: Vec<u64> = b.spi.iter().map(|x| x.2).collect();
        assert_eq!(t[1] - t[0], s.frame_ns(), "no gap between frames");
        // The second byte found RXNE still set: lost, OVR.
        assert_eq!(s.read(SR).unwrap() & (OVR | RXNE), OVR | RXNE);
        assert_eq!(s.read(DR), Some(1));
        s.read(SR);
        assert_eq!(s.read(SR).unwrap() & OVR, 0, "DR then SR clears OVR");
    }

    #[test]
    fn dma_requests_follow_txe_and_rxne() {
        let mut s = rfm_spi();
        let mut b = Board::default();
        s.write(CR2, RXDMAEN | TXDMAEN, 0);
        assert!(s.tx_request());
        s.write(DR, 1, 0);
        assert!(s.tx_request(), "the shifter took it");
        s.write(DR, 2, 0);
        assert!(!s.tx_request());
        s.process(s.next_event(), &mut b);
        assert!(s.rx_request());
        assert!(s.tx_request());
    }

    #[test]
    fn data_written_before_spe_goes_out_when_enabled_and_lsbfirst_reverses_the_wire() {
        let mut s = Spi::new(1);
        let mut b = Board::default();
        s.set_pclk(84_000_000);
        s.write(CR1, MSTR | SSI | SSM | LSBFIRST | CPOL | CPHA, 0);
        s.write(DR, 0x01, 0);
        assert_eq!(s.next_event(), u64::MAX);
        s.write(CR1, MSTR | SSI | SSM | LSBFIRST | CPOL | CPHA | SPE, 100);
        s.process(u64::MAX - 1, &mut b);
        assert_eq!(b.spi[0].1, 0x80);
        assert_eq!(s.read(DR), Some(0xFF));
        assert_eq!(s.sck_idle(), Some(true));
    }

    #[test]
    fn master_with_nss_low_is_a_mode_fault() {
        let mut s = Spi::new(1);
        s.write(CR1, MSTR | SSM | SPE, 0);
        assert_eq!(s.read(SR).unwrap() & MODF, MODF);
        assert_eq!(s.read(CR1).unwrap() & (SPE | MSTR), 0);
    }
}
