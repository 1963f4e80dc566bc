//! Settings persisted in NOR flash through sequential-storage's map (one key, one record).
//!
//! Power-cut safety comes from sequential-storage: an item is written, then its CRC-checked
//! header makes it valid, and the old item stays readable until then; a torn write is found
//! and repaired on the next access. The tests cut power at every byte of a save (and of the
//! page migration a save can cause) with its fault-injecting mock flash.

use core::ops::Range;

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

use super::{DecodeError, RECORD_LEN, Settings};

/// The map key of the settings record.
const SETTINGS_KEY: u8 = 1;

type Map<S> = MapStorage<u8, S, Cache<Uncached, Uncached, Uncached, u8>>;

/// Why loading or saving failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError<E> {
    /// The flash driver failed (or the power was cut).
    Flash(E),
    /// The flash range does not suit the map (page alignment, at least two pages).
    BadRange,
    /// The storage holds data sequential-storage cannot repair; erase it.
    Corrupted,
    /// No room even after garbage collection (cannot happen with one small record).
    Full,
    /// The stored record does not decode.
    Record(DecodeError),
    /// sequential-storage reported an internal error or a buffer problem.
    Internal,
}

impl<E: core::fmt::Debug> core::fmt::Display for StoreError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Flash(e) => write!(f, "flash error {e:?}"),
            Self::BadRange => f.write_str("settings flash range unusable"),
            Self::Corrupted => f.write_str("settings storage corrupted"),
            Self::Full => f.write_str("settings storage full"),
            Self::Record(e) => write!(f, "settings record invalid: {e}"),
            Self::Internal => f.write_str("settings storage internal error"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for StoreError<E> {}

impl<E> From<sequential_storage::Error<E>> for StoreError<E> {
    fn from(error: sequential_storage::Error<E>) -> Self {
        match error {
            sequential_storage::Error::Storage { value, .. } => Self::Flash(value),
            sequential_storage::Error::Corrupted { .. } => Self::Corrupted,
            sequential_storage::Error::FullStorage => Self::Full,
            _ => Self::Internal,
        }
    }
}

/// A word-aligned work buffer: the key, the record and the item header, rounded up.
#[repr(align(4))]
struct WorkBuffer([u8; 32]);

/// The settings in their flash range.
pub struct SettingsStore<S: NorFlash> {
    map: Map<S>,
    buffer: WorkBuffer,
}

impl<S: NorFlash> SettingsStore<S> {
    /// A store over `range` of `flash` (page-aligned, at least two erase pages).
    pub fn new(flash: S, range: Range<u32>) -> Result<Self, StoreError<S::Error>> {
        let config = MapConfig::try_new(range).map_err(|_| StoreError::BadRange)?;
        Ok(Self {
            map: MapStorage::new(flash, config, Cache::new_uncached()),
            buffer: WorkBuffer([0; 32]),
        })
    }

    /// The stored settings, `Ok(None)` if none were ever saved.
    pub async fn load(&mut self) -> Result<Option<Settings>, StoreError<S::Error>> {
        let record: Option<&[u8]> = self
            .map
            .fetch_item(&mut self.buffer.0, &SETTINGS_KEY)
            .await?;
        record
            .map(|bytes| Settings::from_record(bytes).map_err(StoreError::Record))
            .transpose()
    }

    /// Saves `settings` (one item write; the previous record stays valid until it is done).
    pub async fn save(&mut self, settings: &Settings) -> Result<(), StoreError<S::Error>> {
        let record: [u8; RECORD_LEN] = settings.to_record();
        self.map
            .store_item(&mut self.buffer.0, &SETTINGS_KEY, &&record[..])
            .await?;
        Ok(())
    }

    /// Gives the flash back.
    pub fn release(self) -> S {
        self.map.destroy().0
    }
}

#[cfg(test)]
#[path = "store_tests.rs"]
mod tests;
