//! Settings in flash through sequential-storage's map: one item per parameter, keyed by the
//! parameter's stable key, holding its 32 value bits.
//!
//! Power-fail behaviour: sequential-storage writes each item with a CRC and never erases the
//! only copy of a live item, so a power cut during `save` leaves every parameter with either
//! its old or its new value (tested with the crate's fault-injecting mock flash). Values that
//! fail their range check on load (a table change between firmware versions) are skipped and
//! keep their defaults.

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::CacheImpl;
use sequential_storage::map::MapStorage;

use super::params::{ParamError, Settings};

/// Scratch buffer size for one item (key + value, rounded up to the flash word).
pub const FLASH_BUFFER: usize = 32;

/// A storage failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError {
    /// The flash driver failed, the area is full or corrupt; the settings in RAM are intact.
    Flash,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("settings flash failure")
    }
}

impl core::error::Error for StoreError {}

/// What `load` found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadReport {
    /// Parameters read from flash.
    pub loaded: u16,
    /// Stored values refused by today's range checks (they keep their defaults).
    pub refused: u16,
}

/// Reads every stored parameter into `settings` (which should hold the defaults).
pub async fn load<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &mut Settings,
) -> Result<LoadReport, StoreError> {
    let mut report = LoadReport::default();
    let keys: heapless::Vec<u16, { super::params::COUNT }> =
        settings.iter().map(|(p, _)| p.key).collect();
    for key in keys {
        let mut buf = [0u8; FLASH_BUFFER];
        match map.fetch_item::<u32>(&mut buf, &key).await {
            Ok(Some(bits)) => match settings.set_by_key(key, bits) {
                Ok(()) => report.loaded += 1,
                Err(ParamError::OutOfRange | ParamError::Unparsable | ParamError::Unknown) => {
                    report.refused += 1
                }
            },
            Ok(None) => {}
            Err(_) => return Err(StoreError::Flash),
        }
    }
    Ok(report)
}

/// Writes the parameters whose value differs from `stored` (what flash holds now), so an
/// unchanged setting costs no flash wear. Call only while disarmed: on the F405 a sector
/// erase stalls instruction fetch.
pub async fn save<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &Settings,
    stored: &Settings,
) -> Result<u16, StoreError> {
    let mut written = 0;
    for ((p, value), (_, old)) in settings.iter().zip(stored.iter()) {
        if value.to_bits() == old.to_bits() {
            continue;
        }
        let mut buf = [0u8; FLASH_BUFFER];
        map.store_item(&mut buf, &p.key, &value.to_bits())
            .await
            .map_err(|_| StoreError::Flash)?;
        written += 1;
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_futures::block_on;
    use sequential_storage::cache::Cache;
    use sequential_storage::map::MapConfig;
    use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

    type Flash = MockFlashBase<4, 4, 256>; // 4 pages of 1 KiB

    fn map(flash: Flash) -> MapStorage<u16, Flash, impl CacheImpl<u16>> {
        let config = MapConfig::try_new(Flash::FULL_FLASH_RANGE).unwrap();
        MapStorage::new(flash, config, Cache::new_uncached())
    }

    #[test]
    fn round_trip_and_only_changes_are_written() {
        let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
        let defaults = Settings::default();
        let mut s = defaults.clone();
        s.set_text("pid.roll.kp", "0.0042").unwrap();
        s.set_text("output.protocol", "oneshot125").unwrap();
        assert_eq!(block_on(save(&mut m, &s, &defaults)), Ok(2));
        assert_eq!(block_on(save(&mut m, &s, &s)), Ok(0));
        let mut loaded = Settings::default();
        let report = block_on(load(&mut m, &mut loaded)).unwrap();
        assert_eq!(
            report,
            LoadReport {
                loaded: 2,
                refused: 0
            }
        );
        assert_eq!(loaded, s);
    }

    #[test]
    fn out_of_range_stored_values_keep_defaults() {
        let mut m = map(Flash::default());
        let mut buf = [0u8; FLASH_BUFFER];
        // pid.roll.kp (key 300) = 7.0 is outside 0..=1; battery.cells (500) = 3 is fine.
        block_on(m.store_item(&mut buf, &300u16, &7.0f32.to_bits())).unwrap();
        block_on(m.store_item(&mut buf, &500u16, &3u32)).unwrap();
        let mut s = Settings::default();
        let report = block_on(load(&mut m, &mut s)).unwrap();
        assert_eq!(
            report,
            LoadReport {
                loaded: 1,
                refused: 1
            }
        );
        assert_eq!(s.f32("pid.roll.kp"), Settings::default().f32("pid.roll.kp"));
        assert_eq!(s.u32("battery.cells"), 3);
    }

    /// Cuts the power after every possible number of written bytes during a save of three
    /// changed parameters, then boots: every parameter is its old or its new value.
    #[test]
    fn power_cut_at_every_byte_leaves_old_or_new_values() {
        let old = {
            let mut s = Settings::default();
            s.set_text("pid.roll.kp", "0.001").unwrap();
            s.set_text("pid.pitch.kp", "0.002").unwrap();
            s.set_text("battery.cells", "1").unwrap();
            s
        };
        let mut new = old.clone();
        new.set_text("pid.roll.kp", "0.009").unwrap();
        new.set_text("pid.pitch.kp", "0.008").unwrap();
        new.set_text("battery.cells", "2").unwrap();
        let names = ["pid.roll.kp", "pid.pitch.kp", "battery.cells"];
        let mut cut_points = 0;
        for budget in 0..400u32 {
            let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
            block_on(save(&mut m, &old, &Settings::default())).unwrap();
            let (mut flash, _) = m.destroy();
            flash.bytes_until_shutoff = Some(budget);
            let mut m = map(flash);
            let finished = block_on(save(&mut m, &new, &old)).is_ok();
            let (mut flash, _) = m.destroy();
            flash.bytes_until_shutoff = None;
            let mut m = map(flash);
            let mut booted = Settings::default();
            block_on(load(&mut m, &mut booted)).unwrap();
            for n in names {
                let v = booted.get(n);
                assert!(
                    v == old.get(n) || v == new.get(n),
                    "budget {budget}: {n} = {v:?}"
                );
            }
            if finished {
                assert_eq!(booted, new);
                break;
            }
            cut_points += 1;
        }
        assert!(cut_points > 20, "the save was cut at {cut_points} points");
    }
}
