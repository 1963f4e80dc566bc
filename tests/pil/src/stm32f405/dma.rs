//! DMA1 and DMA2 (RM0090 §10): eight streams each with CR (CHSEL, DIR, CIRC, PINC, MINC,
//! sizes, DBM/CT, interrupt enables, EN), NDTR, PAR, M0AR/M1AR, FCR; the interrupt status
//! and clear registers; the per-stream interrupt lines; and the request mapping of RM0090
//! Tables 42/43 for the peripherals modelled.
//!
//! The controller decides *what* to move; the SoC moves it (a peripheral request is served
//! at once, one peripheral-sized item per request). Transfers are instantaneous: bus
//! arbitration, burst and FIFO timing are not modelled; in FIFO mode the memory side sees
//! the same byte stream as in direct mode. Reachability is checked: the DMA cannot reach
//! the CCM RAM (a transfer error, as on the silicon), DMA1's peripheral port reaches APB1
//! only, and memory-to-memory needs DMA2.

use super::map::{CCM_BASE, CCM_SIZE, irq};

// Flag bits within a stream's 6-bit group.
const FEIF: u32 = 1 << 0;
const DMEIF: u32 = 1 << 2;
const TEIF: u32 = 1 << 3;
const HTIF: u32 = 1 << 4;
const TCIF: u32 = 1 << 5;
/// Bit offsets of streams 0–3 (LISR) and 4–7 (HISR) groups.
const GROUP_SHIFT: [u32; 4] = [0, 6, 16, 22];

// CR bits.
const EN: u32 = 1 << 0;
const DMEIE: u32 = 1 << 1;
const TEIE: u32 = 1 << 2;
const HTIE: u32 = 1 << 3;
const TCIE: u32 = 1 << 4;
const PFCTRL: u32 = 1 << 5;
const CIRC: u32 = 1 << 8;
const PINC: u32 = 1 << 9;
const MINC: u32 = 1 << 10;
const PINCOS: u32 = 1 << 15;
const DBM: u32 = 1 << 18;
const CT: u32 = 1 << 19;
const FEIE: u32 = 1 << 7;

/// A peripheral's DMA request line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// SPI1 transmit buffer empty.
    Spi1Tx,
    /// SPI1 receive buffer not empty.
    Spi1Rx,
    /// SPI3 TXE.
    Spi3Tx,
    /// SPI3 RXNE.
    Spi3Rx,
    /// I2C1 TxE.
    I2c1Tx,
    /// I2C1 RxNE.
    I2c1Rx,
    /// USART1 TXE.
    Usart1Tx,
    /// USART1 RXNE.
    Usart1Rx,
    /// DAC channel 1 trigger.
    Dac1,
    /// ADC1 end of conversion.
    Adc1,
}

/// The request on `controller` (0 = DMA1) `stream` `channel` (RM0090 Tables 42/43), for
/// the modelled peripherals.
pub fn request_of(controller: u8, stream: u8, channel: u8) -> Option<Request> {
    use Request::*;
    Some(match (controller, stream, channel) {
        (0, 0 | 2, 0) => Spi3Rx,
        (0, 5 | 7, 0) => Spi3Tx,
        (0, 0 | 5, 1) => I2c1Rx,
        (0, 6 | 7, 1) => I2c1Tx,
        (0, 5, 7) => Dac1,
        (1, 0 | 4, 0) => Adc1,
        (1, 0 | 2, 3) => Spi1Rx,
        (1, 3 | 5, 3) => Spi1Tx,
        (1, 2 | 5, 4) => Usart1Rx,
        (1, 7, 4) => Usart1Tx,
        _ => return None,
    })
}

/// Direction of a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Peripheral → memory.
    PeripheralToMemory,
    /// Memory → peripheral.
    MemoryToPeripheral,
    /// Memory → memory (DMA2 only, no request).
    MemoryToMemory,
}

/// One item to move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Item {
    /// Which way.
    pub dir: Direction,
    /// Peripheral-port address (source for P→M, destination for M→P; source for M→M).
    pub periph_addr: u32,
    /// Memory-port address.
    pub mem_addr: u32,
    /// Bytes (PSIZE).
    pub size: u32,
}

#[derive(Clone, Copy, Debug, Default)]
struct Stream {
    cr: u32,
    ndtr: u32,
    par: u32,
    m0ar: u32,
    m1ar: u32,
    fcr: u32,
    /// NDTR as programmed (reload value, half-transfer point).
    initial: u32,
    periph_ptr: u32,
    mem_ptr: u32,
}

impl Stream {
    fn reset() -> Self {
        Self {
            fcr: 0x21,
            ..Self::default()
        }
    }

    fn enabled(&self) -> bool {
        self.cr & EN != 0
    }

    fn channel(&self) -> u8 {
        ((self.cr >> 25) & 7) as u8
    }

    fn dir(&self) -> Option<Direction> {
        match (self.cr >> 6) & 3 {
            0 => Some(Direction::PeripheralToMemory),
            1 => Some(Direction::MemoryToPeripheral),
            2 => Some(Direction::MemoryToMemory),
            _ => None,
        }
    }

    fn psize(&self) -> u32 {
        1 << ((self.cr >> 11) & 3).min(2)
    }

    fn msize(&self) -> u32 {
        1 << ((self.cr >> 13) & 3).min(2)
    }

    fn priority(&self) -> u32 {
        (self.cr >> 16) & 3
    }

    fn memory_base(&self) -> u32 {
        if self.cr & DBM != 0 && self.cr & CT != 0 {
            self.m1ar
        } else {
            self.m0ar
        }
    }

    fn start(&mut self) {
        self.initial = self.ndtr;
        self.periph_ptr = self.par;
        self.mem_ptr = self.memory_base();
    }
}

/// One DMA controller.
pub struct Dma {
    index: u8,
    streams: [Stream; 8],
    /// LISR (streams 0–3) and HISR (4–7).
    isr: [u32; 2],
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
    /// Rule breaks to record.
    pub violations: Vec<String>,
    /// The streams whose interrupt line is up (kept current on every change).
    lines: u8,
}

/// How an item ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Moved.
    Done,
    /// A bus error on either port: TEIF, stream disabled.
    BusError,
}

impl Dma {
    /// Controller `index` (0 = DMA1) in its reset state.
    pub fn new(index: u8) -> Self {
        Self {
            index,
            streams: [Stream::reset(); 8],
            isr: [0; 2],
            unmodelled: Vec::new(),
            violations: Vec::new(),
            lines: 0,
        }
    }

    /// Back to reset values.
    pub fn reset(&mut self) {
        self.streams = [Stream::reset(); 8];
        self.isr = [0; 2];
        self.lines = 0;
    }

    fn flag_pos(stream: usize) -> (usize, u32) {
        (
            stream / 4,
            GROUP_SHIFT.get(stream % 4).copied().unwrap_or(0),
        )
    }

    fn set_flag(&mut self, stream: usize, flag: u32) {
        let (reg, shift) = Self::flag_pos(stream);
        if let Some(r) = self.isr.get_mut(reg) {
            *r |= flag << shift;
        }
    }

    fn flags(&self, stream: usize) -> u32 {
        let (reg, shift) = Self::flag_pos(stream);
        self.isr.get(reg).map_or(0, |r| (r >> shift) & 0x3D)
    }

    /// The interrupt lines of this controller's streams, as IRQ numbers.
    pub fn irqs(&self) -> impl Iterator<Item = u32> + '_ {
        (0..8u8)
            .filter(move |s| self.lines & (1 << s) != 0)
            .map(move |s| irq::dma_stream(self.index, s))
    }

    fn update_lines(&mut self) {
        let mut lines = 0;
        for (i, st) in self.streams.iter().enumerate() {
            let f = self.flags(i);
            let cr = st.cr;
            let on = (f & TCIF != 0 && cr & TCIE != 0)
                || (f & HTIF != 0 && cr & HTIE != 0)
                || (f & TEIF != 0 && cr & TEIE != 0)
                || (f & DMEIF != 0 && cr & DMEIE != 0)
                || (f & FEIF != 0 && st.fcr & FEIE != 0);
            if on {
                lines |= 1 << i;
            }
        }
        self.lines = lines;
    }

    /// Whether any stream is enabled (nothing to serve otherwise).
    pub fn active(&self) -> bool {
        self.streams.iter().any(Stream::enabled)
    }

    /// Enabled streams waiting on a peripheral request, highest priority first (PL, then
    /// the lower stream number: RM0090 §10.3.3).
    pub fn requesting(&self) -> impl Iterator<Item = (usize, Request)> + '_ {
        (0..4u32).rev().flat_map(move |pl| {
            self.streams.iter().enumerate().filter_map(move |(i, s)| {
                let wanted =
                    s.enabled() && s.priority() == pl && s.dir() != Some(Direction::MemoryToMemory);
                if !wanted {
                    return None;
                }
                request_of(self.index, i as u8, s.channel()).map(|r| (i, r))
            })
        })
    }

    /// The first enabled memory-to-memory stream (they run without a request).
    pub fn memory_to_memory(&self) -> Option<usize> {
        self.streams
            .iter()
            .position(|s| s.enabled() && s.dir() == Some(Direction::MemoryToMemory))
    }

    /// The stream serving `req`, if one is enabled.
    pub fn stream_for(&self, req: Request) -> Option<usize> {
        self.requesting().find(|&(_, r)| r == req).map(|(i, _)| i)
    }

    /// Remaining items on `stream`.
    pub fn remaining(&self, stream: usize) -> u32 {
        self.streams.get(stream).map_or(0, |s| s.ndtr)
    }

    /// The next item `stream` moves.
    pub fn item(&self, stream: usize) -> Option<Item> {
        let s = self.streams.get(stream)?;
        if !s.enabled() || s.ndtr == 0 {
            return None;
        }
        Some(Item {
            dir: s.dir()?,
            periph_addr: s.periph_ptr,
            mem_addr: s.mem_ptr,
            size: s.psize(),
        })
    }

    /// Whether this controller's port can reach `addr` (None: it can).
    pub fn reach_error(&self, addr: u32, periph_port: bool) -> Option<String> {
        if (CCM_BASE..CCM_BASE + CCM_SIZE).contains(&addr) {
            return Some(format!(
                "DMA{} stream addresses the CCM RAM at 0x{addr:08x}: the CCM is on the D-bus only (RM0090 §2.3.1), a DMA transfer error",
                self.index + 1
            ));
        }
        if periph_port && self.index == 0 && !(0x4000_0000..0x4000_8000).contains(&addr) {
            return Some(format!(
                "DMA1 peripheral port at 0x{addr:08x}: it reaches APB1 only (RM0090 Figure 1)"
            ));
        }
        None
    }

    /// Accounts for a moved item (or a bus error) on `stream`.
    pub fn complete(&mut self, stream: usize, outcome: Outcome) {
        self.complete_item(stream, outcome);
        self.update_lines();
    }

    fn complete_item(&mut self, stream: usize, outcome: Outcome) {
        let Some(s) = self.streams.get_mut(stream) else {
            return;
        };
        if outcome == Outcome::BusError {
            s.cr &= !EN;
            self.set_flag(stream, TEIF);
            return;
        }
        let psize = s.psize();
        if s.cr & PINC != 0 {
            s.periph_ptr = s
                .periph_ptr
                .wrapping_add(if s.cr & PINCOS != 0 { 4 } else { psize });
        }
        let mem_inc = s.cr & MINC != 0 || s.dir() == Some(Direction::MemoryToMemory);
        if mem_inc {
            s.mem_ptr = s.mem_ptr.wrapping_add(psize);
        }
        s.ndtr = s.ndtr.saturating_sub(1);
        let half = s.ndtr == s.initial / 2 && s.initial > 1;
        let done = s.ndtr == 0;
        let circular = s.cr & (CIRC | DBM) != 0;
        if done {
            if circular {
                s.ndtr = s.initial;
                if s.cr & DBM != 0 {
                    s.cr ^= CT;
                }
                s.periph_ptr = s.par;
                s.mem_ptr = s.memory_base();
            } else {
                s.cr &= !EN;
            }
        }
        if half {
            self.set_flag(stream, HTIF);
        }
        if done {
            self.set_flag(stream, TCIF);
        }
    }

    /// Register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        match offset {
            0x00 => self.isr.first().copied(),
            0x04 => self.isr.get(1).copied(),
            0x08 | 0x0C => Some(0),
            0x10..=0xCF => {
                let i = ((offset - 0x10) / 0x18) as usize;
                let s = self.streams.get(i)?;
                Some(match (offset - 0x10) % 0x18 {
                    0x00 => s.cr,
                    0x04 => s.ndtr,
                    0x08 => s.par,
                    0x0C => s.m0ar,
                    0x10 => s.m1ar,
                    _ => s.fcr,
                })
            }
            _ => None,
        }
    }

    /// Register write.
    pub fn write(&mut self, offset: u32, value: u32) -> Option<()> {
        let done = self.write_register(offset, value);
        self.update_lines();
        done
    }

    fn write_register(&mut self, offset: u32, value: u32) -> Option<()> {
        match offset {
            0x00 | 0x04 => {}
            0x08 | 0x0C => {
                let r = self.isr.get_mut(((offset - 0x08) / 4) as usize)?;
                *r &= !(value & 0x0F7D_0F7D);
            }
            0x10..=0xCF => {
                let i = ((offset - 0x10) / 0x18) as usize;
                let reg = (offset - 0x10) % 0x18;
                self.write_stream(i, reg, value)?;
            }
            _ => return None,
        }
        Some(())
    }

    fn write_stream(&mut self, i: usize, reg: u32, value: u32) -> Option<()> {
        let index = self.index;
        let flags = self.flags(i);
        let s = self.streams.get_mut(i)?;
        let enabled = s.enabled();
        match reg {
            // RM0090 §10.5.5: while the stream runs only clearing EN takes effect (CT flips
            // by hardware in double-buffer mode).
            0x00 if enabled && value & EN == 0 => {
                s.cr &= !EN;
                if s.ndtr > 0 {
                    // Stopped by software mid-transfer: TCIF (RM0090 §10.3.17).
                    self.set_flag(i, TCIF);
                }
            }
            0x00 if enabled => {}
            0x00 => {
                s.cr = value & 0x0FEF_FFFF;
                if value & EN == 0 {
                    return Some(());
                }
                s.start();
                let (dir, ndtr) = (s.dir(), s.ndtr);
                let packing = s.msize() != s.psize() && s.fcr & 4 == 0;
                if dir == Some(Direction::MemoryToMemory) && index == 0 {
                    s.cr &= !EN;
                    self.set_flag(i, TEIF);
                    self.violations.push(
                        "DMA1 in memory-to-memory mode (only DMA2 can, RM0090 §10.3.6)".into(),
                    );
                } else if ndtr == 0 {
                    s.cr &= !EN;
                }
                if value & PFCTRL != 0 {
                    self.unmodelled.push("DMA peripheral flow control");
                }
                if packing {
                    self.violations.push(format!(
                        "DMA{} stream {i}: MSIZE differs from PSIZE in direct mode (RM0090 §10.3.11: MSIZE is ignored)",
                        index + 1
                    ));
                }
                if flags != 0 {
                    self.violations.push(format!(
                        "DMA{} stream {i} enabled with its status flags still set (RM0090 §10.3.17: clear them first)",
                        index + 1
                    ));
                }
            }
            0x04 if !enabled => s.ndtr = value & 0xFFFF,
            0x08 if !enabled => s.par = value,
            0x0C if !enabled || (s.cr & DBM != 0 && s.cr & CT != 0) => s.m0ar = value,
            0x10 if !enabled || (s.cr & DBM != 0 && s.cr & CT == 0) => s.m1ar = value,
            0x14 if !enabled => s.fcr = (s.fcr & 0x38) | (value & 0x87),
            _ => {}
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// embassy's `configure` for SPI1 RX on DMA2 stream 0, channel 3: 4 bytes into SRAM.
    fn spi1_rx(d: &mut Dma) {
        let base = 0x10;
        d.write(0x08, 0x3D); // clear_irqs
        d.write(base + 0x08, 0x4001_300C);
        d.write(base + 0x0C, 0x2000_0100);
        d.write(base + 0x04, 4);
        d.write(base + 0x14, 0x04); // direct mode
        d.write(base, 3 << 25 | 3 << 16 | MINC | TEIE | TCIE);
        d.write(base, 3 << 25 | 3 << 16 | MINC | TEIE | TCIE | EN);
    }

    #[test]
    fn a_peripheral_to_memory_stream_moves_ndtr_items_then_completes() {
        let mut d = Dma::new(1);
        spi1_rx(&mut d);
        assert_eq!(
            d.requesting().collect::<Vec<_>>(),
            vec![(0, Request::Spi1Rx)]
        );
        for k in 0..4 {
            let item = d.item(0).unwrap();
            assert_eq!(item.dir, Direction::PeripheralToMemory);
            assert_eq!(item.periph_addr, 0x4001_300C);
            assert_eq!(item.mem_addr, 0x2000_0100 + k);
            assert_eq!(item.size, 1);
            assert_eq!(d.irqs().count(), 0);
            d.complete(0, Outcome::Done);
        }
        assert_eq!(d.read(0x10).unwrap() & EN, 0);
        assert_eq!(d.read(0x00).unwrap(), TCIF | HTIF);
        assert_eq!(d.irqs().collect::<Vec<_>>(), vec![56]);
        d.write(0x08, TCIF | HTIF);
        assert_eq!(d.irqs().count(), 0);
    }

    #[test]
    fn circular_streams_reload_and_flag_half_and_complete() {
        let mut d = Dma::new(0);
        // DAC1 on DMA1 stream 5 channel 7, halfwords, circular, 4 items.
        let base = 0x10 + 5 * 0x18;
        d.write(base + 0x08, 0x4000_7408);
        d.write(base + 0x0C, 0x2000_0000);
        d.write(base + 0x04, 4);
        d.write(
            base,
            7 << 25 | 1 << 13 | 1 << 11 | MINC | CIRC | 1 << 6 | EN,
        );
        assert_eq!(d.requesting().collect::<Vec<_>>(), vec![(5, Request::Dac1)]);
        let addrs: Vec<u32> = (0..6)
            .map(|_| {
                let a = d.item(5).unwrap().mem_addr;
                d.complete(5, Outcome::Done);
                a
            })
            .collect();
        assert_eq!(
            addrs,
            [
                0x2000_0000,
                0x2000_0002,
                0x2000_0004,
                0x2000_0006,
                0x2000_0000,
                0x2000_0002
            ]
        );
        assert_eq!(d.read(0x04).unwrap() >> 6 & 0x3D, TCIF | HTIF);
        assert_eq!(d.read(0x10 + 5 * 0x18).unwrap() & EN, EN);
    }

    #[test]
    fn double_buffer_mode_alternates_the_memory_targets() {
        let mut d = Dma::new(1);
        let base = 0x10 + 2 * 0x18;
        d.write(base + 0x0C, 0x2000_0000);
        d.write(base + 0x10, 0x2000_1000);
        d.write(base + 0x04, 2);
        d.write(base, 4 << 25 | MINC | DBM | EN);
        assert_eq!(
            d.requesting().collect::<Vec<_>>(),
            vec![(2, Request::Usart1Rx)]
        );
        d.complete(2, Outcome::Done);
        d.complete(2, Outcome::Done);
        assert_eq!(d.item(2).unwrap().mem_addr, 0x2000_1000);
        assert_eq!(d.read(base).unwrap() & CT, CT);
        // The target not in use may be rewritten while running.
        d.write(base + 0x0C, 0x2000_2000);
        d.complete(2, Outcome::Done);
        d.complete(2, Outcome::Done);
        assert_eq!(d.item(2).unwrap().mem_addr, 0x2000_2000);
    }

    #[test]
    fn registers_are_locked_while_enabled_and_a_stop_sets_tcif() {
        let mut d = Dma::new(1);
        spi1_rx(&mut d);
        d.write(0x10 + 0x04, 99);
        assert_eq!(d.read(0x14), Some(4));
        d.write(0x10, 0);
        assert_eq!(d.read(0x10).unwrap() & EN, 0);
        assert_eq!(d.read(0x00).unwrap() & TCIF, TCIF);
    }

    #[test]
    fn the_ccm_and_apb2_from_dma1_are_out_of_reach() {
        let d1 = Dma::new(0);
        let d2 = Dma::new(1);
        assert!(d2.reach_error(0x1000_0400, false).is_some());
        assert!(d2.reach_error(0x2000_0400, false).is_none());
        assert!(d1.reach_error(0x4001_300C, true).is_some());
        assert!(d1.reach_error(0x4000_3C0C, true).is_none());
        let mut d = Dma::new(1);
        spi1_rx(&mut d);
        d.complete(0, Outcome::BusError);
        assert_eq!(d.read(0x00).unwrap() & TEIF, TEIF);
        assert_eq!(d.read(0x10).unwrap() & EN, 0);
    }

    #[test]
    fn request_mapping_matches_the_boards_streams() {
        // board.rs: SPI3 TX DMA1 S7 / RX S2 ch0; I2C1 TX S6 / RX S0 ch1; DAC1 S5 ch7;
        // SPI1 TX DMA2 S3 / RX S0 ch3.
        assert_eq!(request_of(0, 7, 0), Some(Request::Spi3Tx));
        assert_eq!(request_of(0, 2, 0), Some(Request::Spi3Rx));
        assert_eq!(request_of(0, 6, 1), Some(Request::I2c1Tx));
        assert_eq!(request_of(0, 0, 1), Some(Request::I2c1Rx));
        assert_eq!(request_of(0, 5, 7), Some(Request::Dac1));
        assert_eq!(request_of(1, 3, 3), Some(Request::Spi1Tx));
        assert_eq!(request_of(1, 0, 3), Some(Request::Spi1Rx));
        assert_eq!(request_of(1, 7, 4), Some(Request::Usart1Tx));
        assert_eq!(request_of(0, 1, 0), None);
    }
}
