//! Settings in flash sectors 2–3 (0x0800_8000–0x0800_FFFF, hardware/brushedsparky): loaded
//! at boot before the watchdog starts (a load problem goes to the app, which refuses to arm
//! until a save), saved when the app hands out a job (`FlightApp::take_save_job`, disarmed
//! only) with the watchdog stretched to the job's period over the possible sector erase.

use defmt::{info, warn};
use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_stm32::flash::{Bank1Region1, Blocking};
use embassy_time::{Duration, Timer};
use flight_app::settings::{LoadProblem, Settings, load_at_boot};
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

use super::supervisor::with_long_timeout;
use crate::firmware::clocks::DataCacheOff;
use crate::firmware::shared::{now_ms, with_app};

/// The flash under the map.
pub type SettingsFlash = BlockingAsync<Bank1Region1<'static, Blocking>>;
/// The settings map.
pub type SettingsMap = MapStorage<u16, SettingsFlash, Cache<Uncached, Uncached, Uncached, u16>>;

/// Sectors 2 and 3, as offsets in bank 1 region 1 (which starts at 0x0800_0000).
const SETTINGS_RANGE: core::ops::Range<u32> = 0x8000..0x1_0000;

/// Opens the map and loads the settings (defaults for anything missing or refused), with
/// the load's problem if any (`load_at_boot`: an unreadable store is `Corrupt`). No map means the area is
/// unusable: fly on defaults, never stop the flight controller.
pub async fn open(
    flash: Bank1Region1<'static, Blocking>,
) -> (Option<SettingsMap>, Settings, Option<LoadProblem>) {
    let mut settings = Settings::default();
    let Ok(config) = MapConfig::try_new(SETTINGS_RANGE) else {
        warn!("settings area does not fit the flash sectors; using defaults");
        return (None, settings, None);
    };
    let mut map = MapStorage::new(BlockingAsync::new(flash), config, Cache::new_uncached());
    // A load may write (sequential-storage repairs an interrupted page).
    let cache_off = DataCacheOff::new();
    let (report, unreadable) = load_at_boot(&mut map, &mut settings).await;
    drop(cache_off);
    match unreadable {
        Some(e) => warn!("settings unreadable ({}), using defaults", e),
        None => {
            info!(
                "settings: {} loaded, {} refused, generation {}",
                report.loaded, report.refused, report.generation
            );
            if let Some(problem) = report.problem {
                warn!("settings: {}", problem);
            }
        }
    }
    let problem = report.problem;
    (Some(map), settings, problem)
}

#[embassy_executor::task]
pub async fn storage_task(mut map: SettingsMap) {
    loop {
        Timer::after(Duration::from_millis(100)).await;
        // The app hands out a save only while disarmed, with the watchdog period it needs.
        let Some(job) = with_app(|a| a.take_save_job()).flatten() else {
            continue;
        };
        let cache_off = DataCacheOff::new();
        let written = with_long_timeout(job.watchdog_ms, job.write(&mut map)).await;
        drop(cache_off);
        let saved = written.as_ref().ok().map(|_| job.live.clone());
        with_app(|a| a.on_save_done(now_ms(), saved));
        match written {
            Ok(n) => info!("settings saved ({} written)", n),
            Err(e) => warn!("settings save failed: {}", e),
        }
    }
}
