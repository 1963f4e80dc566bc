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

    /// The storage task's save (`whole` after a load problem); `true` if it succeeded.
    pub(crate) fn save(&mut self, live: &Settings, stored: &Settings, whole: bool) -> bool {
        let Some(map) = self.map.as_mut() else {
            return false;
        };
        if whole {
            block_on(save_whole(map, live)).is_ok()
        } else {
            block_on(save(map, live, stored)).is_ok()
        }
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
    use flight_core::settings::Value;

    fn tuned() -> Settings {
        let mut s = Settings::default();
        let _ = s.set("pid.roll.kp", Value::F32(0.0042));
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
