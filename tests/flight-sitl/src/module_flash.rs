//! The module's settings flash: the nRF52840's 0xEC000–0xF3FFF (8 × 4 KiB pages, as
//! module-fw's `board::SETTINGS_FLASH`) as sequential-storage's `MockFlashBase`, kept by the
//! world so it survives resets, written and read only through module-core's
//! `SettingsStore` as the firmware's boot and settings task do; a save costs the board the
//! NVMC's time ([`nrf52840_us`]).

use embassy_futures::block_on;
use module_core::settings::{Settings, SettingsStore};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

/// Eight 4 KiB pages of 4-byte words.
type Flash = MockFlashBase<8, 4, 1024>;

/// nRF52840 page erase, µs (Product Specification, NVMC electrical specification,
/// t_ERASEPAGE: 85 ms max.). The CPU halts while the NVMC erases or writes flash it runs
/// from: the whole board waits.
pub(crate) const NRF52840_PAGE_ERASE_US: u64 = 85_000;
/// nRF52840 32-bit word write, µs (same table, t_WRITE: 41 µs max.).
pub(crate) const NRF52840_WORD_WRITE_US: u64 = 41;

/// How long the nRF52840 is halted for `erases` pages erased and `bytes_written` bytes.
pub(crate) fn nrf52840_us(erases: u64, bytes_written: u64) -> u64 {
    erases * NRF52840_PAGE_ERASE_US + bytes_written.div_ceil(4) * NRF52840_WORD_WRITE_US
}

/// The settings flash of the module board.
pub(crate) struct ModuleFlash {
    store: Option<SettingsStore<Flash>>,
}

impl ModuleFlash {
    /// The flash holding `settings` (what the module stored before the scenario).
    pub(crate) fn new(settings: &Settings) -> Self {
        let flash = Flash::new(WriteCountCheck::Twice, None, true);
        let mut store = SettingsStore::new(flash, Flash::FULL_FLASH_RANGE).ok();
        if let Some(s) = store.as_mut() {
            let _ = block_on(s.save(settings));
        }
        Self { store }
    }

    /// The boot-time load, as the firmware's: nothing stored or unreadable is the factory set.
    pub(crate) fn load(&mut self) -> Settings {
        let loaded = self.store.as_mut().map(|s| block_on(s.load()));
        match loaded {
            Some(Ok(Some(settings))) => settings,
            _ => Settings::default(),
        }
    }

    /// The settings task's save: whether it succeeded, and how long it halts the board, µs.
    pub(crate) fn save(&mut self, settings: &Settings) -> (bool, u64) {
        let Some(store) = self.store.take() else {
            return (false, 0);
        };
        let flash = store.release();
        let before = flash.stats_snapshot();
        // The store keeps no state a fresh one would not find again (its live record).
        let Ok(mut store) = SettingsStore::new(flash, Flash::FULL_FLASH_RANGE) else {
            return (false, 0);
        };
        let ok = block_on(store.save(settings)).is_ok();
        let flash = store.release();
        let done = before.compare_to(flash.stats_snapshot());
        self.store = SettingsStore::new(flash, Flash::FULL_FLASH_RANGE).ok();
        (ok, nrf52840_us(done.erases, done.bytes_written))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saved_settings_load_back_and_a_save_costs_the_nvmc_time() {
        let mut flash = ModuleFlash::new(&Settings::default());
        let changed = Settings {
            tx_power: 3,
            ..Settings::default()
        };
        let (ok, us) = flash.save(&changed);
        assert!(ok);
        // At least one word written; no page full yet, so no erase.
        assert!(
            (NRF52840_WORD_WRITE_US..NRF52840_PAGE_ERASE_US).contains(&us),
            "{us} µs"
        );
        assert_eq!(flash.load(), changed);
    }

    #[test]
    fn saves_that_fill_a_page_erase_one_for_85_ms() {
        let mut flash = ModuleFlash::new(&Settings::default());
        let costs: Vec<u64> = (0..400u16)
            .map(|i| {
                let s = Settings {
                    tx_power: (i % 7) as u8,
                    ..Settings::default()
                };
                flash.save(&s).1
            })
            .collect();
        assert!(
            costs.iter().any(|&us| us >= NRF52840_PAGE_ERASE_US),
            "no erase in {} saves",
            costs.len()
        );
    }
}
