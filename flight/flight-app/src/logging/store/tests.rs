//! The log store on a simulated NOR flash (programs only clear bits, erases set a sector to
//! 0xFF), with a power cut at every step of a write: the step's program or erase is left
//! half done, the board boots again, and every earlier page must still read back.

use std::collections::BTreeMap;

use super::*;

/// A small area: 4 sectors of 4 pages.
const GEO: Geometry = Geometry {
    start: 0x1000,
    sector: 4 * PAGE as u32,
    sectors: 4,
};

#[derive(Clone)]
struct Flash {
    bytes: Vec<u8>,
}

impl Flash {
    fn new() -> Self {
        Self {
            bytes: vec![0xFF; (GEO.sector * GEO.sectors) as usize],
        }
    }
    fn at(addr: u32) -> usize {
        (addr - GEO.start) as usize
    }
    fn read(&self, addr: u32, buf: &mut [u8]) {
        let a = Self::at(addr);
        buf.copy_from_slice(&self.bytes[a..a + buf.len()]);
    }
    /// Programs the first `upto` bytes of `page` (a cut after them).
    fn program(&mut self, addr: u32, page: &[u8; PAGE], upto: usize) {
        let a = Self::at(addr);
        for (d, s) in self.bytes[a..a + upto].iter_mut().zip(page) {
            *d &= *s;
        }
    }
    /// Erases every `stride`-th byte of the sector (a cut part-way: the rest keeps its
    /// bits).
    fn erase(&mut self, addr: u32, stride: usize) {
        let a = Self::at(addr);
        if stride == 0 {
            return; // cut before it began
        }
        for b in self.bytes[a..a + GEO.sector as usize]
            .iter_mut()
            .step_by(stride)
        {
            *b = 0xFF;
        }
    }
    fn page(&self, index: u32) -> [u8; PAGE] {
        let mut p = [0; PAGE];
        self.read(GEO.address(index), &mut p);
        p
    }
    fn mount(&self) -> (LogStore, Mounted) {
        LogStore::mount(GEO, |addr, buf| self.read(addr, buf))
    }
    /// Every log's bytes, pages in order.
    fn logs(&self) -> BTreeMap<u16, Vec<(u32, Vec<u8>)>> {
        let mut logs: BTreeMap<u16, Vec<(u32, Vec<u8>)>> = BTreeMap::new();
        for i in 0..GEO.pages() {
            let p = self.page(i);
            if let Some(h) = PageHeader::parse(&p) {
                logs.entry(h.log)
                    .or_default()
                    .push((h.seq, h.payload(&p).to_vec()));
            }
        }
        for pages in logs.values_mut() {
            pages.sort();
        }
        logs
    }
}

/// A cut: during the `step`-th operation (0-based), how much of it is done.
#[derive(Clone, Copy, Debug)]
struct Cut {
    step: usize,
    /// Bytes programmed of a page, or the stride of an erase's bytes reset.
    part: usize,
}

/// What the flash must hold: every page whose program completed and whose sector was not
/// erased since, by area index.
type Model = BTreeMap<u32, [u8; PAGE]>;

/// Writes `data` as one boot's log (armed or not), performing the store's operations until
/// everything is on the flash or `cut` stops the board. Returns whether the cut struck.
fn write_log(
    flash: &mut Flash,
    model: &mut Model,
    data: &[u8],
    armed: bool,
    cut: Option<Cut>,
    step: &mut usize,
) -> bool {
    let (mut store, _) = flash.mount();
    let mut rest = data;
    loop {
        let n = store.push(rest);
        rest = &rest[n..];
        if rest.is_empty() {
            store.flush();
        }
        let Some(op) = store.next_op(armed) else {
            if rest.is_empty() || store.room() == 0 {
                return false; // written, or the erased space is used up in flight
            }
            continue;
        };
        let struck = cut.filter(|c| c.step == *step);
        *step += 1;
        let program = matches!(op, Op::Program { .. });
        match op {
            Op::Program { addr, page } => {
                let page = *page;
                let index = (addr - GEO.start) / PAGE as u32;
                flash.program(addr, &page, struck.map_or(PAGE, |c| c.part));
                if struck.is_none() {
                    model.insert(index, page);
                }
            }
            Op::Erase { addr } => {
                assert!(
                    !armed || store.erased_ahead > 0,
                    "in flight only ahead of time"
                );
                let first = (addr - GEO.start) / PAGE as u32;
                let pps = GEO.sector / PAGE as u32;
                model.retain(|i, _| !(first..first + pps).contains(i));
                flash.erase(addr, struck.map_or(1, |c| c.part));
            }
        }
        if struck.is_some() {
            return true;
        }
        store.done(program);
    }
}

/// Every page the model holds reads back as written, and every valid page is one the model
/// holds or the page the cut struck.
fn check(flash: &Flash, model: &Model, context: &str) {
    for (i, want) in model {
        assert_eq!(&flash.page(*i), want, "{context}: page {i} lost");
    }
    for i in 0..GEO.pages() {
        let p = flash.page(i);
        if PageHeader::parse(&p).is_some() && !model.contains_key(&i) {
            // Only a page programmed in full but cut before `done` can be valid unmodelled.
            assert!(p.iter().any(|b| *b != 0xFF), "{context}");
        }
    }
}

fn pattern(seed: u8, len: usize) -> Vec<u8> {
    (0..len)
        .map(|i| seed.wrapping_mul(31).wrapping_add(i as u8))
        .collect()
}

#[test]
fn a_log_reads_back_as_written_and_each_boot_opens_the_next() {
    let mut flash = Flash::new();
    let mut model = Model::new();
    let mut step = 0;
    let a = pattern(1, 3 * PAYLOAD + 17);
    assert!(!write_log(
        &mut flash, &mut model, &a, false, None, &mut step
    ));
    let b = pattern(2, PAYLOAD);
    assert!(!write_log(
        &mut flash, &mut model, &b, false, None, &mut step
    ));
    let logs = flash.logs();
    let joined = |log: u16| -> Vec<u8> { logs[&log].iter().flat_map(|p| p.1.clone()).collect() };
    assert_eq!(joined(0), a);
    assert_eq!(joined(1), b);
    assert_eq!(logs[&0].len(), 4, "three full pages and the flushed rest");
    let (store, mounted) = flash.mount();
    assert_eq!(mounted.newest, Some(1));
    assert_eq!(mounted.valid_pages, 5);
    assert_eq!(store.log(), 2);
}

#[test]
fn in_flight_erases_come_ahead_of_time_and_take_the_oldest_sectors() {
    let mut flash = Flash::new();
    let mut model = Model::new();
    let mut step = 0;
    let a = pattern(1, 14 * PAYLOAD);
    write_log(&mut flash, &mut model, &a, false, None, &mut step);
    let b = pattern(2, 10 * PAYLOAD);
    write_log(&mut flash, &mut model, &b, true, None, &mut step);
    let logs = flash.logs();
    assert_eq!(logs[&1].len(), 10, "the flight log is whole");
    // It took pages 14, 15, 0–7: sectors 0–2 were erased ahead, sector 3 is left.
    let kept: Vec<u32> = logs[&0].iter().map(|p| p.0).collect();
    assert_eq!(kept, [12, 13]);
    check(&flash, &model, "flight");
}

#[test]
fn in_flight_without_erased_room_nothing_is_erased_on_the_ground_it_is() {
    let mut flash = Flash::new();
    let mut model = Model::new();
    let mut step = 0;
    // One log over the whole area: the next one starts on a written sector.
    write_log(
        &mut flash,
        &mut model,
        &pattern(1, 16 * PAYLOAD),
        false,
        None,
        &mut step,
    );
    let before = flash.bytes.clone();
    let flown = write_log(
        &mut flash,
        &mut model,
        &pattern(2, PAYLOAD),
        true,
        None,
        &mut step,
    );
    assert!(!flown);
    assert_eq!(
        flash.bytes, before,
        "no erase that a page would wait for, in flight"
    );
    write_log(
        &mut flash,
        &mut model,
        &pattern(3, PAYLOAD),
        false,
        None,
        &mut step,
    );
    let logs = flash.logs();
    assert_eq!(
        logs[&1].len(),
        1,
        "on the ground the oldest sector is erased"
    );
    // And the next, to keep a sector's worth erased ahead.
    assert_eq!(logs[&0].len(), 8);
}

#[test]
fn a_log_longer_than_the_area_stops_before_its_own_start() {
    let mut flash = Flash::new();
    let mut model = Model::new();
    let mut step = 0;
    let a = pattern(1, 40 * PAYLOAD);
    write_log(&mut flash, &mut model, &a, false, None, &mut step);
    let logs = flash.logs();
    let pages: Vec<u32> = logs[&0].iter().map(|p| p.0).collect();
    assert_eq!(
        pages,
        (0..16).collect::<Vec<_>>(),
        "the whole area, nothing overwritten"
    );
}

#[test]
fn a_power_cut_at_every_step_loses_at_most_the_page_being_written() {
    let earlier = pattern(7, 9 * PAYLOAD + 5);
    let flown = pattern(8, 12 * PAYLOAD + 100);
    let next = pattern(9, 3 * PAYLOAD);
    // Every step of the second log's writing (programs and the erases it needs), each cut
    // at several points of the operation.
    let steps = {
        let (mut flash, mut model, mut step) = (Flash::new(), Model::new(), 0);
        write_log(&mut flash, &mut model, &earlier, false, None, &mut step);
        let before = step;
        write_log(&mut flash, &mut model, &flown, false, None, &mut step);
        before..step
    };
    assert!(steps.len() > 12, "{steps:?}");
    let mut cuts = 0;
    for s in steps {
        for part in [0, 1, HEADER, 100, PAGE - 1] {
            let (mut flash, mut model, mut step) = (Flash::new(), Model::new(), 0);
            write_log(&mut flash, &mut model, &earlier, false, None, &mut step);
            let cut = Cut { step: s, part };
            let struck = write_log(&mut flash, &mut model, &flown, false, Some(cut), &mut step);
            assert!(struck, "{cut:?}");
            cuts += 1;
            let context = format!("cut {cut:?}");
            check(&flash, &model, &context);
            // The board boots again and logs on: nothing of before is lost.
            let (store, mounted) = flash.mount();
            assert!(store.log() > mounted.newest.unwrap_or(0), "{context}");
            write_log(&mut flash, &mut model, &next, false, None, &mut step);
            check(&flash, &model, &context);
            let logs = flash.logs();
            let newest = *logs.keys().last().unwrap();
            let joined: Vec<u8> = logs[&newest].iter().flat_map(|p| p.1.clone()).collect();
            assert_eq!(joined, next, "{context}");
            // The flown log (if a page of it survived, it is log 1 and `next` log 2): one
            // contiguous run of pages (the next log's erases ahead may have taken its first
            // sector, the oldest data), each as written.
            if newest == 2 {
                let pages = &logs[&1];
                for (k, (seq, payload)) in pages.iter().enumerate() {
                    let at = *seq as usize * PAYLOAD;
                    assert_eq!(payload[..], flown[at..at + payload.len()], "{context}");
                    if k > 0 {
                        assert_eq!(*seq, pages[k - 1].0 + 1, "{context}");
                    }
                }
            }
        }
    }
    assert!(cuts > 60);
}
