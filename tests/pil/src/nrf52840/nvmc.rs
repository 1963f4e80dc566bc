//! The NVMC (PS "NVMC"): write and erase enables, the busy time of each operation with the
//! CPU stalled on flash meanwhile, the UICR erase, and the instruction cache with its
//! profiling counters — plus the model of instruction fetch timing from flash.
//!
//! Timing (PS "NVMC electrical specification", nRF52840): a word write 41 µs, a page erase
//! 85 ms, erasing everything 169 ms; the UICR erase is taken as a page erase.
//!
//! Fetch timing. Nordic publishes neither the flash access time nor the cache geometry
//! (the PS only says the cache reduces wait states). The model: flash is read in 16-byte
//! lines through a one-line buffer; an instruction in a line other than the buffered one
//! costs [`FlashTiming::wait_states`] cycles, unless the cache (ICACHECNF.CACHEEN) holds
//! the line. The cache is taken as large enough for every line it has seen since it was
//! last invalidated (an optimistic bound). The defaults (16-byte lines, 1 wait state) are
//! fitted to the one public measurement found: `cortex_m::asm::delay`'s two-instruction
//! loop takes 4, 5 or 6 cycles on an nRF52840 depending on whether it sits 16-, 8- or
//! 2-byte aligned (rust-embedded/cortex-m issue 151) — a penalty of 0–2 cycles per
//! iteration, which a 1-cycle line change reproduces in size.

use super::map::FLASH_PAGE;
use super::memory::{Flash, Uicr};

/// Word write time, ns.
pub const WRITE_NS: u64 = 41_000;
/// Page erase time, ns.
pub const ERASE_PAGE_NS: u64 = 85_000_000;
/// Full erase time, ns.
pub const ERASE_ALL_NS: u64 = 169_000_000;

/// CONFIG.WEN values.
const REN: u32 = 0;
const WEN: u32 = 1;
const EEN: u32 = 2;

/// The instruction-fetch timing from flash (see the module docs for its source).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FlashTiming {
    /// Bytes the flash delivers per read.
    pub line_bytes: u32,
    /// Cycles an instruction waits when its line must be read from flash.
    pub wait_states: u32,
}

impl Default for FlashTiming {
    fn default() -> Self {
        Self {
            line_bytes: 16,
            wait_states: 1,
        }
    }
}

/// The flash controller.
pub struct Nvmc {
    config: u32,
    busy_until: u64,
    icachecnf: u32,
    ihit: u32,
    imiss: u32,
    partial_cfg: u32,
    timing: FlashTiming,
    buffered_line: Option<u32>,
    cached: LineSet,
}

/// Flash lines, one bit each (the cache's contents): a fetch from a new line looks one up.
#[derive(Debug, Default)]
struct LineSet {
    words: Vec<u64>,
}

impl LineSet {
    /// Adds `line`; whether it was not there.
    fn insert(&mut self, line: u32) -> bool {
        let i = (line / 64) as usize;
        if i >= self.words.len() {
            self.words.resize(i + 1, 0);
        }
        let bit = 1u64 << (line % 64);
        self.words.get_mut(i).is_some_and(|w| {
            let new = *w & bit == 0;
            *w |= bit;
            new
        })
    }

    fn clear(&mut self) {
        self.words.fill(0);
    }
}

impl Nvmc {
    /// Reset state: read-only, idle, cache off (ICACHECNF resets to 0).
    pub fn new(timing: FlashTiming) -> Self {
        Self {
            config: REN,
            busy_until: 0,
            icachecnf: 0,
            ihit: 0,
            imiss: 0,
            partial_cfg: 0x0A,
            timing,
            buffered_line: None,
            cached: LineSet::default(),
        }
    }

    /// The time the current operation ends (0 when idle since power-on).
    pub const fn busy_until(&self) -> u64 {
        self.busy_until
    }

    /// Whether the instruction cache is on.
    pub const fn cache_enabled(&self) -> bool {
        self.icachecnf & 1 != 0
    }

    /// A register read.
    pub fn read(&self, offset: u32, now: u64) -> Option<u32> {
        Some(match offset {
            0x400 | 0x408 => u32::from(now >= self.busy_until),
            0x504 => self.config,
            0x51C => self.partial_cfg,
            0x540 => self.icachecnf,
            0x548 => self.ihit,
            0x54C => self.imiss,
            _ => return None,
        })
    }

    /// Starts an operation of `ns` after the current one.
    fn occupy(&mut self, now: u64, ns: u64) {
        self.busy_until = self.busy_until.max(now) + ns;
        // Writing or erasing invalidates the cache (PS "NVMC": CONFIG).
        self.cached.clear();
        self.buffered_line = None;
    }

    /// A register write. Returns `Some(changed)` when the offset is implemented, `changed`
    /// telling whether flash or UICR content changed.
    pub fn write(
        &mut self,
        offset: u32,
        value: u32,
        now: u64,
        flash: &mut Flash,
        uicr: &mut Uicr,
    ) -> Option<Result<bool, &'static str>> {
        let erase_enabled = self.config == EEN;
        Some(match offset {
            0x504 => {
                self.config = value & 3;
                if self.config != REN {
                    self.cached.clear();
                }
                Ok(false)
            }
            // ERASEPAGE / ERASEPCR1, and the deprecated ERASEPCR0.
            0x508 | 0x510 if !erase_enabled => Err("page erase without CONFIG.WEN = Een"),
            0x508 | 0x510 => {
                if !value.is_multiple_of(FLASH_PAGE) || !flash.erase_page(value) {
                    Err("page erase of an address that is no page start")
                } else {
                    self.occupy(now, ERASE_PAGE_NS);
                    Ok(true)
                }
            }
            0x50C | 0x514 if value & 1 == 0 => Ok(false),
            0x50C | 0x514 if !erase_enabled => Err("erase without CONFIG.WEN = Een"),
            0x50C => {
                flash.erase_all();
                uicr.erase();
                self.occupy(now, ERASE_ALL_NS);
                Ok(true)
            }
            0x514 => {
                uicr.erase();
                self.occupy(now, ERASE_PAGE_NS);
                Ok(true)
            }
            0x51C => {
                self.partial_cfg = value & 0x7F;
                Ok(false)
            }
            0x540 => {
                if value & 1 == 0 {
                    self.cached.clear();
                }
                self.icachecnf = value & 0x101;
                Ok(false)
            }
            0x548 => {
                self.ihit = value;
                Ok(false)
            }
            0x54C => {
                self.imiss = value;
                Ok(false)
            }
            _ => return None,
        })
    }

    /// A CPU store to flash or UICR: allowed (the word write occupies the NVMC) or why not.
    pub fn program(&mut self, now: u64, word_store: bool) -> Result<(), &'static str> {
        if self.config != WEN {
            return Err("store to flash without CONFIG.WEN = Wen");
        }
        if !word_store {
            return Err("flash store narrower than a word");
        }
        self.occupy(now, WRITE_NS);
        Ok(())
    }

    /// Stall cycles for an instruction fetched from flash at `addr`.
    #[inline]
    pub fn fetch_stall(&mut self, addr: u32) -> u32 {
        let bytes = self.timing.line_bytes.max(1);
        let line = if bytes.is_power_of_two() {
            addr >> bytes.trailing_zeros()
        } else {
            addr / bytes
        };
        if self.buffered_line == Some(line) {
            return 0;
        }
        self.fetch_new_line(line)
    }

    /// A fetch from another line than the buffered one.
    fn fetch_new_line(&mut self, line: u32) -> u32 {
        self.buffered_line = Some(line);
        if !self.cache_enabled() {
            return self.timing.wait_states;
        }
        let profiling = self.icachecnf & 0x100 != 0;
        if self.cached.insert(line) {
            if profiling {
                self.imiss = self.imiss.wrapping_add(1);
            }
            self.timing.wait_states
        } else {
            if profiling {
                self.ihit = self.ihit.wrapping_add(1);
            }
            0
        }
    }

    /// Reset state (an operation in progress completes: the NVMC is not reset mid-write).
    pub fn reset(&mut self) {
        let busy_until = self.busy_until;
        *self = Self::new(self.timing);
        self.busy_until = busy_until;
    }
}
