//! Settings persisted in NOR flash through sequential-storage's map.
//!
//! Power-cut safety comes from sequential-storage: an item is written, then its CRC-checked
//! header makes it valid, and the old item stays readable until then; a torn write is found
//! and repaired on the next access. The tests cut power at every byte of a save (and of the
//! page migration a save can cause) with its fault-injecting mock flash.
//!
//! Corruption safety is ours. sequential-storage skips an item whose CRC fails and returns
//! the newest valid one, so with every version kept under one key, a corrupted newest record
//! would bring back an older one — an older bind ID presented as current. So only one
//! version is ever live: a save writes `generation ‖ record` under the key *not* holding the
//! current settings, then erases every item of the other key (and of the legacy key 1 that
//! older firmware wrote). After a cut between the two steps both keys hold a record and the
//! higher generation is the newer; after corruption of the live record nothing valid is
//! left, so the module boots with defaults (unbound), never with an older bind. A save reads
//! its record back before it reports success; storage sequential-storage calls corrupted is
//! erased and written afresh.

use core::ops::Range;

use embedded_storage_async::nor_flash::MultiwriteNorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

use super::{DecodeError, RECORD_LEN, Settings};

/// The key the first firmware stored its (generation-less) record under; read, never written.
const LEGACY_KEY: u8 = 1;
/// The two keys a save alternates between.
const KEYS: [u8; 2] = [2, 3];
/// Bytes of the generation in front of the record.
const GENERATION_BYTES: usize = 4;
/// A stored value: generation (u32 LE) ‖ record.
const VALUE_LEN: usize = GENERATION_BYTES + RECORD_LEN;

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
    /// The record read back after a save is not the one written.
    Verify,
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
            Self::Verify => f.write_str("settings record did not read back"),
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

/// Bytes of the work buffer: the key, the value and the item header, rounded up to words.
const WORK_BUFFER_LEN: usize = (1 + VALUE_LEN + 8 + 3) & !3;

/// A word-aligned work buffer: the key, the record and the item header, rounded up.
#[repr(align(4))]
struct WorkBuffer([u8; WORK_BUFFER_LEN]);

/// Where the live settings are: the key and its generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Live {
    key: u8,
    generation: u32,
}

/// The settings in their flash range.
pub struct SettingsStore<S: MultiwriteNorFlash> {
    map: Map<S>,
    buffer: WorkBuffer,
    /// Found by the last load or save (`None`: look again before the next save).
    live: Option<Option<Live>>,
}

impl<S: MultiwriteNorFlash> SettingsStore<S> {
    /// A store over `range` of `flash` (page-aligned, at least two erase pages).
    pub fn new(flash: S, range: Range<u32>) -> Result<Self, StoreError<S::Error>> {
        let config = MapConfig::try_new(range).map_err(|_| StoreError::BadRange)?;
        Ok(Self {
            map: MapStorage::new(flash, config, Cache::new_uncached()),
            buffer: WorkBuffer([0; WORK_BUFFER_LEN]),
            live: None,
        })
    }

    /// The stored settings, `Ok(None)` if none were ever saved (or the live record was
    /// destroyed: an older one is never returned).
    pub async fn load(&mut self) -> Result<Option<Settings>, StoreError<S::Error>> {
        self.live = None;
        let live = self.find_live().await?;
        self.live = Some(live);
        let Some(live) = live else {
            return Ok(None);
        };
        let mut record = [0u8; RECORD_LEN];
        let len = self
            .fetch(live.key, &mut record)
            .await?
            .map_or(0, |(_, len)| len);
        Settings::from_record(record.get(..len).unwrap_or(&[]))
            .map(Some)
            .map_err(StoreError::Record)
    }

    /// Saves `settings`: the record under the other key, then the older one erased; it is
    /// read back before `Ok` is returned. Storage found corrupted (or holding an undecodable
    /// record) is erased and written anew.
    pub async fn save(&mut self, settings: &Settings) -> Result<(), StoreError<S::Error>> {
        match self.try_save(settings).await {
            // Nothing of the old settings is worth more than the new ones being saved.
            Err(StoreError::Corrupted | StoreError::Record(_)) => {
                self.live = None;
                self.map.erase_all().await?;
                self.try_save(settings).await
            }
            other => other,
        }
    }

    async fn try_save(&mut self, settings: &Settings) -> Result<(), StoreError<S::Error>> {
        let live = match self.live.take() {
            Some(live) => live,
            None => self.find_live().await?,
        };
        let (target, other) = match live {
            Some(Live { key, .. }) if key == KEYS[0] => (KEYS[1], KEYS[0]),
            _ => (KEYS[0], KEYS[1]),
        };
        let generation = live.map_or(1, |l| l.generation.wrapping_add(1));
        let mut value = [0u8; VALUE_LEN];
        let (head, tail) = value.split_at_mut(GENERATION_BYTES);
        head.copy_from_slice(&generation.to_le_bytes());
        tail.copy_from_slice(&settings.to_record());
        // Stale items of the target (a save cut before its clean-up) go first, so that once
        // the new record is written nothing older than it is live under either key.
        self.map.remove_item(&mut self.buffer.0, &target).await?;
        self.map
            .store_item(&mut self.buffer.0, &target, &&value[..])
            .await?;
        self.map.remove_item(&mut self.buffer.0, &other).await?;
        self.map
            .remove_item(&mut self.buffer.0, &LEGACY_KEY)
            .await?;
        let mut record = [0u8; RECORD_LEN];
        let back = self.fetch(target, &mut record).await?;
        if back != Some((generation, RECORD_LEN)) || record != settings.to_record() {
            return Err(StoreError::Verify);
        }
        self.live = Some(Some(Live {
            key: target,
            generation,
        }));
        Ok(())
    }

    /// The live record's key: the newer generation if both keys hold one (a save cut before
    /// its clean-up), else the legacy key's record (generation 0).
    async fn find_live(&mut self) -> Result<Option<Live>, StoreError<S::Error>> {
        let mut record = [0u8; RECORD_LEN];
        let mut live: Option<Live> = None;
        for key in KEYS {
            if let Some((generation, _)) = self.fetch(key, &mut record).await? {
                let newer = live.is_none_or(|l| {
                    // Wrapping comparison: a generation counter never runs out.
                    (generation.wrapping_sub(l.generation) as i32) > 0
                });
                if newer {
                    live = Some(Live { key, generation });
                }
            }
        }
        if live.is_none() && self.fetch(LEGACY_KEY, &mut record).await?.is_some() {
            live = Some(Live {
                key: LEGACY_KEY,
                generation: 0,
            });
        }
        Ok(live)
    }

    /// The item under `key`: its generation (0 for the legacy key) and the record copied
    /// into `record`, with its length.
    async fn fetch(
        &mut self,
        key: u8,
        record: &mut [u8; RECORD_LEN],
    ) -> Result<Option<(u32, usize)>, StoreError<S::Error>> {
        let value: Option<&[u8]> = self.map.fetch_item(&mut self.buffer.0, &key).await?;
        let Some(value) = value else {
            return Ok(None);
        };
        let (generation, body) = if key == LEGACY_KEY {
            (0, value)
        } else {
            let Some((generation, body)) = value.split_first_chunk::<GENERATION_BYTES>() else {
                return Err(StoreError::Record(DecodeError::Length {
                    found: value.len(),
                }));
            };
            (u32::from_le_bytes(*generation), body)
        };
        let Some(target) = record.get_mut(..body.len()) else {
            return Err(StoreError::Record(DecodeError::Length {
                found: body.len(),
            }));
        };
        target.copy_from_slice(body);
        Ok(Some((generation, body.len())))
    }

    /// Gives the flash back.
    pub fn release(self) -> S {
        self.map.destroy().0
    }
}

#[cfg(test)]
#[path = "store_tests.rs"]
mod tests;
