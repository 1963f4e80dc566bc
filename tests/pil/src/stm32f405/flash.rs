//! The flash interface (RM0090 §3): FLASH_ACR with the ART accelerator's cycle model, and
//! programming — unlock keys, CR (PG/SER/MER/SNB/PSIZE/STRT), SR flags and busy times.
//!
//! **ART cycle model** (RM0090 §3.4.2 "Adaptive real-time memory accelerator"): the flash
//! is read in 128-bit lines; a read the accelerator cannot serve costs LATENCY wait states.
//! Instruction fetches: within the line in use, free; a line held by the prefetch buffer
//! (PRFTEN: the next sequential line, fetched while the current one executes) costs what
//! the prefetch has not yet hidden, LATENCY + 1 minus the instructions executed from the
//! current line (each takes at least one cycle; an approximation of the bus timing); a line
//! in the 64-line instruction cache (ICEN, LRU replacement as §3.4.2 states) is free; any
//! other line is a miss (LATENCY cycles) and enters the I-cache. Data reads (literal pools,
//! constants) through the D-bus: a hit in the 8-line data cache (DCEN) is free, otherwise
//! LATENCY cycles and the line enters the D-cache. With PRFTEN/ICEN/DCEN off — the reset
//! state, and what embassy-stm32 0.6 leaves (`FLASH.acr().write(latency)`) — every line
//! change costs LATENCY cycles.
//!
//! **Programming times** (DS8626 "Flash memory programming", typical / maximum): a program
//! operation 16 / 100 µs for any parallelism; a sector erase at ×8, ×16, ×32 parallelism
//! (PSIZE): 16 KiB 400/800, 300/600, 250/500 ms; 64 KiB 1200/2400, 700/1400, 550/1100 ms;
//! 128 KiB 2000/4000, 1300/2600, 1000/2000 ms; mass erase 16/32, 11/22, 8/16 s (×64 is taken
//! as ×32: it needs VPP, which these boards do not have). The F405 has one bank: while BSY,
//! every instruction fetch and data read from flash stalls until the operation ends. The
//! content changes when the operation starts; a reset before its end leaves a torn sector
//! (the erased prefix in proportion to the time that passed, the rest as before).

use super::map::FLASH_SIZE;

// Registers (RM0090 §3.9).
const ACR: u32 = 0x00;
const KEYR: u32 = 0x04;
const OPTKEYR: u32 = 0x08;
const SR: u32 = 0x0C;
const CR: u32 = 0x10;
const OPTCR: u32 = 0x14;

const PRFTEN: u32 = 1 << 8;
const ICEN: u32 = 1 << 9;
const DCEN: u32 = 1 << 10;
const ICRST: u32 = 1 << 11;
const DCRST: u32 = 1 << 12;

const EOP: u32 = 1 << 0;
const OPERR: u32 = 1 << 1;
const WRPERR: u32 = 1 << 4;
const PGAERR: u32 = 1 << 5;
const PGPERR: u32 = 1 << 6;
const PGSERR: u32 = 1 << 7;
const SR_ERRORS: u32 = OPERR | WRPERR | PGAERR | PGPERR | PGSERR;
const BSY: u32 = 1 << 16;

const PG: u32 = 1 << 0;
const SER: u32 = 1 << 1;
const MER: u32 = 1 << 2;
const STRT: u32 = 1 << 16;
const EOPIE: u32 = 1 << 24;
const ERRIE: u32 = 1 << 25;
const LOCK: u32 = 1 << 31;

const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;
const OPTKEY1: u32 = 0x0819_2A3B;
const OPTKEY2: u32 = 0x4C5D_6E7F;

/// I-cache lines (RM0090 §3.4.2).
const ICACHE_LINES: usize = 64;
/// D-cache lines.
const DCACHE_LINES: usize = 8;

/// Which column of DS8626's programming table the model uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlashTiming {
    /// Typical figures.
    Typical,
    /// Maximum figures (a worn or hot part).
    Maximum,
}

/// Wait states HCLK needs at 2.7–3.6 V (RM0090 Table 10: one per 30 MHz).
pub fn required_latency(hclk: u32) -> u32 {
    hclk.saturating_sub(1) / 30_000_000
}

/// A fully associative cache of 128-bit line numbers with LRU replacement.
struct LineCache<const N: usize> {
    /// Line numbers, most recently used first; `u32::MAX` is empty.
    lines: [u32; N],
}

impl<const N: usize> LineCache<N> {
    const fn new() -> Self {
        Self {
            lines: [u32::MAX; N],
        }
    }

    /// Looks `line` up; a hit moves it to the front.
    fn hit(&mut self, line: u32) -> bool {
        match self.lines.iter().position(|&l| l == line) {
            Some(i) => {
                if let Some(s) = self.lines.get_mut(..=i) {
                    s.rotate_right(1);
                }
                true
            }
            None => false,
        }
    }

    /// Inserts `line`, evicting the least recently used.
    fn insert(&mut self, line: u32) {
        self.lines.rotate_right(1);
        if let Some(first) = self.lines.first_mut() {
            *first = line;
        }
    }

    fn clear(&mut self) {
        self.lines = [u32::MAX; N];
    }
}

/// A program or erase under way.
struct Operation {
    /// Flash offset and length the operation changes.
    start: usize,
    len: usize,
    /// The content before it, for a reset that tears it.
    before: Vec<u8>,
    started_ns: u64,
    erase: bool,
}

/// Counters for the cycle model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ArtStats {
    /// Instruction line changes.
    pub fetch_lines: u64,
    /// …served by the prefetch buffer.
    pub prefetch_hits: u64,
    /// …served by the I-cache.
    pub icache_hits: u64,
    /// …that missed.
    pub fetch_misses: u64,
    /// Data reads from flash.
    pub data_reads: u64,
    /// …served by the D-cache.
    pub dcache_hits: u64,
    /// Wait-state cycles charged to the core in total.
    pub stall_cycles: u64,
}

/// The flash interface.
pub struct FlashIf {
    acr: u32,
    sr: u32,
    cr: u32,
    optcr: u32,
    key_stage: u8,
    opt_key_stage: u8,
    /// A wrong key sequence locks CR until reset.
    key_error: bool,
    busy_until: u64,
    op: Option<Operation>,
    icache: LineCache<ICACHE_LINES>,
    dcache: LineCache<DCACHE_LINES>,
    current_line: u32,
    prefetched: u32,
    executed_in_line: u32,
    generation: u64,
    timing: FlashTiming,
    stats: ArtStats,
    /// The end of the last busy wait charged to the core.
    waited_until: u64,
    /// Erases started, oldest first.
    erases: Vec<Erase>,
}

/// An erase the firmware started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Erase {
    /// First byte erased, as a flash offset (0 = 0x0800_0000).
    pub offset: u32,
    /// Bytes erased.
    pub len: u32,
    /// When STRT was written, ns.
    pub started_ns: u64,
    /// When BSY clears, ns.
    pub ends_ns: u64,
}

/// What a flash-interface access did beyond its registers.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct FlashEffects {
    /// The access waits until the busy operation ends: ns of stall.
    pub stall_ns: u64,
    /// A rule break to record.
    pub violation: Option<&'static str>,
    /// Something written that the model ignores.
    pub unmodelled: Option<&'static str>,
    /// The access is a bus error (wrong unlock key).
    pub bus_error: bool,
}

impl FlashIf {
    /// Reset state: 0 wait states, accelerator off, CR locked.
    pub fn new(timing: FlashTiming) -> Self {
        Self {
            acr: 0,
            sr: 0,
            cr: LOCK,
            optcr: 0x0FFF_AAED,
            key_stage: 0,
            opt_key_stage: 0,
            key_error: false,
            busy_until: 0,
            op: None,
            icache: LineCache::new(),
            dcache: LineCache::new(),
            current_line: u32::MAX,
            prefetched: u32::MAX,
            executed_in_line: 0,
            generation: 0,
            timing,
            stats: ArtStats::default(),
            waited_until: 0,
            erases: Vec::new(),
        }
    }

    /// A system reset: registers to reset values; an operation under way is torn.
    pub fn reset(&mut self, flash: &mut [u8], now: u64) {
        if let Some(op) = self.op.take()
            && now < self.busy_until
        {
            tear(flash, &op, now, self.busy_until);
            self.generation += 1;
        }
        let (timing, generation, stats) = (self.timing, self.generation, self.stats);
        let erases = std::mem::take(&mut self.erases);
        *self = Self::new(timing);
        self.generation = generation;
        self.stats = stats;
        self.erases = erases;
    }

    /// The erases started since the model was made, oldest first (kept across resets).
    pub fn erases(&self) -> &[Erase] {
        &self.erases
    }

    /// Bumped whenever flash content changes.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Cycle-model counters.
    pub fn stats(&self) -> ArtStats {
        self.stats
    }

    /// The configured wait states.
    pub fn latency(&self) -> u32 {
        self.acr & 7
    }

    /// The time the current operation ends (0 when idle).
    pub fn busy_until(&self) -> u64 {
        if self.op.is_some() {
            self.busy_until
        } else {
            0
        }
    }

    /// Stall cycles for an instruction fetch at flash offset `offset`, at `now` (the
    /// latest time the SoC saw), with `hclk` for converting a busy wait.
    #[inline]
    pub fn fetch_stall(&mut self, offset: u32, now: u64, hclk: u32) -> u32 {
        let line = offset >> 4;
        if line == self.current_line {
            self.executed_in_line += 1;
            return 0;
        }
        self.fetch_new_line(line, now, hclk)
    }

    /// A fetch from another line than the last one's.
    fn fetch_new_line(&mut self, line: u32, now: u64, hclk: u32) -> u32 {
        let latency = self.latency();
        self.stats.fetch_lines += 1;
        let mut stall = if self.acr & PRFTEN != 0 && line == self.prefetched {
            self.stats.prefetch_hits += 1;
            (latency + 1).saturating_sub(self.executed_in_line)
        } else if self.acr & ICEN != 0 && self.icache.hit(line) {
            self.stats.icache_hits += 1;
            0
        } else {
            self.stats.fetch_misses += 1;
            if self.acr & ICEN != 0 {
                self.icache.insert(line);
            }
            latency
        };
        stall += self.busy_stall(now, hclk);
        self.current_line = line;
        self.executed_in_line = 1;
        self.prefetched = line.wrapping_add(1);
        self.stats.stall_cycles += u64::from(stall);
        stall
    }

    /// Stall cycles for a data read from flash offset `offset`.
    pub fn data_stall(&mut self, offset: u32, now: u64, hclk: u32) -> u32 {
        let line = offset >> 4;
        self.stats.data_reads += 1;
        let mut stall = if self.acr & DCEN != 0 && self.dcache.hit(line) {
            self.stats.dcache_hits += 1;
            0
        } else {
            if self.acr & DCEN != 0 {
                self.dcache.insert(line);
            }
            self.latency()
        };
        stall += self.busy_stall(now, hclk);
        self.stats.stall_cycles += u64::from(stall);
        stall
    }

    /// Cycles until the busy operation ends.
    fn busy_stall(&mut self, now: u64, hclk: u32) -> u32 {
        // `now` is the SoC's last known time; a stall already charged moved the core past it.
        let now = now.max(self.waited_until);
        if self.op.is_none() || now >= self.busy_until {
            return 0;
        }
        self.waited_until = self.busy_until;
        let ns = self.busy_until - now;
        u32::try_from(u128::from(ns) * u128::from(hclk) / 1_000_000_000).unwrap_or(u32::MAX)
    }

    /// The next time the interface changes by itself (an operation ending).
    pub fn next_event(&self) -> u64 {
        if self.op.is_some() {
            self.busy_until
        } else {
            u64::MAX
        }
    }

    /// Ends an operation due by `now`.
    pub fn process(&mut self, now: u64) {
        if self.op.is_some() && now >= self.busy_until {
            self.op = None;
            if self.cr & EOPIE != 0 && self.sr & SR_ERRORS == 0 {
                self.sr |= EOP;
            }
        }
    }

    /// The FLASH interrupt line (EOP with EOPIE, errors with ERRIE).
    pub fn irq(&self) -> bool {
        (self.sr & EOP != 0 && self.cr & EOPIE != 0)
            || (self.sr & SR_ERRORS != 0 && self.cr & ERRIE != 0)
    }

    /// Register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        Some(match offset {
            ACR => self.acr,
            KEYR | OPTKEYR => 0,
            SR => self.sr | if self.op.is_some() { BSY } else { 0 },
            CR => self.cr,
            OPTCR => self.optcr,
            _ => return None,
        })
    }

    /// Register write at `now`.
    pub fn write(
        &mut self,
        offset: u32,
        value: u32,
        flash: &mut [u8],
        now: u64,
    ) -> Option<FlashEffects> {
        let mut fx = FlashEffects::default();
        match offset {
            ACR => {
                if value & ICRST != 0 {
                    if self.acr & ICEN != 0 || value & ICEN != 0 {
                        fx.violation = Some(
                            "FLASH_ACR.ICRST with the I-cache enabled (RM0090 §3.9.1: only while ICEN = 0)",
                        );
                    } else {
                        self.icache.clear();
                    }
                }
                if value & DCRST != 0 {
                    if self.acr & DCEN != 0 || value & DCEN != 0 {
                        fx.violation = Some(
                            "FLASH_ACR.DCRST with the D-cache enabled (RM0090 §3.9.1: only while DCEN = 0)",
                        );
                    } else {
                        self.dcache.clear();
                    }
                }
                self.acr = value & (7 | PRFTEN | ICEN | DCEN | ICRST | DCRST);
            }
            KEYR => self.write_key(value, &mut fx),
            OPTKEYR => match (self.opt_key_stage, value) {
                (0, OPTKEY1) => self.opt_key_stage = 1,
                (1, OPTKEY2) => {
                    self.opt_key_stage = 0;
                    self.optcr &= !1;
                }
                _ => {
                    self.opt_key_stage = 0;
                    fx.bus_error = true;
                }
            },
            SR => self.sr &= !(value & (EOP | SR_ERRORS)),
            CR => {
                fx.stall_ns = self.wait_idle(now);
                let at = now + fx.stall_ns;
                self.process(at);
                if self.cr & LOCK != 0 {
                    // Locked: only LOCK itself can be written (to 1), the rest is ignored.
                    return Some(fx);
                }
                self.cr = value & (PG | SER | MER | 0x78 | 0x300 | EOPIE | ERRIE | LOCK);
                if value & STRT != 0 {
                    self.start_erase(flash, at, &mut fx);
                }
            }
            OPTCR => {
                if self.optcr & 1 == 0 {
                    fx.unmodelled = Some("FLASH_OPTCR option byte programming");
                    self.optcr = (self.optcr & !1) | (value & 1);
                }
            }
            _ => return None,
        }
        Some(fx)
    }

    fn write_key(&mut self, value: u32, fx: &mut FlashEffects) {
        if self.key_error {
            fx.bus_error = true;
            return;
        }
        match (self.key_stage, value) {
            (0, KEY1) => self.key_stage = 1,
            (1, KEY2) => {
                self.key_stage = 0;
                self.cr &= !LOCK;
            }
            _ => {
                // RM0090 §3.5.1: a wrong sequence is a bus error and locks CR until reset.
                self.key_stage = 0;
                self.key_error = true;
                fx.bus_error = true;
            }
        }
    }

    /// Time until the running operation ends (an access that must wait for it).
    fn wait_idle(&self, now: u64) -> u64 {
        if self.op.is_some() {
            self.busy_until.saturating_sub(now)
        } else {
            0
        }
    }

    fn parallelism(&self) -> usize {
        ((self.cr >> 8) & 3) as usize
    }

    fn start_erase(&mut self, flash: &mut [u8], now: u64, fx: &mut FlashEffects) {
        let (start, len, ms) = if self.cr & MER != 0 && self.cr & SER != 0 {
            // RM0090 §3.5.3: with MER and SER both set, nothing is erased.
            self.sr |= PGSERR;
            return;
        } else if self.cr & MER != 0 {
            let ms = [
                [16_000, 32_000],
                [11_000, 22_000],
                [8_000, 16_000],
                [8_000, 16_000],
            ];
            (0, FLASH_SIZE as usize, self.pick(&ms))
        } else if self.cr & SER != 0 {
            let snb = ((self.cr >> 3) & 0xF) as usize;
            let Some((start, len)) = sector(snb) else {
                fx.violation = Some("FLASH_CR.SNB names no sector of a 1 MiB F405");
                self.sr |= PGSERR;
                return;
            };
            let ms = match len {
                0x4000 => [[400, 800], [300, 600], [250, 500], [250, 500]],
                0x1_0000 => [[1200, 2400], [700, 1400], [550, 1100], [550, 1100]],
                _ => [[2000, 4000], [1300, 2600], [1000, 2000], [1000, 2000]],
            };
            (start, len, self.pick(&ms))
        } else {
            self.sr |= PGSERR;
            return;
        };
        let Some(area) = flash.get_mut(start..start + len) else {
            return;
        };
        let before = area.to_vec();
        area.fill(0xFF);
        self.op = Some(Operation {
            start,
            len,
            before,
            started_ns: now,
            erase: true,
        });
        self.busy_until = now + ms * 1_000_000;
        self.generation += 1;
        self.erases.push(Erase {
            offset: start as u32,
            len: len as u32,
            started_ns: now,
            ends_ns: self.busy_until,
        });
    }

    fn pick(&self, table: &[[u64; 2]; 4]) -> u64 {
        let row = table.get(self.parallelism()).copied().unwrap_or([0, 0]);
        match self.timing {
            FlashTiming::Typical => row[0],
            FlashTiming::Maximum => row[1],
        }
    }

    /// A CPU store of `width` bytes to flash offset `offset`: programs it if PG is set.
    pub fn program(
        &mut self,
        flash: &mut [u8],
        offset: u32,
        width: u32,
        value: u32,
        now: u64,
    ) -> FlashEffects {
        let mut fx = FlashEffects {
            stall_ns: self.wait_idle(now),
            ..FlashEffects::default()
        };
        let at = now + fx.stall_ns;
        self.process(at);
        if self.cr & LOCK != 0 || self.cr & PG == 0 {
            // RM0090 §3.9.4: a write to flash without a correct programming set-up.
            self.sr |= PGSERR;
            fx.violation = Some("store to flash without FLASH_CR.PG (programming sequence error)");
            return fx;
        }
        let psize_bytes = 1u32 << self.parallelism();
        if width != psize_bytes.min(4) {
            self.sr |= PGPERR;
            return fx;
        }
        if !offset.is_multiple_of(width) {
            self.sr |= PGAERR;
            return fx;
        }
        let start = offset as usize;
        let Some(cells) = flash.get_mut(start..start + width as usize) else {
            return fx;
        };
        let before = cells.to_vec();
        for (i, c) in cells.iter_mut().enumerate() {
            // Programming can only clear bits (RM0090 §3.5.4).
            *c &= (value >> (8 * i)) as u8;
        }
        let prog_ns = match self.timing {
            FlashTiming::Typical => 16_000,
            FlashTiming::Maximum => 100_000,
        };
        self.op = Some(Operation {
            start,
            len: width as usize,
            before,
            started_ns: at,
            erase: false,
        });
        self.busy_until = at + prog_ns;
        self.generation += 1;
        fx
    }

    /// Whether a check of LATENCY against `hclk` fails (too few wait states).
    pub fn latency_too_low(&self, hclk: u32) -> bool {
        self.latency() < required_latency(hclk)
    }
}

/// Sector `snb`'s offset and length (RM0090 Table 5).
fn sector(snb: usize) -> Option<(usize, usize)> {
    match snb {
        0..=3 => Some((snb * 0x4000, 0x4000)),
        4 => Some((0x1_0000, 0x1_0000)),
        5..=11 => Some((0x2_0000 * (snb - 4), 0x2_0000)),
        _ => None,
    }
}

/// A reset during an operation: the erased (or programmed) prefix in proportion to the
/// time that passed, the old content after it.
fn tear(flash: &mut [u8], op: &Operation, now: u64, until: u64) {
    let total = until.saturating_sub(op.started_ns).max(1);
    let done = now.saturating_sub(op.started_ns).min(total);
    let keep_from = if op.erase {
        (op.len as u128 * u128::from(done) / u128::from(total)) as usize
    } else {
        0
    };
    if let (Some(area), Some(old)) = (
        flash.get_mut(op.start + keep_from..op.start + op.len),
        op.before.get(keep_from..),
    ) {
        area.copy_from_slice(old);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unlocked() -> FlashIf {
        let mut f = FlashIf::new(FlashTiming::Typical);
        let mut flash = vec![];
        f.write(KEYR, KEY1, &mut flash, 0);
        f.write(KEYR, KEY2, &mut flash, 0);
        assert_eq!(f.read(CR).unwrap() & LOCK, 0);
        f
    }

    #[test]
    fn without_the_accelerator_every_line_change_costs_the_wait_states() {
        let mut f = FlashIf::new(FlashTiming::Typical);
        let mut flash = vec![];
        f.write(ACR, 5, &mut flash, 0);
        // 8 halfword instructions per line, straight-line code over 4 lines.
        let stalls: Vec<u32> = (0..32)
            .map(|i| f.fetch_stall(i * 2, 0, 168_000_000))
            .collect();
        assert_eq!(stalls.iter().sum::<u32>(), 4 * 5);
        assert_eq!(stalls[0], 5);
        assert_eq!(stalls[1], 0);
        assert_eq!(stalls[8], 5);
    }

    #[test]
    fn prefetch_hides_sequential_lines_and_the_icache_serves_loops() {
        let mut f = FlashIf::new(FlashTiming::Typical);
        let mut flash = vec![];
        f.write(ACR, 5 | PRFTEN | ICEN | DCEN, &mut flash, 0);
        // First line: miss. Next lines after 8 instructions each: fully hidden (8 ≥ 6).
        let first: u32 = (0..32).map(|i| f.fetch_stall(i * 2, 0, 168_000_000)).sum();
        assert_eq!(first, 5);
        // Short lines (4 instructions of 32 bits): 6 - 4 = 2 cycles each after the first.
        let mut g = FlashIf::new(FlashTiming::Typical);
        g.write(ACR, 5 | PRFTEN, &mut flash, 0);
        let short: u32 = (0..16)
            .map(|i| g.fetch_stall(0x1000 + i * 4, 0, 168_000_000))
            .sum();
        assert_eq!(short, 5 + 3 * 2);
        // A loop over 3 lines: after the first pass everything is in the I-cache.
        let mut h = FlashIf::new(FlashTiming::Typical);
        h.write(ACR, 5 | ICEN, &mut flash, 0);
        let pass = |h: &mut FlashIf| -> u32 { (0..24).map(|i| h.fetch_stall(i * 2, 0, 1)).sum() };
        assert_eq!(pass(&mut h), 15);
        assert_eq!(pass(&mut h), 0);
        assert_eq!(h.stats().icache_hits, 3);
    }

    #[test]
    fn the_icache_is_64_lines_lru_and_the_dcache_8() {
        let mut f = FlashIf::new(FlashTiming::Typical);
        let mut flash = vec![];
        f.write(ACR, 3 | ICEN | DCEN, &mut flash, 0);
        for line in 0..65u32 {
            f.fetch_stall(line * 16, 0, 1);
        }
        // Line 0 was evicted by the 65th, line 1 is still there.
        f.fetch_stall(16, 0, 1);
        assert_eq!(f.stats().icache_hits, 1);
        assert_eq!(f.fetch_stall(0, 0, 1), 3);
        for line in 0..8u32 {
            assert_eq!(f.data_stall(0x8000 + line * 16, 0, 1), 3);
        }
        assert_eq!(f.data_stall(0x8004, 0, 1), 0);
        assert_eq!(f.data_stall(0x9000, 0, 1), 3);
    }

    #[test]
    fn a_sector_erase_stalls_fetches_for_the_datasheet_time_at_the_psize_used() {
        let mut f = unlocked();
        let mut flash = vec![0u8; FLASH_SIZE as usize];
        // embassy's blocking erase leaves PSIZE at its reset value, ×8: 400 ms for 16 KiB.
        f.write(CR, SER | 2 << 3, &mut flash, 1_000);
        f.write(CR, SER | 2 << 3 | STRT, &mut flash, 1_000);
        assert_eq!(f.read(SR).unwrap() & BSY, BSY);
        assert!(flash[0x8000..0xC000].iter().all(|&b| b == 0xFF));
        assert_eq!(flash[0xC000], 0);
        assert_eq!(f.busy_until(), 1_000 + 400_000_000);
        // A fetch 100 ms in waits 300 ms at 168 MHz; the next line, fetched after that wait
        // (the SoC's clock has not moved yet), waits no more.
        let stall = f.fetch_stall(0x1_0000, 100_001_000, 168_000_000);
        assert_eq!(stall, 300 * 168_000);
        assert_eq!(f.fetch_stall(0x1_0010, 100_001_000, 168_000_000), 0);
        f.process(400_001_000);
        assert_eq!(f.read(SR).unwrap() & (BSY | EOP), 0, "EOP only with EOPIE");
        // At ×32 the same sector takes 250 ms.
        f.write(
            CR,
            SER | 2 << 3 | 2 << 8 | STRT | EOPIE,
            &mut flash,
            500_000_000,
        );
        assert_eq!(f.busy_until(), 750_000_000);
        f.process(750_000_000);
        assert_eq!(f.read(SR).unwrap() & EOP, EOP);
        assert!(f.irq());
        f.write(SR, EOP, &mut flash, 750_000_000);
        assert!(!f.irq());
    }

    #[test]
    fn programming_clears_bits_only_and_checks_parallelism() {
        let mut f = unlocked();
        let mut flash = vec![0xF0u8; 64];
        f.write(CR, PG | 2 << 8, &mut flash, 0);
        let fx = f.program(&mut flash, 8, 4, 0x0F0F_3C3C, 0);
        assert_eq!(fx.stall_ns, 0);
        assert_eq!(&flash[8..12], &[0x30, 0x30, 0x00, 0x00]);
        assert_eq!(f.busy_until(), 16_000);
        // A second store while busy waits for the first.
        let fx = f.program(&mut flash, 12, 4, 0, 4_000);
        assert_eq!(fx.stall_ns, 12_000);
        // Halfword with PSIZE ×32: PGPERR, nothing written.
        f.process(1_000_000);
        f.program(&mut flash, 16, 2, 0, 1_000_000);
        assert_eq!(f.read(SR).unwrap() & PGPERR, PGPERR);
        assert_eq!(flash[16], 0xF0);
    }

    #[test]
    fn a_wrong_key_is_a_bus_error_and_locks_until_reset() {
        let mut f = FlashIf::new(FlashTiming::Typical);
        let mut flash = vec![0u8; 16];
        assert!(f.write(KEYR, 0x1234, &mut flash, 0).unwrap().bus_error);
        f.write(KEYR, KEY1, &mut flash, 0);
        assert!(f.write(KEYR, KEY2, &mut flash, 0).unwrap().bus_error);
        assert_eq!(f.read(CR).unwrap() & LOCK, LOCK);
        f.reset(&mut flash, 0);
        f.write(KEYR, KEY1, &mut flash, 0);
        f.write(KEYR, KEY2, &mut flash, 0);
        assert_eq!(f.read(CR).unwrap() & LOCK, 0);
    }

    #[test]
    fn a_reset_mid_erase_tears_the_sector() {
        let mut f = unlocked();
        let mut flash = vec![0u8; FLASH_SIZE as usize];
        f.write(CR, SER | 2 << 8 | STRT, &mut flash, 0);
        f.reset(&mut flash, 62_500_000); // a quarter of 250 ms
        assert!(flash[..0x1000].iter().all(|&b| b == 0xFF));
        assert!(flash[0x1000..0x4000].iter().all(|&b| b == 0));
        assert_eq!(f.read(CR).unwrap() & LOCK, LOCK);
    }
}
