//! The flight log on a NOR flash (the Sparky2's M25P16 log area), sans-IO: the store says
//! which page to program or which sector to erase next and the caller's flash task does it
//! when the shared bus is free (between radio slots), then reports it done.
//!
//! Each page is self-describing — magic, log number, page number in the log, payload length
//! and a CRC over all of them — and pages are only ever programmed once after an erase, in
//! order. So a power cut while programming spoils at most that page (its CRC fails, the
//! reader skips it) and never touches an earlier one; the next boot starts a new log after
//! the newest valid page. Sectors are erased ahead of time: the next one as soon as less
//! than a sector's worth of erased pages is left, so in flight ([`LogStore::next_op`]'s
//! `armed`) the log never runs out of erased room, and an erase with no room left happens
//! only on the ground. The oldest data is erased first (the area is a ring); the current
//! log never.

/// Bytes of a flash page (the M25P16's program unit).
pub const PAGE: usize = 256;
/// A page's header: magic (2), log number (2), page number (4), payload length (2), CRC (2).
pub const HEADER: usize = 12;
/// Log bytes a page carries.
pub const PAYLOAD: usize = PAGE - HEADER;
/// What starts every log page.
const MAGIC: [u8; 2] = *b"TL";

/// Where the log area is and how the flash is cut up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Geometry {
    /// The area's first byte address (sector-aligned).
    pub start: u32,
    /// Bytes of an erase sector (a multiple of [`PAGE`]).
    pub sector: u32,
    /// Sectors in the area (at least two).
    pub sectors: u32,
}

impl Geometry {
    /// Sectors 16–31 of the Sparky2's M25P16 (64 KiB each), [`super::SPARKY2_LOG_AREA_BYTES`].
    pub const SPARKY2: Geometry = Geometry {
        start: 16 * 65_536,
        sector: 65_536,
        sectors: super::SPARKY2_LOG_AREA_BYTES / 65_536,
    };

    fn pages_per_sector(&self) -> u32 {
        self.sector / PAGE as u32
    }

    /// Pages in the area.
    pub fn pages(&self) -> u32 {
        self.pages_per_sector() * self.sectors
    }

    /// The address of page `index` of the area.
    pub fn address(&self, index: u32) -> u32 {
        self.start + (index % self.pages()) * PAGE as u32
    }
}

/// A valid page's header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PageHeader {
    /// The log (one per boot, counting up).
    pub log: u16,
    /// The page's number in its log, from 0.
    pub seq: u32,
    /// Payload bytes used.
    pub len: u16,
}

impl PageHeader {
    /// The header of a page whose magic, length and CRC hold, else `None` (erased, cut while
    /// programming, or not a log page).
    pub fn parse(page: &[u8; PAGE]) -> Option<Self> {
        let (head, payload) = page.split_first_chunk::<HEADER>()?;
        let [m0, m1, l0, l1, s0, s1, s2, s3, n0, n1, c0, c1] = *head;
        let len = u16::from_le_bytes([n0, n1]);
        let used = payload.get(..usize::from(len))?;
        let ok = [m0, m1] == MAGIC && u16::from_le_bytes([c0, c1]) == page_crc(head, used);
        ok.then_some(Self {
            log: u16::from_le_bytes([l0, l1]),
            seq: u32::from_le_bytes([s0, s1, s2, s3]),
            len,
        })
    }

    /// Its payload in `page`.
    pub fn payload<'p>(&self, page: &'p [u8; PAGE]) -> &'p [u8] {
        page.get(HEADER..HEADER + usize::from(self.len))
            .unwrap_or(&[])
    }
}

fn page_crc(head: &[u8; HEADER], payload: &[u8]) -> u16 {
    let mut digest = telemetry::checksum::CHIP_CRC.digest();
    digest.update(head.get(..10).unwrap_or(&[]));
    digest.update(payload);
    digest.finalize()
}

/// What the caller's flash task does next.
#[derive(Debug, PartialEq, Eq)]
pub enum Op<'a> {
    /// Program this page at `addr` (one page program).
    Program {
        /// Byte address.
        addr: u32,
        /// The page.
        page: &'a [u8; PAGE],
    },
    /// Erase the sector at `addr`.
    Erase {
        /// Byte address (sector-aligned).
        addr: u32,
    },
}

/// What the store found on the flash at boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mounted {
    /// The newest log found (`None`: no log on the flash).
    pub newest: Option<u16>,
    /// Pages that hold data of some log.
    pub valid_pages: u32,
}

/// The log area's writer.
#[derive(Debug, Clone)]
pub struct LogStore {
    geo: Geometry,
    /// This boot's log number.
    log: u16,
    /// The next page this log programs (area index, not wrapped).
    head: u32,
    /// The page this log began at.
    log_start: u32,
    /// Erased pages from `head` on (the run ends on a sector boundary).
    erased_ahead: u32,
    /// Pages written in this log.
    seq: u32,
    page: [u8; PAGE],
    fill: usize,
    /// The page buffer is closed and waits for its program.
    sealed: bool,
}

impl LogStore {
    /// Scans the area through `read` (address, buffer) and opens a new log after the newest
    /// valid page.
    pub fn mount(geo: Geometry, mut read: impl FnMut(u32, &mut [u8])) -> (Self, Mounted) {
        let total = geo.pages();
        let mut newest: Option<(u16, u32, u32)> = None;
        let mut valid_pages = 0;
        let mut page = [0xFF; PAGE];
        for i in 0..total {
            read(geo.address(i), &mut page);
            if let Some(h) = PageHeader::parse(&page) {
                valid_pages += 1;
                if newest.is_none_or(|(log, seq, _)| (h.log, h.seq) > (log, seq)) {
                    newest = Some((h.log, h.seq, i));
                }
            }
        }
        let pps = geo.pages_per_sector();
        let mut head = newest.map_or(0, |(_, _, i)| i + 1) % total;
        let mut erased = |i: u32, page: &mut [u8; PAGE]| {
            read(geo.address(i), page);
            page.iter().all(|b| *b == 0xFF)
        };
        // The rest of the head's sector must be erased, else the log starts at the next one.
        if (head..head.next_multiple_of(pps)).any(|i| !erased(i, &mut page)) {
            head = head.next_multiple_of(pps) % total;
        }
        // The rest of the head's sector (checked above), then every whole erased sector.
        let mut erased_ahead = head.next_multiple_of(pps) - head;
        while erased_ahead < total && (0..pps).all(|k| erased(head + erased_ahead + k, &mut page)) {
            erased_ahead += pps;
        }
        let store = Self {
            geo,
            log: newest.map_or(0, |(log, _, _)| log.wrapping_add(1)),
            head,
            log_start: head,
            erased_ahead,
            seq: 0,
            page: [0xFF; PAGE],
            fill: 0,
            sealed: false,
        };
        let mounted = Mounted {
            newest: newest.map(|(log, _, _)| log),
            valid_pages,
        };
        (store, mounted)
    }

    /// This boot's log number.
    pub fn log(&self) -> u16 {
        self.log
    }

    /// Log bytes the store can take before it must program (0: a page waits for its program,
    /// or the erased space is used up).
    pub fn room(&self) -> usize {
        if self.sealed || self.erased_ahead == 0 {
            0
        } else {
            PAYLOAD - self.fill
        }
    }

    /// Takes what fits of `bytes` into the page being filled; a full page is sealed for
    /// programming. Returns the bytes taken.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        let n = self.room().min(bytes.len());
        let at = HEADER + self.fill;
        if let (Some(dst), Some(src)) = (self.page.get_mut(at..at + n), bytes.get(..n)) {
            dst.copy_from_slice(src);
            self.fill += n;
        }
        if self.fill == PAYLOAD {
            self.seal();
        }
        n
    }

    /// Seals a partly filled page (on disarming: what is logged reaches the flash).
    pub fn flush(&mut self) {
        if self.fill > 0 && !self.sealed {
            self.seal();
        }
    }

    fn seal(&mut self) {
        let [l0, l1] = self.log.to_le_bytes();
        let [s0, s1, s2, s3] = self.seq.to_le_bytes();
        let [n0, n1] = (self.fill as u16).to_le_bytes();
        let mut head = [MAGIC[0], MAGIC[1], l0, l1, s0, s1, s2, s3, n0, n1, 0, 0];
        let used = self.page.get(HEADER..HEADER + self.fill).unwrap_or(&[]);
        let [c0, c1] = page_crc(&head, used).to_le_bytes();
        head[10] = c0;
        head[11] = c1;
        if let Some(dst) = self.page.get_mut(..HEADER) {
            dst.copy_from_slice(&head);
        }
        self.sealed = true;
    }

    /// The flash operation due, if any: the erase of the sector after the erased run when it
    /// is due (`armed`: the motors may turn), else a sealed page's program.
    pub fn next_op(&self, armed: bool) -> Option<Op<'_>> {
        if self.erase_due(armed) {
            return Some(Op::Erase {
                addr: self.geo.address(self.head + self.erased_ahead),
            });
        }
        (self.sealed && self.erased_ahead > 0).then(|| Op::Program {
            addr: self.geo.address(self.head),
            page: &self.page,
        })
    }

    /// Whether the sector after the erased run is erased now: when less than a sector is
    /// left erased, so the log never runs out of erased room (an M25P16 sector erase takes
    /// up to 3 s, a sector holds 19 s of the `flight` profile; the ring holds the entries
    /// meanwhile) — in flight only then, with room still left; on the ground also when none
    /// is left. Never the sectors of this log.
    fn erase_due(&self, armed: bool) -> bool {
        let pps = self.geo.pages_per_sector();
        // From the start of this log's first sector to the end of the sector to erase.
        let span = self.log_start % pps + self.seq + self.erased_ahead + pps;
        self.erased_ahead < pps && (!armed || self.erased_ahead > 0) && span <= self.geo.pages()
    }

    /// The operation [`Self::next_op`] returned has completed.
    pub fn done(&mut self, op_was_program: bool) {
        if op_was_program {
            self.head = (self.head + 1) % self.geo.pages();
            self.erased_ahead = self.erased_ahead.saturating_sub(1);
            self.seq += 1;
            self.page = [0xFF; PAGE];
            self.fill = 0;
            self.sealed = false;
        } else {
            self.erased_ahead += self.geo.pages_per_sector();
        }
    }
}

#[cfg(test)]
mod tests;
