//! Both ends bound, as after a bind, through the images' own settings flash. The pairing is
//! flight-sitl's (`flight_sitl::world::module_settings` and `pair_flight_settings`: the
//! module's factory settings with a bind ID at the scenario's rate, the flight side storing
//! the module's link and its key), plus, with a phrase, what a bind on it leaves (spec
//! §12.1: the module's key, salt and phrase derivation); each end's settings are then
//! written with the firmware's own storage code — `flight_app::settings::save_whole` into
//! the sequential-storage map of flight sectors 2–3, module-core's `SettingsStore::save`
//! into the module's eight pages — onto flash of the same geometry, and those bytes are
//! programmed into the emulated flash before power-on. The images boot into exactly what a
//! pilot's boards hold after the phrase typed at the module, `bind PHRASE` and the long
//! press: the least artificial way in, as the images' consoles are not reachable without a
//! USB host.

use core::ops::Range;

use embassy_futures::block_on;
use embedded_storage_async::nor_flash::{
    ErrorType, MultiwriteNorFlash, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use flight_app::settings::Settings;
use flight_sitl::Scenario;
use sequential_storage::cache::Cache;
use sequential_storage::map::{MapConfig, MapStorage};
use telemetry::link::{Entropy, LinkKey};

/// The flight settings' flash: sectors 2–3 (flight-fw `tasks/storage.rs`: offsets
/// 0x8000..0x1_0000 of bank 1 region 1, which starts at 0x0800_0000; 16 KiB sectors,
/// 4-byte writes in embassy-stm32's F405 flash).
pub const FLIGHT_SETTINGS: Range<u32> = 0x8000..0x1_0000;
/// Where bank 1 region 1 starts.
pub const FLIGHT_FLASH_BASE: u32 = 0x0800_0000;
/// The module's settings pages (module-fw `board.rs` `SETTINGS_FLASH`; NVMC pages of 4 KiB,
/// 4-byte writes).
pub const MODULE_SETTINGS: Range<u32> = 0xEC000..0xF4000;

/// A NOR flash window `[base, base + len)` with the geometry `W` (write) and `E` (erase):
/// programming only clears bits, erasing sets a whole sector to 0xFF.
#[derive(Debug, Clone)]
pub struct FlashWindow<const W: usize, const E: usize> {
    range: Range<u32>,
    bytes: Vec<u8>,
}

/// An access outside the window or not aligned to the geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlashError(NorFlashErrorKind);

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

impl<const W: usize, const E: usize> FlashWindow<W, E> {
    /// An erased window over `range`.
    pub fn erased(range: Range<u32>) -> Self {
        let len = range.end.saturating_sub(range.start) as usize;
        Self {
            range,
            bytes: vec![0xFF; len],
        }
    }

    /// Its bytes, from `range.start`.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Fills the window with `bytes` (a read-back of the real flash).
    ///
    /// # Errors
    /// When the length differs from the window's.
    pub fn load(&mut self, bytes: &[u8]) -> Result<(), FlashError> {
        if bytes.len() != self.bytes.len() {
            return Err(FlashError(NorFlashErrorKind::OutOfBounds));
        }
        self.bytes.copy_from_slice(bytes);
        Ok(())
    }

    fn span(&self, offset: u32, len: usize) -> Result<Range<usize>, FlashError> {
        let start = offset
            .checked_sub(self.range.start)
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))? as usize;
        let end = start + len;
        (end <= self.bytes.len())
            .then_some(start..end)
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))
    }
}

impl<const W: usize, const E: usize> ErrorType for FlashWindow<W, E> {
    type Error = FlashError;
}

impl<const W: usize, const E: usize> ReadNorFlash for FlashWindow<W, E> {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        let span = self.span(offset, bytes.len())?;
        let src = self
            .bytes
            .get(span)
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.range.end as usize
    }
}

impl<const W: usize, const E: usize> NorFlash for FlashWindow<W, E> {
    const WRITE_SIZE: usize = W;
    const ERASE_SIZE: usize = E;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        if !(from as usize).is_multiple_of(E) || !(to as usize).is_multiple_of(E) {
            return Err(FlashError(NorFlashErrorKind::NotAligned));
        }
        let span = self.span(from, to.saturating_sub(from) as usize)?;
        self.bytes
            .get_mut(span)
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))?
            .fill(0xFF);
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        if !(offset as usize).is_multiple_of(W) || !bytes.len().is_multiple_of(W) {
            return Err(FlashError(NorFlashErrorKind::NotAligned));
        }
        let span = self.span(offset, bytes.len())?;
        let dst = self
            .bytes
            .get_mut(span)
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))?;
        for (d, s) in dst.iter_mut().zip(bytes) {
            *d &= *s;
        }
        Ok(())
    }
}

/// A word may be programmed again (bits only clear), as on the F405 and the nRF52840's NVMC.
impl<const W: usize, const E: usize> MultiwriteNorFlash for FlashWindow<W, E> {}

/// Both ends' settings for `scenario`, bound as flight-sitl's world binds them. With
/// `phrase`, as after a bind on it (spec §12.1): the module holds its module key (drawn from
/// the scenario's seed, as the firmware draws it from its RNG), its phrase salt and the
/// phrase's derivation; the flight side the key of its link, as the key agreement hands it
/// over — the phrase itself is stored on neither end. Without one, the unauthenticated link
/// by both ends' explicit settings.
///
/// # Errors
///
/// A phrase the strength rule refuses (`telemetry::link::check_phrase`), in words.
pub fn bound_pair(
    scenario: &Scenario,
    phrase: Option<&str>,
) -> Result<(Settings, module_core::settings::Settings), String> {
    let mut module = flight_sitl::world::module_settings(scenario);
    if let Some(phrase) = phrase {
        let mut entropy = Entropy::new(seed_bytes(scenario.seed));
        let key = entropy.draw(b"module key");
        let salt = entropy.draw(b"phrase salt");
        module.link_key = Some(LinkKey::from_bytes(head(&key)));
        module.phrase_salt = head(&salt);
        module.plain = false;
        module
            .set_text("phrase", phrase)
            .map_err(|e| format!("binding phrase {phrase:?}: {e}"))?;
    }
    let mut flight = scenario.settings.clone();
    flight_sitl::world::pair_flight_settings(&mut flight, &module);
    Ok((flight, module))
}

/// The scenario seed as the 32 bytes an [`Entropy`] starts from.
fn seed_bytes(seed: u64) -> [u8; 32] {
    let seed = seed.to_le_bytes();
    core::array::from_fn(|i| seed.get(i).copied().unwrap_or(0))
}

/// The first `N` bytes of a draw.
fn head<const N: usize>(bytes: &[u8; 32]) -> [u8; N] {
    bytes.first_chunk::<N>().copied().unwrap_or([0; N])
}

/// The flight settings' sectors holding `settings` as the firmware stores them: (address,
/// bytes) to program.
///
/// # Errors
/// When flight-core's store refuses (it does not for a valid set).
pub fn flight_flash(settings: &Settings) -> Result<(u32, Vec<u8>), String> {
    let flash = FlashWindow::<4, 16_384>::erased(FLIGHT_SETTINGS);
    let config =
        MapConfig::try_new(FLIGHT_SETTINGS).map_err(|_| "flight settings range".to_owned())?;
    let mut map: MapStorage<u16, _, _> = MapStorage::new(flash, config, Cache::new_uncached());
    block_on(flight_app::settings::save_whole(&mut map, settings))
        .map_err(|e| format!("flight settings: {e:?}"))?;
    let (flash, _) = map.destroy();
    Ok((
        FLIGHT_FLASH_BASE + FLIGHT_SETTINGS.start,
        flash.bytes().to_vec(),
    ))
}

/// The module's settings pages holding `settings` as module-fw stores them.
///
/// # Errors
/// When module-core's store refuses.
pub fn module_flash(settings: &module_core::settings::Settings) -> Result<(u32, Vec<u8>), String> {
    let flash = FlashWindow::<4, 4_096>::erased(MODULE_SETTINGS);
    let mut store = module_core::settings::SettingsStore::new(flash, MODULE_SETTINGS)
        .map_err(|e| format!("module settings: {e:?}"))?;
    block_on(store.save(settings)).map_err(|e| format!("module settings: {e:?}"))?;
    Ok((MODULE_SETTINGS.start, store.release().bytes().to_vec()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_app::control::mixer::QUAD_X;
    use flight_sitl::PilotInput;
    use quad_sim::quad::QuadParams;

    const PHRASE: &str = "amber kettle under the oak";

    fn scenario() -> Scenario {
        Scenario::new(
            Settings::default(),
            QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X),
            1.0,
            Box::new(|_| PilotInput::default()),
        )
    }

    #[test]
    fn both_ends_read_back_bound_with_the_phrase_by_their_own_load() {
        let s = scenario();
        let (flight, module) = bound_pair(&s, Some(PHRASE)).unwrap();
        assert_ne!(module.bind_id, 0);
        // The flight side holds its link's key of the module key; the module the phrase's
        // derivation under its salt, never the phrase.
        let module_key = module.link_key.unwrap();
        let link = module_core::air::link_params(&module).unwrap();
        assert_eq!(flight.link_key(), Some(module_key.for_link(link.bind_id)));
        assert_eq!(
            module.phrase_prs,
            Some(telemetry::link::phrase::PhraseSecret::derive(PHRASE, module.phrase_salt).prs)
        );
        // The flight side, loaded as the firmware's storage task does at boot.
        let (addr, bytes) = flight_flash(&flight).unwrap();
        assert_eq!(addr, 0x0800_8000);
        assert_eq!(bytes.len(), 0x8000);
        let mut window = FlashWindow::<4, 16_384>::erased(FLIGHT_SETTINGS);
        window.bytes.copy_from_slice(&bytes);
        let config = MapConfig::try_new(FLIGHT_SETTINGS).unwrap();
        let mut map: MapStorage<u16, _, _> = MapStorage::new(window, config, Cache::new_uncached());
        let mut loaded = Settings::default();
        let (report, unreadable) =
            block_on(flight_app::settings::load_at_boot(&mut map, &mut loaded));
        assert!(
            unreadable.is_none() && report.problem.is_none(),
            "{report:?}"
        );
        assert_eq!(loaded, flight);
        // The module, loaded by its store.
        let (addr, bytes) = module_flash(&module).unwrap();
        assert_eq!(addr, 0xEC000);
        let mut window = FlashWindow::<4, 4_096>::erased(MODULE_SETTINGS);
        window.bytes.copy_from_slice(&bytes);
        let mut store = module_core::settings::SettingsStore::new(window, MODULE_SETTINGS).unwrap();
        let back = block_on(store.load()).unwrap();
        assert_eq!(back, Some(module));
    }

    #[test]
    fn a_phrase_the_strength_rule_refuses_binds_nothing() {
        let err = bound_pair(&scenario(), Some("short")).unwrap_err();
        assert!(err.contains("binding phrase"), "{err}");
        let (flight, module) = bound_pair(&scenario(), None).unwrap();
        assert_eq!((flight.link_key(), module.link_key), (None, None));
        assert!(module.plain);
    }

    #[test]
    fn the_window_behaves_as_nor_flash() {
        let mut f = FlashWindow::<4, 4_096>::erased(0x1000..0x3000);
        block_on(f.write(0x1004, &[0x0F, 0xF0, 0x00, 0xFF])).unwrap();
        block_on(f.write(0x1004, &[0xFF, 0x3C, 0xFF, 0x0F])).unwrap();
        let mut got = [0u8; 4];
        block_on(f.read(0x1004, &mut got)).unwrap();
        assert_eq!(got, [0x0F, 0x30, 0x00, 0x0F], "writes only clear bits");
        assert!(block_on(f.write(0x1002, &[0; 4])).is_err(), "unaligned");
        assert!(block_on(f.write(0x0FFC, &[0; 4])).is_err(), "outside");
        block_on(f.erase(0x1000, 0x2000)).unwrap();
        block_on(f.read(0x1004, &mut got)).unwrap();
        assert_eq!(got, [0xFF; 4]);
    }
}
