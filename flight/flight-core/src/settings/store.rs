//! Settings in flash: the whole set as one record — format version, generation number, every
//! (key, value) pair, CRC-32 — in sequential-storage's map, alternating between two slots.
//!
//! Integrity: a save writes the new generation into the slot that does not hold the newest
//! one, so the last committed set stays untouched until the new record is completely written
//! (and sequential-storage itself never erases the only copy of a live item); then it writes
//! the same record into the other slot, so one damaged copy still leaves the newest set. A
//! power cut mid-save therefore leaves the previous set whole; a multi-parameter change (the
//! five `link.*` values after a bind) is one record, so it lands whole or not at all. On load,
//! a record counts only if its CRC, version and every cross-setting rule
//! ([`crate::pipeline::validate`]) pass; the newest such record wins. Nothing ever mixes
//! stored values with defaults while reporting success: a damaged or missing record is
//! reported in [`LoadReport::problem`], and without a usable record the set is the factory
//! one. The limit: sequential-storage skips an item whose CRC fails and returns the previous
//! item of that key, so if *both* copies of the newest record are destroyed (an erased page
//! holding both, bit flips in both), an older committed generation loads without a report —
//! a whole set, never a mix, but not the newest (measured in the random-corruption test).
//!
//! The old format (one map item per parameter, before this record) is not migrated: such a
//! store loads as factory settings with [`LoadProblem::OldFormat`], and the next save writes
//! the record format.
//!
//! Record versions: 4 (now) ends its pairs with the link key — a flag byte (0 none, 1 a key)
//! and, with 1, the 16 key bytes (the random key agreed at bind, spec §12.1; no phrase or
//! value derived from one is stored). Versions 3 (a key hashed from the phrase alone, which
//! a recording let a guesser test) and 2 (no key) load with their pairs, but neither their
//! key nor their bound link: the link was bound by the protocol before the key agreement,
//! so the controller runs no link until it is bound again.

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::CacheImpl;
use sequential_storage::map::MapStorage;

use telemetry::link::LinkKey;
use telemetry::link::auth::KEY_BYTES;

use super::params::Settings;
use crate::pipeline::InvalidSettings;
use telemetry::settings::PARAMS;

/// Scratch buffer size for one map item: the slot key and the record, rounded up to the
/// flash word (the record is 11 + 6 × parameters bytes).
pub const FLASH_BUFFER: usize = 16 + RECORD_MAX;

/// The map's scratch buffer, aligned for the flash's write word (the F405's internal flash
/// and the mock both need at least 4).
#[repr(align(8))]
struct Buffer([u8; FLASH_BUFFER]);

impl Buffer {
    const fn new() -> Self {
        Self([0; FLASH_BUFFER])
    }
}

/// The two slots' map keys (parameter keys are 100…999, the old format's item keys).
const SLOTS: [u16; 2] = [0xFE00, 0xFE01];
/// Record format version.
const VERSION: u8 = 4;
/// The version whose key was the binding phrase's hash: its pairs load, not its link.
const VERSION_PHRASE_KEY: u8 = 3;
/// The version before the link key: its pairs load, not its link.
const VERSION_NO_KEY: u8 = 2;
/// Longest record: version, generation, count, pairs, key flag and key, CRC.
pub const RECORD_MAX: usize = 1 + 4 + 2 + 6 * super::params::COUNT + 1 + KEY_BYTES + 4;

/// A storage failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError {
    /// The flash driver failed, the area is full or corrupt; the settings in RAM are intact.
    /// (Also a record that did not fit `RECORD_MAX`, which the bound's formula rules out:
    /// nothing is written rather than a record cut short.)
    Flash,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("settings flash failure")
    }
}

impl core::error::Error for StoreError {}

/// What went wrong with the stored settings (the set loaded is still whole: see each case).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LoadProblem {
    /// No usable record although something was stored: factory settings.
    Corrupt,
    /// One slot holds a damaged record; the other slot's whole set loaded (it may be one
    /// generation older than the last save).
    CopyDamaged,
    /// Only the old one-item-per-parameter format is stored: factory settings.
    OldFormat,
    /// The newest record is intact but breaks a cross-setting rule: factory settings.
    Invalid(InvalidSettings),
    /// The record holds values today's table refuses (a range narrowed, a key retired);
    /// those parameters have their factory values.
    Refused,
}

impl core::fmt::Display for LoadProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LoadProblem::Corrupt => f.write_str("stored settings corrupt, factory settings"),
            LoadProblem::CopyDamaged => {
                f.write_str("one settings copy damaged, the other loaded (may be older)")
            }
            LoadProblem::OldFormat => {
                f.write_str("settings in the old format, factory settings (save to convert)")
            }
            LoadProblem::Invalid(e) => {
                write!(f, "stored settings cannot run ({e}), factory settings")
            }
            LoadProblem::Refused => f.write_str("some stored values refused, factory values"),
        }
    }
}

/// What `load` found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadReport {
    /// Parameters read from flash.
    pub loaded: u16,
    /// Stored values refused by today's range checks (they keep their defaults).
    pub refused: u16,
    /// Generation of the loaded record (0 = none loaded).
    pub generation: u32,
    /// Anything the console and telemetry should say; `None` = the stored set, whole.
    pub problem: Option<LoadProblem>,
}

/// IEEE CRC-32 (reflected, polynomial 0xEDB88320), bitwise: the record is read once per boot
/// (the resume record, `flight_app::app::resume`, reuses it).
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |crc, &b| crc32_step(crc, b))
}

/// [`crc32`] of the words' little-endian bytes (the resume record's blocks).
pub fn crc32_words(words: &[u32]) -> u32 {
    !words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .fold(!0u32, crc32_step)
}

/// One byte into a running CRC-32.
fn crc32_step(mut crc: u32, b: u8) -> u32 {
    crc ^= u32::from(b);
    for _ in 0..8 {
        crc = if crc & 1 != 0 {
            (crc >> 1) ^ 0xEDB8_8320
        } else {
            crc >> 1
        };
    }
    crc
}

/// Serialises `settings` as generation `generation`; returns the record.
/// (The record tests read it through `encode`, copied into a whole buffer.)
///
/// # Errors
/// [`StoreError::Flash`] if the record outgrew [`RECORD_MAX`] (ruled out by the bound's
/// formula): refused rather than stored cut short.
pub fn record(
    settings: &Settings,
    generation: u32,
) -> Result<heapless::Vec<u8, RECORD_MAX>, StoreError> {
    let mut out: heapless::Vec<u8, RECORD_MAX> = heapless::Vec::new();
    let mut put = |bytes: &[u8]| out.extend_from_slice(bytes).map_err(|_| StoreError::Flash);
    put(&[VERSION])?;
    put(&generation.to_le_bytes())?;
    put(&(PARAMS.len() as u16).to_le_bytes())?;
    for (p, v) in settings.iter() {
        put(&p.key.to_le_bytes())?;
        put(&v.to_bits().to_le_bytes())?;
    }
    match settings.link_key() {
        Some(key) => {
            put(&[1])?;
            put(&key.to_bytes())?;
        }
        None => put(&[0])?,
    }
    let crc = crc32(&out);
    out.extend_from_slice(&crc.to_le_bytes())
        .map_err(|_| StoreError::Flash)?;
    Ok(out)
}

/// The record tests' view of [`record`]: copied into `out`, its length returned.
#[cfg(test)]
fn encode(settings: &Settings, generation: u32, out: &mut [u8; RECORD_MAX]) -> usize {
    let bytes = record(settings, generation).unwrap();
    out[..bytes.len()].copy_from_slice(&bytes);
    bytes.len()
}

/// A decoded record.
pub struct Record {
    generation: u32,
    /// The settings it holds (values the table refused at their factory value).
    pub settings: Settings,
    loaded: u16,
    /// How many of its values the table refused.
    pub refused: u16,
}

/// Parses and checks a record (CRC, version, length); values go through the table's checks.
pub fn decode(bytes: &[u8]) -> Option<Record> {
    let (body, crc) = bytes.split_at_checked(bytes.len().checked_sub(4)?)?;
    if crc32(body).to_le_bytes() != *crc {
        return None;
    }
    let (&version, rest) = body.split_first()?;
    if version != VERSION && version != VERSION_PHRASE_KEY && version != VERSION_NO_KEY {
        return None;
    }
    let (generation, rest) = rest.split_first_chunk::<4>()?;
    let (count, rest) = rest.split_first_chunk::<2>()?;
    let count = usize::from(u16::from_le_bytes(*count));
    let (pairs, key) = rest.split_at_checked(6 * count)?;
    let link_key = match (version, key) {
        (VERSION_NO_KEY, []) | (VERSION | VERSION_PHRASE_KEY, [0]) => None,
        (VERSION | VERSION_PHRASE_KEY, [1, key @ ..]) => {
            Some(LinkKey::from_bytes(key.try_into().ok()?))
        }
        _ => return None,
    };
    // A link bound before the key agreement is no link now (module doc).
    let link_key = link_key.filter(|_| version == VERSION);
    let mut record = Record {
        generation: u32::from_le_bytes(*generation),
        settings: Settings::default(),
        loaded: 0,
        refused: 0,
    };
    record.settings.set_link_key(link_key);
    for pair in pairs.chunks_exact(6) {
        let (key, bits) = pair.split_first_chunk::<2>()?;
        let bits: [u8; 4] = bits.try_into().ok()?;
        match record
            .settings
            .set_by_key(u16::from_le_bytes(*key), u32::from_le_bytes(bits))
        {
            Ok(()) => record.loaded += 1,
            Err(_) => record.refused += 1,
        }
    }
    if version != VERSION {
        record
            .settings
            .apply(&[super::handles::LINK_BIND_ID.to(0)])
            .ok()?;
    }
    Some(record)
}

/// What one slot holds. (No heap to box the record in; two of these live briefly on the
/// stack at boot and during a save.)
#[allow(clippy::large_enum_variant)]
enum Slot {
    Empty,
    Damaged,
    Record(Record),
}

async fn read_slot<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    key: u16,
) -> Result<Slot, StoreError> {
    let mut buf = Buffer::new();
    match map.fetch_item::<&[u8]>(&mut buf.0, &key).await {
        Ok(None) => Ok(Slot::Empty),
        Ok(Some(bytes)) => Ok(decode(bytes).map_or(Slot::Damaged, Slot::Record)),
        Err(sequential_storage::Error::Corrupted { .. })
        | Err(sequential_storage::Error::SerializationError(_)) => Ok(Slot::Damaged),
        Err(_) => Err(StoreError::Flash),
    }
}

/// Both slots, read in turn (one read in the image for `load` and `save_whole`).
async fn read_slots<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
) -> Result<[Slot; 2], StoreError> {
    let mut slots = [Slot::Empty, Slot::Empty];
    for (slot, key) in slots.iter_mut().zip(SLOTS) {
        *slot = read_slot(map, key).await?;
    }
    Ok(slots)
}

/// The record of higher generation (the second on a tie), if either slot holds one.
fn newest(slots: [Slot; 2]) -> Option<Record> {
    match slots {
        [Slot::Record(x), Slot::Record(y)] => Some(if x.generation > y.generation { x } else { y }),
        [Slot::Record(r), _] | [_, Slot::Record(r)] => Some(r),
        _ => None,
    }
}

/// Whether every byte of the settings area reads erased (0xFF): nothing was ever stored.
async fn area_erased<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
) -> Result<bool, StoreError> {
    let range = map.flash_range();
    let mut chunk = [0u8; 64];
    let mut address = range.start;
    while address < range.end {
        let n = (range.end - address).min(64);
        // 64 and any remainder of a flash range are multiples of every read size in use.
        let Some(buf) = chunk.get_mut(..n as usize) else {
            return Err(StoreError::Flash);
        };
        map.flash()
            .read(address, buf)
            .await
            .map_err(|_| StoreError::Flash)?;
        if buf.iter().any(|&b| b != 0xFF) {
            return Ok(false);
        }
        address += n;
    }
    Ok(true)
}

/// Whether any old-format item (one per parameter key) is stored. Read as bytes, as the
/// slots are: one instance of the map's fetch in the image, not a second one for `u32`.
async fn old_format_present<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
) -> bool {
    for p in PARAMS {
        let mut buf = Buffer::new();
        if let Ok(Some(_)) = map.fetch_item::<&[u8]>(&mut buf.0, &p.key).await {
            return true;
        }
    }
    false
}

/// Loads the newest whole, valid record into `settings` — or the factory set, with the
/// reason in [`LoadReport::problem`]. `settings` is only written once the outcome is known.
pub async fn load<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &mut Settings,
) -> Result<LoadReport, StoreError> {
    let slots = read_slots(map).await?;
    let damaged = slots.iter().any(|s| matches!(s, Slot::Damaged));
    let mut report = LoadReport::default();
    let Some(record) = newest(slots) else {
        *settings = Settings::default();
        report.problem = if damaged {
            Some(LoadProblem::Corrupt)
        } else if old_format_present(map).await {
            Some(LoadProblem::OldFormat)
        } else if !area_erased(map).await? {
            // Written, yet no record to be found: sequential-storage skips items whose own
            // CRC fails, so two damaged copies read as "nothing stored". Only a blank area
            // (a new board) is the factory set without complaint.
            Some(LoadProblem::Corrupt)
        } else {
            None
        };
        return Ok(report);
    };
    if let Err(e) = record.settings.check() {
        *settings = Settings::default();
        report.problem = Some(LoadProblem::Invalid(e));
        return Ok(report);
    }
    report.loaded = record.loaded;
    report.refused = record.refused;
    report.generation = record.generation;
    report.problem = if damaged {
        Some(LoadProblem::CopyDamaged)
    } else if record.refused > 0 {
        Some(LoadProblem::Refused)
    } else {
        None
    };
    *settings = record.settings;
    Ok(report)
}

/// The boot-time load, as the firmware's storage task and the simulators do it: [`load`],
/// where a store that cannot be read at all (the map itself fails) counts as
/// [`LoadProblem::Corrupt`] with the factory set — the flight controller boots on defaults
/// and refuses to arm until a save; it never stops. The flash error, if any, comes back
/// beside the report for the log.
pub async fn load_at_boot<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &mut Settings,
) -> (LoadReport, Option<StoreError>) {
    match load(map, settings).await {
        Ok(report) => (report, None),
        Err(e) => {
            *settings = Settings::default();
            let report = LoadReport {
                problem: Some(LoadProblem::Corrupt),
                ..LoadReport::default()
            };
            (report, Some(e))
        }
    }
}

/// Writes `settings` as a new generation when it differs from `stored` (what flash holds
/// now), into the slot not holding the newest record; returns how many parameters changed
/// (the link key counts as one; 0 = nothing written). Call only while disarmed: on the F405 a sector erase stalls
/// instruction fetch.
pub async fn save<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &Settings,
    stored: &Settings,
) -> Result<u16, StoreError> {
    let changed = settings
        .iter()
        .zip(stored.iter())
        .filter(|((_, v), (_, old))| v.to_bits() != old.to_bits())
        .count() as u16
        + u16::from(settings.link_key() != stored.link_key());
    if changed == 0 {
        return Ok(0);
    }
    save_whole(map, settings).await?;
    Ok(changed)
}

/// Writes `settings` as a new generation whatever flash holds — after a boot-time load
/// problem, when the stored copy is damaged or is not the set in use. Same commit order
/// as [`save`].
pub async fn save_whole<S: NorFlash, C: CacheImpl<u16>>(
    map: &mut MapStorage<u16, S, C>,
    settings: &Settings,
) -> Result<(), StoreError> {
    let [a, b] = SLOTS;
    let [ga, gb] = read_slots(map).await?.map(|s| match s {
        Slot::Record(r) => Some(r.generation),
        _ => None,
    });
    // Overwrite the slot that does not hold the newest whole record.
    let (target, newest) = match (ga, gb) {
        (Some(x), Some(y)) if x >= y => (b, x),
        (Some(x), None) => (b, x),
        (_, Some(y)) => (a, y),
        (None, None) => (a, 0),
    };
    let record = record(settings, newest.wrapping_add(1))?;
    let record: &[u8] = &record;
    // First the slot without the newest record: once it is whole, the new set is committed.
    // Then the same record into the other slot, so a damaged copy later still leaves the
    // newest set readable instead of bringing back the previous one.
    let other = if target == a { b } else { a };
    for slot in [target, other] {
        let mut buf = Buffer::new();
        map.store_item(&mut buf.0, &slot, &record)
            .await
            .map_err(|_| StoreError::Flash)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
