//! The flight settings store (`flight_app::settings::load`): sequential-storage's mock flash
//! filled with fuzz bytes (the rest erased), loaded as at boot.
//!
//! Invariants: loading never panics and only returns a flash error or a report; every value
//! it leaves is inside its parameter's range (refused values keep their defaults); the report
//! counts no more parameters than exist; loading twice gives the same settings (reading
//! changes nothing the second read could see).
#![no_main]

use flight_app::settings::{PARAMS, Settings, load};
use libfuzzer_sys::fuzz_target;
use sequential_storage::cache::Cache;
use sequential_storage::map::{MapConfig, MapStorage};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};
use taulink_fuzz::block_on;

type Flash = MockFlashBase<4, 4, 64>;

fuzz_target!(|data: &[u8]| {
    let mut flash = Flash::new(WriteCountCheck::Twice, None, true);
    for (cell, &byte) in flash.as_bytes_mut().iter_mut().zip(data) {
        *cell = byte;
    }
    let config = MapConfig::try_new(Flash::FULL_FLASH_RANGE).expect("whole mock flash is a map");
    let mut map = MapStorage::new(flash, config, Cache::new_uncached());
    let mut first = Settings::default();
    let Ok(report) = block_on(load(&mut map, &mut first)) else {
        return;
    };
    assert!(usize::from(report.loaded) + usize::from(report.refused) <= PARAMS.len());
    for (param, value) in first.iter() {
        assert_eq!(param.check(value), Ok(value), "{} out of range", param.name);
    }
    let mut second = Settings::default();
    if block_on(load(&mut map, &mut second)).is_ok() {
        assert_eq!(
            first.iter().map(|(_, v)| v.to_bits()).collect::<Vec<_>>(),
            second.iter().map(|(_, v)| v.to_bits()).collect::<Vec<_>>()
        );
    }
});
