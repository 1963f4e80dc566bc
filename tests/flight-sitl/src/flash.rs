//! The flight controller's settings flash: sectors 2–3 of the F405 (2 × 16 KiB) as
//! sequential-storage's `MockFlashBase`, kept by the world so it survives resets and power
//! cycles, written and read only through `flight_core::settings::{load, save, save_whole}`
//! as the firmware's storage task does. What it holds at the first boot is the scenario's
//! [`FlashInjection`].

use embassy_futures::block_on;
use flight_core::settings::{LoadProblem, Settings, load, save, save_whole};
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};
use telemetry::mock::SplitMix64;

use crate::scenario::FlashInjection;

/// Two 16 KiB sectors of 4-byte words.
type Flash = MockFlashBase<2, 4, 4096>;
type Map = MapStorage<u16, Flash, Cache<Uncached, Uncached, Uncached, u16>>;

/// The settings flash of the flight board.
pub(crate) struct SettingsFlash {
    map: Option<Map>,
}

fn open(flash: Flash) -> Option<Map> {
    let config = MapConfig::try_new(Flash::FULL_FLASH_RANGE).ok()?;
    Some(MapStorage::new(flash, config, Cache::new_uncached()))
}

impl SettingsFlash {
    /// The flash as the scenario has it at the first boot: `settings` stored (then maybe
    /// corrupted), or erased.
    pub(crate) fn new(settings: &Settings, injection: FlashInjection) -> Self {
        let mut map = open(Flash::new(WriteCountCheck::Twice, None, true));
        if injection != FlashInjection::Erased
            && let Some(m) = map.as_mut()
        {
            let _ = block_on(save_whole(m, settings));
        }
        if let FlashInjection::Corrupted(seed) = injection
            && let Some(m) = map.take()
        {
            let (mut flash, _) = m.destroy();
            corrupt(&mut flash, seed);
            map = open(flash);
        }
        Self { map }
    }

    /// The storage task's boot-time load: the settings and the load's problem (an
    /// unreadable store is `Corrupt`, as the firmware treats it).
    pub(crate) fn load(&mut self) -> (Settings, Option<LoadProblem>) {
        let mut settings = Settings::default();
        let Some(map) = self.map.as_mut() else {
            return (settings, None);
        };
        match block_on(load(map, &mut settings)) {
            Ok(report) => (settings, report.problem),
            Err(_) => (Settings::default(), Some(LoadProblem::Corrupt)),
        }
    }

    /// The storage task's save (`whole` after a load problem): whether it succeeded, and
    /// what it did to the flash (sectors erased, bytes programmed).
    pub(crate) fn save(
        &mut self,
        live: &Settings,
        stored: &Settings,
        whole: bool,
    ) -> (bool, FlashWork) {
        let Some(map) = self.map.take() else {
            return (false, FlashWork::default());
        };
        let (flash, _) = map.destroy();
        let before = flash.stats_snapshot();
        let Some(mut map) = open(flash) else {
            return (false, FlashWork::default());
        };
        let ok = if whole {
            block_on(save_whole(&mut map, live)).is_ok()
        } else {
            block_on(save(&mut map, live, stored)).is_ok()
        };
        // The uncached map can be taken apart and opened again at no cost.
        let (flash, _) = map.destroy();
        let done = before.compare_to(flash.stats_snapshot());
        self.map = open(flash);
        let work = FlashWork {
            erases: done.erases,
            bytes_written: done.bytes_written,
        };
        (ok, work)
    }
}

/// What a save did to the flash.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct FlashWork {
    /// Sectors erased.
    pub(crate) erases: u64,
    /// Bytes programmed.
    pub(crate) bytes_written: u64,
}

/// STM32F405 16 KiB sector erase, typical, at ×32 parallelism (2.7–3.6 V), µs (DS8626
/// "Flash memory programming": 250 ms typ., 500 ms max.).
pub(crate) const F405_SECTOR_ERASE_US: u64 = 250_000;
/// STM32F405 word (32-bit) program, typical, µs (DS8626: 16 µs typ., 100 µs max.).
pub(crate) const F405_WORD_PROGRAM_US: u64 = 16;

impl FlashWork {
    /// How long the F405 takes for it, µs. The F405 has a single flash bank: while it
    /// erases or programs, code fetch from flash stalls — the whole board waits.
    pub(crate) fn f405_us(self) -> u64 {
        self.erases * F405_SECTOR_ERASE_US + self.bytes_written.div_ceil(4) * F405_WORD_PROGRAM_US
    }
}

/// Bytes per flash page (a 16 KiB sector).
const PAGE_BYTES: usize = 4 * 4096;

/// Bit flips in the written bytes, then both sectors' state markers overwritten (a write
/// torn by a power cut during a sector's close, flash wear): what sequential-storage can
/// only read as a corrupted map.
fn corrupt(flash: &mut Flash, seed: u64) {
    let mut rng = SplitMix64::new(seed ^ 0xF1A5_C0DE);
    let bytes = flash.as_bytes_mut();
    let written: Vec<usize> = (0..bytes.len())
        .filter(|&i| bytes.get(i) != Some(&0xFF))
        .collect();
    for _ in 0..4 {
        let Some(&at) = written.get(rng.below(written.len().max(1) as u64) as usize) else {
            break;
        };
        if let Some(b) = bytes.get_mut(at) {
            *b ^= 1 << rng.below(8);
        }
    }
    for page in 0..2 {
        let start = page * PAGE_BYTES;
        for at in (start..start + 4).chain(start + PAGE_BYTES - 4..start + PAGE_BYTES) {
            if let Some(b) = bytes.get_mut(at) {
                *b = 0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_core::settings::handles;

    fn tuned() -> Settings {
        let mut s = Settings::default();
        s.put(handles::PID_ROLL_KP, 0.0042).unwrap();
        s
    }

    #[test]
    fn stored_settings_load_back_whole() {
        let mut f = SettingsFlash::new(&tuned(), FlashInjection::Stored);
        assert_eq!(f.load(), (tuned(), None));
    }

    #[test]
    fn an_erased_flash_is_the_factory_set_without_complaint() {
        let mut f = SettingsFlash::new(&tuned(), FlashInjection::Erased);
        assert_eq!(f.load(), (Settings::default(), None));
    }

    #[test]
    fn a_corrupted_flash_is_the_factory_set_with_the_problem() {
        for seed in 0..8 {
            let mut f = SettingsFlash::new(&tuned(), FlashInjection::Corrupted(seed));
            assert_eq!(
                f.load(),
                (Settings::default(), Some(LoadProblem::Corrupt)),
                "seed {seed}"
            );
        }
    }
}
