//! Settings in flash sectors 2–3 (0x0800_8000–0x0800_FFFF, hardware/brushedsparky): loaded
//! at boot before the watchdog starts (a load problem goes to the app, which refuses to arm
//! until a save), saved when the app asks (`FlightApp::take_save`, disarmed only) with the
//! watchdog stretched over the possible sector erase.

use defmt::{info, warn};
use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_stm32::flash::{Bank1Region1, Blocking};
use embassy_time::{Duration, Timer};
use flight_core::settings::{LoadProblem, Settings, load, save, save_whole};
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

use super::supervisor::with_long_timeout;
use crate::firmware::shared::with_app;

/// The flash under the map.
pub type SettingsFlash = BlockingAsync<Bank1Region1<'static, Blocking>>;
/// The settings map.
pub type SettingsMap = MapStorage<u16, SettingsFlash, Cache<Uncached, Uncached, Uncached, u16>>;

/// Sectors 2 and 3, as offsets in bank 1 region 1 (which starts at 0x0800_0000).
const SETTINGS_RANGE: core::ops::Range<u32> = 0x8000..0x1_0000;

/// Opens the map and loads the settings (defaults for anything missing or refused), with
/// the load's problem if any (an unreadable store is `Corrupt`). No map means the area is
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
    let problem = match load(&mut map, &mut settings).await {
        Ok(report) => {
            info!(
                "settings: {} loaded, {} refused, generation {}",
                report.loaded, report.refused, report.generation
            );
            if let Some(problem) = report.problem {
                warn!("settings: {}", problem);
            }
            report.problem
        }
        Err(e) => {
            warn!("settings unreadable ({}), using defaults", e);
            Some(LoadProblem::Corrupt)
        }
    };
    (Some(map), settings, problem)
}

#[embassy_executor::task]
pub async fn storage_task(mut map: SettingsMap) {
    loop {
        Timer::after(Duration::from_millis(100)).await;
        // The app hands out a save only while disarmed.
        let Some(Some((live, stored, whole))) =
            with_app(|a| a.take_save().map(|(l, s)| (l, s, a.save_whole())))
        else {
            continue;
        };
        let written = async {
            if whole {
                // After a load problem flash is not what `stored` says: write it all.
                save_whole(&mut map, &live).await.map(|()| 1)
            } else {
                save(&mut map, &live, &stored).await
            }
        };
        match with_long_timeout(written).await {
            Ok(n) => {
                info!("settings saved ({} changed)", n);
                with_app(|a| a.on_saved(live));
            }
            Err(e) => warn!("settings save failed: {}", e),
        }
    }
}
