//! The flight controller's settings flash: sectors 2–3 of the F405 (2 × 16 KiB) as
//! sequential-storage's `MockFlashBase`, kept by the world so it survives resets and power
//! cycles, written and read only through `flight_app::settings::{load, save, save_whole}`
//! as the firmware's storage task does. What it holds at the first boot is the scenario's
//! [`FlashInjection`].

use embassy_futures::block_on;
use flight_app::app::SaveJob;
use flight_app::settings::{
    Handle, LoadProblem, Settings, handles, load_at_boot, save, save_whole,
};
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
        if injection == FlashInjection::NearlyFull
            && let Some(m) = map.take()
        {
            map = fill_until_erase_due(m, settings);
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

    /// The storage task's boot-time load (`load_at_boot`, as the firmware's): the settings
    /// and the load's problem.
    pub(crate) fn load(&mut self) -> (Settings, Option<LoadProblem>) {
        let mut settings = Settings::default();
        let Some(map) = self.map.as_mut() else {
            return (settings, None);
        };
        let (report, _) = block_on(load_at_boot(map, &mut settings));
        (settings, report.problem)
    }

    /// The storage task's save of the app's job (`SaveJob::write`, as the firmware's):
    /// whether it succeeded, and what it did to the flash (sectors erased, bytes programmed).
    pub(crate) fn save(&mut self, job: &SaveJob) -> (bool, FlashWork) {
        let Some(map) = self.map.take() else {
            return (false, FlashWork::default());
        };
        let (flash, _) = map.destroy();
        let before = flash.stats_snapshot();
        let Some(mut map) = open(flash) else {
            return (false, FlashWork::default());
        };
        let ok = block_on(job.write(&mut map)).is_ok();
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
/// table "Flash memory programming", t_ERASE16KB: 250 ms typ., 500 ms max. at ×32; 400 /
/// 800 ms at ×8). ×32 is what embassy-stm32 (0.6, `flash/f4.rs`: `PSIZE32`) programs for
/// both erase and write.
pub(crate) const F405_SECTOR_ERASE_US: u64 = 250_000;
/// STM32F405 word (32-bit) program, typical, µs (DS8626 same table, t_prog: 16 µs typ.,
/// 100 µs max.).
pub(crate) const F405_WORD_PROGRAM_US: u64 = 16;

impl FlashWork {
    /// How long the F405 takes for it, µs. The F405 has a single flash bank: while it
    /// erases or programs, code fetch from flash stalls — the whole board waits.
    pub(crate) fn f405_us(self) -> u64 {
        self.erases * F405_SECTOR_ERASE_US + self.bytes_written.div_ceil(4) * F405_WORD_PROGRAM_US
    }
}

/// The parameter the fill toggles (any one-parameter change makes a record of one size).
const FILLER: Handle<f32> = handles::LQG_Q_TORQUE;

/// `settings` with [`FILLER`] changed.
fn with_filler_changed(settings: &Settings) -> Settings {
    let mut changed = settings.clone();
    let v = settings.get(FILLER);
    let _ = changed.put(FILLER, if v > 1.0 { v * 0.5 } else { v + 1.0 });
    changed
}

/// Whether saving `live` over `stored` on (a copy of) `flash` would erase a sector.
fn save_would_erase(flash: &Flash, live: &Settings, stored: &Settings) -> bool {
    let before = flash.stats_snapshot();
    let Some(mut trial) = open(flash.clone()) else {
        return false;
    };
    let _ = block_on(save(&mut trial, live, stored));
    let (after, _) = trial.destroy();
    before.compare_to(after.stats_snapshot()).erases > 0
}

/// Saves `settings`' [`FILLER`] changed and back, pair after pair, until a one-parameter
/// save would erase a sector; flash then holds `settings` again.
fn fill_until_erase_due(map: Map, settings: &Settings) -> Option<Map> {
    let changed = with_filler_changed(settings);
    let (mut flash, _) = map.destroy();
    for _ in 0..10_000 {
        if save_would_erase(&flash, &changed, settings) {
            break;
        }
        let mut map = open(flash)?;
        let _ = block_on(save(&mut map, &changed, settings));
        let _ = block_on(save(&mut map, settings, &changed));
        flash = map.destroy().0;
    }
    open(flash)
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
    use flight_app::settings::handles;

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

    /// A nearly full flash loads the scenario's settings, and the next one-parameter save
    /// erases a sector: a stall of at least the F405's sector erase.
    #[test]
    fn a_nearly_full_flash_erases_on_the_next_save() {
        let mut f = SettingsFlash::new(&tuned(), FlashInjection::NearlyFull);
        assert_eq!(f.load(), (tuned(), None));
        let mut live = tuned();
        let _ = live.put(handles::PID_ROLL_KP, 0.005);
        let job = SaveJob {
            live,
            stored: tuned(),
            whole: false,
            watchdog_ms: flight_app::app::SAVE_WATCHDOG_MS,
        };
        let (saved, work) = f.save(&job);
        assert!(saved);
        assert_eq!(work.erases, 1, "{work:?}");
        assert!(work.f405_us() >= F405_SECTOR_ERASE_US);
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
