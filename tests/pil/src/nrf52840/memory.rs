//! The memories: code flash, Data RAM with its nine AHB slaves, the factory page (FICR) and
//! the user page (UICR). RAM also watches for nRF52840 anomaly 198 (errata v1.6, [198]
//! "SPIM3 transmit data might be corrupted"): while SPIM3 transmits, another bus master (the
//! CPU or another EasyDMA channel) touching the AHB slave its TX buffer lies in may corrupt
//! the byte on the wire. The errata's workaround has two halves (Nordic's `nrfx_spim.c`,
//! `anomaly_198_enable`): the TX buffer's slaves written to the undocumented register
//! 0x4000_0E00 for the transfer, and no CPU writes into the TX buffer meanwhile.

use super::map::{FLASH_SIZE, INFO_PAGE_SIZE, RAM_BASE, RAM_SIZE};
use m4_sim::Width;

/// RAM AHB slaves 0–7 each carry two 4 KiB sections (8 KiB); slave 8 the six 32 KiB
/// sections above 0x2001_0000 (PS "Memory": RAM).
const SMALL_SLAVE: u32 = 0x2000;
/// Where slave 8 begins, as an offset into RAM.
const SLAVE8_OFFSET: u32 = 8 * SMALL_SLAVE;

/// The AHB slave (0–8) of a RAM address.
pub const fn ram_slave(addr: u32) -> u32 {
    let offset = addr.wrapping_sub(RAM_BASE);
    if offset < SLAVE8_OFFSET {
        offset / SMALL_SLAVE
    } else {
        8
    }
}

/// The set of AHB slaves (bit n = slave n) that `len` bytes from `ptr` occupy.
pub fn slaves_of(ptr: u32, len: u32) -> u32 {
    if len == 0 {
        return 0;
    }
    let last = ptr.saturating_add(len - 1);
    (ram_slave(ptr)..=ram_slave(last)).fold(0, |m, s| m | (1 << s))
}

/// Whether `[addr, addr + len)` lies in Data RAM (what EasyDMA can reach).
pub const fn in_ram(addr: u32, len: u32) -> bool {
    addr >= RAM_BASE && (addr as u64 + len as u64) <= RAM_BASE as u64 + RAM_SIZE as u64
}

/// A bus master other than SPIM3 that touched the watched slave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Master {
    /// The CPU (data access or instruction fetch from RAM).
    Cpu,
    /// An EasyDMA channel, e.g. "UARTE1 RXD".
    Dma(&'static str),
}

/// One access that met the conditions of anomaly 198.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Anomaly198Hit {
    /// When, ns.
    pub at_ns: u64,
    /// The address touched.
    pub addr: u32,
    /// Who touched it.
    pub master: Master,
    /// A store (true) or a load.
    pub write: bool,
    /// The AHB slave shared with SPIM3's TX buffer.
    pub slave: u32,
}

/// How the model treats anomaly 198.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Anomaly198Mode {
    /// Count and record the conditions; the bytes go out unchanged.
    #[default]
    Detect,
    /// As `Detect`, and the byte being shifted out when the condition occurs goes out as
    /// 0x00. Nordic does not document the corruption; 0x00 in place of the intended byte is
    /// what users measured (Nordic DevZone threads 48645 and 122571).
    Corrupt,
}

/// What the run saw of anomaly 198.
#[derive(Clone, Debug, Default)]
pub struct Anomaly198 {
    /// SPIM3 transfers with a TX buffer.
    pub transfers: u64,
    /// Accesses that met the anomaly's conditions.
    pub count: u64,
    /// The first accesses (at most 64).
    pub hits: Vec<Anomaly198Hit>,
    /// Bytes sent as 0x00 in [`Anomaly198Mode::Corrupt`].
    pub corrupted_bytes: u64,
}

/// SPIM3's TX buffer while it transmits.
#[derive(Clone, Copy, Debug)]
struct TxWatch {
    ptr: u32,
    len: u32,
    slaves: u32,
    /// A hit since the byte on the wire began.
    pending: bool,
}

/// Data RAM.
pub struct Ram {
    bytes: Vec<u8>,
    /// 1 KiB pages the CPU has fetched instructions from (a write there changes code).
    code_pages: [u64; 4],
    /// Bumped when a store lands in a page code ran from.
    pub generation: u64,
    watch: Option<TxWatch>,
    /// The anomaly-198 workaround register (0x4000_0E00): slaves reserved for SPIM3.
    pub workaround_mask: u32,
    /// What the run saw of anomaly 198.
    pub anomaly: Anomaly198,
}

impl Default for Ram {
    fn default() -> Self {
        Self::new()
    }
}

impl Ram {
    /// 256 KiB of zeros (the silicon powers up with random contents; zeros keep runs
    /// deterministic).
    pub fn new() -> Self {
        Self {
            bytes: vec![0; RAM_SIZE as usize],
            code_pages: [0; 4],
            generation: 0,
            watch: None,
            workaround_mask: 0,
            anomaly: Anomaly198::default(),
        }
    }

    fn span(&self, addr: u32, len: u32) -> Option<core::ops::Range<usize>> {
        let start = addr.checked_sub(RAM_BASE)? as usize;
        let end = start.checked_add(len as usize)?;
        (end <= self.bytes.len()).then_some(start..end)
    }

    /// A CPU load; `None` outside RAM.
    pub fn cpu_read(&mut self, addr: u32, width: Width, now: u64) -> Option<u32> {
        let value = le(self.bytes.get(self.span(addr, width.bytes())?)?);
        self.touch(addr, Master::Cpu, false, now);
        Some(value)
    }

    /// A CPU store; false outside RAM.
    pub fn cpu_write(&mut self, addr: u32, width: Width, value: u32, now: u64) -> bool {
        let Some(span) = self.span(addr, width.bytes()) else {
            return false;
        };
        let page = span.start / 1024;
        let le_value = value.to_le_bytes();
        if let (Some(bytes), Some(src)) =
            (self.bytes.get_mut(span.clone()), le_value.get(..span.len()))
        {
            bytes.copy_from_slice(src);
        }
        if self.is_code_page(page) {
            self.generation += 1;
        }
        self.touch(addr, Master::Cpu, true, now);
        true
    }

    /// A halfword of code fetched from RAM at a Data RAM address.
    pub fn fetch(&mut self, addr: u32, now: u64) -> Option<u16> {
        let span = self.span(addr, 2)?;
        let page = span.start / 1024;
        let half = le(self.bytes.get(span)?) as u16;
        if let Some(word) = self.code_pages.get_mut(page / 64) {
            *word |= 1 << (page % 64);
        }
        self.touch(addr, Master::Cpu, false, now);
        Some(half)
    }

    fn is_code_page(&self, page: usize) -> bool {
        self.code_pages
            .get(page / 64)
            .is_some_and(|w| w & (1 << (page % 64)) != 0)
    }

    /// An EasyDMA read of `out.len()` bytes by `channel`; false (and zeros) if the range
    /// is not Data RAM.
    pub fn dma_read(&mut self, channel: &'static str, addr: u32, out: &mut [u8], now: u64) -> bool {
        let Some(bytes) = self
            .span(addr, out.len() as u32)
            .and_then(|s| self.bytes.get(s))
        else {
            out.fill(0);
            return false;
        };
        out.copy_from_slice(bytes);
        self.touch(addr, Master::Dma(channel), false, now);
        true
    }

    /// An EasyDMA write by `channel`; false (nothing written) if not Data RAM.
    pub fn dma_write(&mut self, channel: &'static str, addr: u32, data: &[u8], now: u64) -> bool {
        let Some(span) = self.span(addr, data.len() as u32) else {
            return false;
        };
        let page = span.start / 1024;
        let Some(bytes) = self.bytes.get_mut(span) else {
            return false;
        };
        bytes.copy_from_slice(data);
        if self.is_code_page(page) {
            self.generation += 1;
        }
        self.touch(addr, Master::Dma(channel), true, now);
        true
    }

    /// Direct access for loading and inspection (no bus master involved).
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// SPIM3 starts sending `len` bytes from `ptr`.
    pub fn watch_spim3(&mut self, ptr: u32, len: u32) {
        self.anomaly.transfers += 1;
        self.watch = Some(TxWatch {
            ptr,
            len,
            slaves: slaves_of(ptr, len),
            pending: false,
        });
    }

    /// SPIM3's transfer ended.
    pub fn unwatch_spim3(&mut self) {
        self.watch = None;
    }

    /// Whether the anomaly's condition occurred since the last call (the byte now on the
    /// wire is affected); clears the flag.
    pub fn take_spim3_hit(&mut self) -> bool {
        self.watch
            .as_mut()
            .is_some_and(|w| core::mem::take(&mut w.pending))
    }

    fn touch(&mut self, addr: u32, master: Master, write: bool, now: u64) {
        let Some(watch) = self.watch.as_mut() else {
            return;
        };
        if matches!(master, Master::Dma(name) if name.starts_with("SPIM3")) {
            return;
        }
        let slave = ram_slave(addr);
        if watch.slaves & (1 << slave) == 0 {
            return;
        }
        let reserved = self.workaround_mask & (1 << slave) != 0;
        let into_buffer = write && addr >= watch.ptr && addr - watch.ptr < watch.len;
        if reserved && !into_buffer {
            return;
        }
        watch.pending = true;
        self.anomaly.count += 1;
        if self.anomaly.hits.len() < 64 {
            self.anomaly.hits.push(Anomaly198Hit {
                at_ns: now,
                addr,
                master,
                write,
                slave,
            });
        }
    }
}

/// Little-endian value of up to four bytes.
pub fn le(bytes: &[u8]) -> u32 {
    bytes.iter().rev().fold(0, |v, &b| (v << 8) | u32::from(b))
}

/// Code flash: 1 MiB, erased to 0xFF.
pub struct Flash {
    bytes: Vec<u8>,
}

impl Default for Flash {
    fn default() -> Self {
        Self::new()
    }
}

impl Flash {
    /// Fully erased.
    pub fn new() -> Self {
        Self {
            bytes: vec![0xFF; FLASH_SIZE as usize],
        }
    }

    /// `len` bytes at `addr` (little-endian value); `None` outside flash.
    pub fn read(&self, addr: u32, len: u32) -> Option<u32> {
        let start = addr as usize;
        Some(le(self
            .bytes
            .get(start..start.checked_add(len as usize)?)?))
    }

    /// Programs a word: bits can only go from 1 to 0.
    pub fn program_word(&mut self, addr: u32, value: u32) -> bool {
        let start = (addr & !3) as usize;
        let Some(bytes) = self.bytes.get_mut(start..start + 4) else {
            return false;
        };
        for (b, v) in bytes.iter_mut().zip(value.to_le_bytes()) {
            *b &= v;
        }
        true
    }

    /// Erases the 4 KiB page holding `addr`.
    pub fn erase_page(&mut self, addr: u32) -> bool {
        let start = (addr & !(super::map::FLASH_PAGE - 1)) as usize;
        match self
            .bytes
            .get_mut(start..start + super::map::FLASH_PAGE as usize)
        {
            Some(page) => {
                page.fill(0xFF);
                true
            }
            None => false,
        }
    }

    /// Erases everything.
    pub fn erase_all(&mut self) {
        self.bytes.fill(0xFF);
    }

    /// Copies a load segment in (what a programmer does); false outside flash.
    pub fn load(&mut self, addr: u32, data: &[u8]) -> bool {
        let start = addr as usize;
        match start
            .checked_add(data.len())
            .and_then(|end| self.bytes.get_mut(start..end))
        {
            Some(bytes) => {
                bytes.copy_from_slice(data);
                true
            }
            None => false,
        }
    }

    /// The whole flash content.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// UICR word offsets the model gives a meaning (PS "UICR").
pub mod uicr {
    /// `NRFFW[0]`: the bootloader's start address (the MBR reads it).
    pub const NRFFW0: u32 = 0x014;
    /// `NRFFW[1]`: the MBR parameter page.
    pub const NRFFW1: u32 = 0x018;
    /// `PSELRESET[0]`.
    pub const PSELRESET0: u32 = 0x200;
    /// `PSELRESET[1]`.
    pub const PSELRESET1: u32 = 0x204;
    /// APPROTECT.
    pub const APPROTECT: u32 = 0x208;
    /// NFCPINS: bit 0 set = P0.09/P0.10 are the NFC antenna, clear = GPIO.
    pub const NFCPINS: u32 = 0x20C;
    /// REGOUT0: VOUT in bits 2:0, the REG0 (VDDH → VDD) output and so the GPIO level.
    pub const REGOUT0: u32 = 0x304;
}

/// The user information page, erased to 0xFFFF_FFFF.
#[derive(Clone, Debug)]
pub struct Uicr {
    words: Vec<u32>,
}

impl Default for Uicr {
    fn default() -> Self {
        Self::new()
    }
}

impl Uicr {
    /// Erased.
    pub fn new() -> Self {
        Self {
            words: vec![0xFFFF_FFFF; (INFO_PAGE_SIZE / 4) as usize],
        }
    }

    /// The word at byte offset `offset` (aligned down).
    pub fn word(&self, offset: u32) -> u32 {
        self.words
            .get((offset / 4) as usize)
            .copied()
            .unwrap_or(0xFFFF_FFFF)
    }

    /// Programs a word (bits only go from 1 to 0); false outside the page.
    pub fn program(&mut self, offset: u32, value: u32) -> bool {
        match self.words.get_mut((offset / 4) as usize) {
            Some(w) => {
                *w &= value;
                true
            }
            None => false,
        }
    }

    /// Erases the page.
    pub fn erase(&mut self) {
        self.words.fill(0xFFFF_FFFF);
    }
}

/// REGOUT0's output voltage for a UICR.REGOUT0 value (PS "UICR": VOUT 0 = 1.8 V, 1 = 2.1 V,
/// 2 = 2.4 V, 3 = 2.7 V, 4 = 3.0 V, 5 = 3.3 V, 7 = the erased default, 1.8 V).
pub fn regout0_volts(regout0: u32) -> f32 {
    match regout0 & 7 {
        1 => 2.1,
        2 => 2.4,
        3 => 2.7,
        4 => 3.0,
        5 => 3.3,
        _ => 1.8,
    }
}
