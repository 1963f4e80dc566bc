//! Settings saves and the watchdog around them: the storage adapter takes a [`SaveJob`]
//! (only while disarmed, [`FlightApp::take_save`]), stretches the independent watchdog to
//! the job's [`SaveJob::watchdog_ms`] for the write ([`FlightApp::on_watchdog_stretched`]:
//! the firmware programs the IWDG, the app's model follows), writes it
//! ([`SaveJob::write`]) and reports ([`FlightApp::on_save_done`], which restores the
//! normal timeout with a feed, as reprogramming the IWDG does).
//!
//! Why the stretch: sequential-storage erases a sector when the map runs out of room, and
//! on the single-bank F405 a 16 KiB sector erase stalls the whole CPU for 250 ms typ.,
//! 500 ms max. (DS8626 table "Flash memory programming", t_ERASE16KB at ×32 parallelism,
//! which embassy-stm32 programs) — longer than the IWDG's timeout at a fast LSI
//! ([`super::watchdog::IWDG`]: 200 ms at 47 kHz), so a save without the stretch can reset the
//! flight controller.

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::CacheImpl;
use sequential_storage::map::MapStorage;

use super::FlightApp;
use crate::settings::{PARAMS, Settings, StoreError, save, save_whole};

/// The watchdog period the storage adapter allows around a save, ms: eight times the F405's
/// worst 16 KiB sector erase (500 ms), with the words programmed after it (16 µs typ.,
/// 100 µs max. each: a few ms for a settings record).
pub const SAVE_WATCHDOG_MS: u32 = 4_000;

/// A settings save for the storage adapter.
#[derive(Debug, Clone, PartialEq)]
pub struct SaveJob {
    /// The settings to write.
    pub live: Settings,
    /// What flash holds (the load, or the last save).
    pub stored: Settings,
    /// Rewrite the whole record (`settings::save_whole`): after a boot-time settings
    /// problem flash does not hold what `stored` says.
    pub whole: bool,
    /// The watchdog period to allow for the write, ms ([`SAVE_WATCHDOG_MS`]).
    pub watchdog_ms: u32,
}

impl SaveJob {
    /// Writes the job to the settings map: the whole set, or what changed since `stored`.
    /// Returns how many parameters were written.
    pub async fn write<S: NorFlash, C: CacheImpl<u16>>(
        &self,
        map: &mut MapStorage<u16, S, C>,
    ) -> Result<u16, StoreError> {
        if self.whole {
            save_whole(map, &self.live).await?;
            Ok(u16::try_from(PARAMS.len()).unwrap_or(u16::MAX))
        } else {
            save(map, &self.live, &self.stored).await
        }
    }
}

impl FlightApp {
    /// For the storage adapter: the save to write now, if one is due and the motors are
    /// stopped.
    pub fn take_save_job(&mut self) -> Option<SaveJob> {
        let (live, stored) = self.take_save()?;
        Some(SaveJob {
            live,
            stored,
            whole: self.save_whole(),
            watchdog_ms: SAVE_WATCHDOG_MS,
        })
    }

    /// The storage adapter stretched the independent watchdog to `timeout_ms` at `now_ms`
    /// (reprogramming feeds it): the app's watchdog model follows.
    pub fn on_watchdog_stretched(&mut self, now_ms: u32, timeout_ms: u32) {
        self.watchdog.stretch(now_ms, timeout_ms);
    }

    /// The storage adapter finished a save at `now_ms` and restored the normal watchdog
    /// timeout (a feed); `saved` is what it wrote, `None` if the write failed.
    pub fn on_save_done(&mut self, now_ms: u32, saved: Option<Settings>) {
        self.watchdog.restore(now_ms);
        if let Some(settings) = saved {
            self.on_saved(settings);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::WATCHDOG_TIMEOUT_MS;

    #[test]
    fn a_stretched_watchdog_outlasts_a_sector_erase_and_comes_back_after_the_save() {
        let mut app = FlightApp::new(Settings::default(), 0).unwrap();
        // Nothing checks in: only the stretch and the restore feed.
        app.on_watchdog_stretched(1_000, SAVE_WATCHDOG_MS);
        // A 500 ms worst-case erase under the stretch: no reset.
        assert!(!app.watchdog().expired(1_500));
        app.on_save_done(1_500, None);
        assert_eq!(app.watchdog().timeout_ms(), WATCHDOG_TIMEOUT_MS);
        assert!(!app.watchdog().expired(1_499 + WATCHDOG_TIMEOUT_MS));
        assert!(app.watchdog().expired(1_500 + WATCHDOG_TIMEOUT_MS));
    }
}
