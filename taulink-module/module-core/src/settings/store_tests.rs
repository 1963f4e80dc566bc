use super::*;
use crate::settings::{Band, Role};
use embassy_futures::block_on;
use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

/// 4 pages of 256 bytes, 4-byte words like the nRF52840 NVMC (which allows two writes per
/// word between erases, PS §4.3.2). Small pages make page migration happen every ~8 saves.
type Flash = MockFlashBase<4, 4, 64>;
const RANGE: Range<u32> = 0..1024;

fn flash() -> Flash {
    Flash::new(WriteCountCheck::Twice, None, true)
}

fn nth(n: u32) -> Settings {
    Settings {
        bind_id: n,
        tx_power: (n % 8) as u8,
        role: if n.is_multiple_of(2) {
            Role::Transmitter
        } else {
            Role::Receiver
        },
        band: if n.is_multiple_of(3) {
            Band::Mhz868
        } else {
            Band::Mhz433
        },
        ..Settings::default()
    }
}

#[test]
fn empty_flash_has_no_settings_then_round_trips() {
    block_on(async {
        let mut store = SettingsStore::new(flash(), RANGE).unwrap();
        assert_eq!(store.load().await, Ok(None));
        store.save(&nth(7)).await.unwrap();
        assert_eq!(store.load().await, Ok(Some(nth(7))));
        // A fresh store on the same flash (a reboot) reads the same.
        let mut store = SettingsStore::new(store.release(), RANGE).unwrap();
        assert_eq!(store.load().await, Ok(Some(nth(7))));
    });
}

#[test]
fn many_saves_wrap_around_the_pages() {
    block_on(async {
        let fresh = flash();
        let start = fresh.stats_snapshot();
        let mut store = SettingsStore::new(fresh, RANGE).unwrap();
        for n in 0..500 {
            store.save(&nth(n)).await.unwrap();
        }
        assert_eq!(store.load().await, Ok(Some(nth(499))));
        let erases = start.compare_to(store.release().stats_snapshot()).erases;
        assert!(erases > 20, "page migration happened ({erases} erases)");
    });
}

#[test]
fn bad_ranges_are_refused() {
    assert!(matches!(
        SettingsStore::new(flash(), 0..256),
        Err(StoreError::BadRange)
    ));
    assert!(matches!(
        SettingsStore::new(flash(), 4..1024),
        Err(StoreError::BadRange)
    ));
}

/// Power cut at every byte of a save, after `before` earlier saves: the next boot reads the
/// old or the new settings, and the store keeps working.
fn cut_everywhere(before: u32) -> usize {
    let mut cuts = 0;
    for cut_after in 0.. {
        let outcome = block_on(async {
            let mut store = SettingsStore::new(flash(), RANGE).unwrap();
            for n in 0..=before {
                store.save(&nth(n)).await.unwrap();
            }
            let mut flash = store.release();
            flash.bytes_until_shutoff = Some(cut_after);
            let mut store = SettingsStore::new(flash, RANGE).unwrap();
            let saved = store.save(&nth(1000)).await;
            // Reboot: the cut-off flash answers again.
            let mut flash = store.release();
            flash.bytes_until_shutoff = None;
            let mut store = SettingsStore::new(flash, RANGE).unwrap();
            let loaded = store.load().await.unwrap().unwrap();
            if saved.is_ok() {
                assert_eq!(loaded, nth(1000), "a completed save must stick");
            } else {
                assert!(
                    loaded == nth(before) || loaded == nth(1000),
                    "cut after {cut_after} bytes (after {before} saves) left {loaded:?}"
                );
            }
            store.save(&nth(2000)).await.unwrap();
            assert_eq!(store.load().await.unwrap(), Some(nth(2000)));
            saved.is_ok()
        });
        if outcome {
            break;
        }
        cuts += 1;
    }
    cuts
}

#[test]
fn power_cut_at_every_byte_leaves_old_or_new() {
    let mut total = 0;
    let mut most = 0;
    for before in 0..48 {
        let cuts = cut_everywhere(before);
        total += cuts;
        most = most.max(cuts);
    }
    // A plain save writes a 28-byte item (8-byte header; key, generation and record padded to
    // words) and marks the other key's item erased; a page holds eight such items, so the
    // saves go round the four pages, and one that must reclaim the oldest page first erases
    // its 256 bytes (measured: 2 800 cut points over the 48 saves, 300 for that save).
    assert!(total > 48 * 28, "{total} cut points tried");
    assert!(
        most > 256,
        "a save with a page erase was cut ({most} points)"
    );
}

/// xorshift64*: a fixed, seedable stream of corruption positions (no dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// What a trial did to the flash after its saves.
#[derive(Debug, Clone, Copy)]
enum Corruption {
    /// 1…4 bits flipped anywhere (retention faults).
    BitFlips,
    /// One page erased (an erase that was not ours, or a cut one that did finish).
    ErasedPage,
    /// One word cleared to zero (a torn write of a neighbour in the same word).
    ZeroedWord,
}

fn corrupt(flash: &mut Flash, kind: Corruption, rng: &mut Rng) {
    let len = flash.as_bytes().len() as u64;
    match kind {
        Corruption::BitFlips => {
            for _ in 0..=rng.below(4) {
                let at = rng.below(len) as usize;
                flash.as_bytes_mut()[at] ^= 1 << rng.below(8);
            }
        }
        Corruption::ErasedPage => {
            let page = rng.below(4) as u32;
            block_on(NorFlash::erase(flash, page * 256, (page + 1) * 256)).unwrap();
        }
        Corruption::ZeroedWord => {
            let at = (rng.below(len / 4) * 4) as usize;
            flash.as_bytes_mut()[at..at + 4].fill(0);
        }
    }
}

/// Random corruption after `saves` saves, then a reboot and a save: the load gives the newest
/// settings or no settings (an error, or none: the firmware then runs the defaults, unbound),
/// never an older bind ID; a save reported successful is what the next boot reads.
fn corruption_trial(seed: u64, kind: Corruption) {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let saves = 1 + rng.below(40) as u32;
    block_on(async {
        let mut store = SettingsStore::new(flash(), RANGE).unwrap();
        for n in 1..=saves {
            store.save(&nth(n)).await.unwrap();
        }
        let mut flash = store.release();
        corrupt(&mut flash, kind, &mut rng);
        let mut store = SettingsStore::new(flash, RANGE).unwrap();
        if let Ok(Some(loaded)) = store.load().await {
            assert_eq!(
                loaded,
                nth(saves),
                "seed {seed} {kind:?}: an older record presented as current after {saves} saves"
            );
        }
        let saved = store.save(&nth(1000)).await;
        let mut store = SettingsStore::new(store.release(), RANGE).unwrap();
        let loaded = store.load().await;
        if saved.is_ok() {
            assert_eq!(
                loaded,
                Ok(Some(nth(1000))),
                "seed {seed} {kind:?}: a save reported successful did not stick"
            );
        } else if let Ok(Some(loaded)) = loaded {
            assert!(
                loaded == nth(saves) || loaded == nth(1000),
                "seed {seed} {kind:?}: a failed save left {loaded:?}"
            );
        }
    });
}

#[test]
fn random_bit_flips_never_present_an_older_bind_id() {
    for seed in 0..3_000 {
        corruption_trial(seed, Corruption::BitFlips);
    }
}

#[test]
fn an_erased_page_never_presents_an_older_bind_id() {
    for seed in 0..1_000 {
        corruption_trial(seed, Corruption::ErasedPage);
    }
}

#[test]
fn a_zeroed_word_never_presents_an_older_bind_id() {
    for seed in 0..3_000 {
        corruption_trial(seed, Corruption::ZeroedWord);
    }
}

#[test]
fn a_record_of_the_first_firmware_loads_and_is_replaced_by_the_next_save() {
    block_on(async {
        // What the first firmware wrote: a version-1 record under key 1, no generation.
        let mut map: Map<Flash> =
            MapStorage::new(flash(), MapConfig::new(RANGE), Cache::new_uncached());
        let mut buffer = WorkBuffer([0; WORK_BUFFER_LEN]);
        let v1 = [1, 0, 2, 0, 2, 0, 7, 0, 0x78, 0x56, 0x34, 0x12];
        map.store_item(&mut buffer.0, &LEGACY_KEY, &&v1[..])
            .await
            .unwrap();
        let mut store = SettingsStore::new(map.destroy().0, RANGE).unwrap();
        let loaded = store.load().await.unwrap().unwrap();
        assert_eq!(loaded.bind_id, 0, "bound before the key agreement: unbound");
        assert_eq!(loaded.failsafe, crate::ppm::FailsafeOutput::HoldLast);
        store.save(&nth(5)).await.unwrap();
        let flash = store.release();
        let mut map: Map<Flash> =
            MapStorage::new(flash, MapConfig::new(RANGE), Cache::new_uncached());
        let legacy: Option<&[u8]> = map.fetch_item(&mut buffer.0, &LEGACY_KEY).await.unwrap();
        assert_eq!(
            legacy, None,
            "the old record is gone: it can never come back"
        );
        let mut store = SettingsStore::new(map.destroy().0, RANGE).unwrap();
        assert_eq!(store.load().await, Ok(Some(nth(5))));
    });
}
