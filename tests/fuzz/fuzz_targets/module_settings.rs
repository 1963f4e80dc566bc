//! The module's settings: the version-1 record parser (`Settings::from_record`) on raw bytes,
//! and the store (`SettingsStore::load`) over sequential-storage's mock flash filled with the
//! same fuzz bytes (the rest erased).
//!
//! Invariants: a record that parses re-encodes to a record of the same settings (to exactly its
//! bytes when it is of the current version); a loaded record is a
//! record that parses; loading twice gives the same answer.
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::settings::Settings;
use module_core::settings::store::SettingsStore;
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};
use taulink_fuzz::block_on;

type Flash = MockFlashBase<4, 4, 64>;

fuzz_target!(|data: &[u8]| {
    if let Ok(settings) = Settings::from_record(data) {
        // Older record versions load and are written back in the current version: what is
        // written parses to the same settings.
        let written = settings.to_record();
        assert_eq!(Settings::from_record(&written), Ok(settings));
        if data.first() == written.first() {
            assert_eq!(
                &written[..],
                data,
                "a current-version record re-encodes to itself"
            );
        }
    }

    let mut flash = Flash::new(WriteCountCheck::Twice, None, true);
    for (cell, &byte) in flash.as_bytes_mut().iter_mut().zip(data) {
        *cell = byte;
    }
    let mut store = SettingsStore::new(flash, Flash::FULL_FLASH_RANGE).expect("valid range");
    let first = block_on(store.load());
    if let Ok(Some(settings)) = &first {
        assert_eq!(Settings::from_record(&settings.to_record()), Ok(*settings));
    }
    if first.is_ok() {
        let second = block_on(store.load());
        assert_eq!(
            format!("{first:?}"),
            format!("{second:?}"),
            "a second load differs"
        );
    }
});
