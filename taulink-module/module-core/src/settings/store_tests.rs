use super::*;
use crate::settings::{Band, Role};
use embassy_futures::block_on;
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
    // A plain save writes 24 bytes (8-byte header, key and record padded to words); every
    // tenth save here starts a new page, and the one that must reclaim the oldest page
    // first erases its 256 bytes (measured: 288 cut points for that save).
    assert!(total > 48 * 24, "{total} cut points tried");
    assert!(
        most > 256,
        "a save with a page erase was cut ({most} points)"
    );
}
