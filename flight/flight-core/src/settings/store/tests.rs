use super::*;
use crate::settings::Value;
use embassy_futures::block_on;
use sequential_storage::cache::Cache;
use sequential_storage::map::MapConfig;
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

type Flash = MockFlashBase<4, 4, 256>; // 4 pages of 1 KiB

fn map(flash: Flash) -> MapStorage<u16, Flash, impl CacheImpl<u16>> {
    let config = MapConfig::try_new(Flash::FULL_FLASH_RANGE).unwrap();
    MapStorage::new(flash, config, Cache::new_uncached())
}

fn boot(flash: Flash) -> (Settings, LoadReport) {
    let mut m = map(flash);
    let mut s = Settings::default();
    // Something in RAM before: load must replace all of it.
    s.set_text("pid.yaw.kp", "0.5").unwrap();
    let report = block_on(load(&mut m, &mut s)).unwrap();
    (s, report)
}

/// A distinct valid set per generation: a bind (the five `link.*` values) and gains.
fn generation_set(n: u32) -> Settings {
    let mut s = Settings::default();
    s.set_many(&[
        ("link.bind_id", Value::U32(0x1000 + n)),
        ("link.band", Value::U32(n % 3)),
        ("link.rate", Value::U32(n % 4)),
        ("link.channels", Value::U32(n % 2)),
        ("link.telemetry_ratio", Value::U32(2 << (n % 6))),
        ("pid.roll.kp", Value::F32(0.001 * (n % 997) as f32)),
    ])
    .unwrap();
    s
}

#[test]
fn round_trip_and_nothing_written_without_a_change() {
    let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
    let defaults = Settings::default();
    let mut s = defaults.clone();
    s.set_text("pid.roll.kp", "0.0042").unwrap();
    s.set_text("output.protocol", "oneshot125").unwrap();
    assert_eq!(block_on(save(&mut m, &s, &defaults)), Ok(2));
    assert_eq!(block_on(save(&mut m, &s, &s)), Ok(0));
    let (flash, _) = m.destroy();
    let (loaded, report) = boot(flash);
    assert_eq!(loaded, s);
    assert_eq!(report.problem, None);
    assert_eq!(report.generation, 1);
    assert_eq!(report.loaded as usize, crate::settings::PARAMS.len());
}

#[test]
fn an_empty_store_is_the_factory_set_without_complaint() {
    let (s, report) = boot(Flash::default());
    assert_eq!(s, Settings::default());
    assert_eq!(report, LoadReport::default());
}

#[test]
fn the_old_per_parameter_format_loads_as_factory_settings_with_an_error() {
    let mut m = map(Flash::default());
    let mut buf = Buffer::new();
    block_on(m.store_item(&mut buf.0, &500u16, &3u32)).unwrap();
    let (flash, _) = m.destroy();
    let (s, report) = boot(flash);
    assert_eq!(s, Settings::default());
    assert_eq!(report.problem, Some(LoadProblem::OldFormat));
}

#[test]
fn a_stored_set_that_cannot_run_loads_as_factory_settings_with_the_reason() {
    // PWM at 32 kHz, as the old console accepted.
    let mut bad = Settings::default();
    bad.set_by_key(100, 1).unwrap();
    let mut record = [0u8; RECORD_MAX];
    let len = encode(&bad, 7, &mut record);
    let mut m = map(Flash::default());
    let mut buf = Buffer::new();
    block_on(m.store_item(&mut buf.0, &SLOTS[0], &&record[..len])).unwrap();
    let (flash, _) = m.destroy();
    let (s, report) = boot(flash);
    assert_eq!(s, Settings::default());
    assert!(
        matches!(report.problem, Some(LoadProblem::Invalid(_))),
        "{report:?}"
    );
}

/// Cuts the power after every possible number of written bytes during a save that changes
/// the five `link.*` values and a gain at once, then boots: the old set or the new one,
/// whole (the old per-parameter store could come back with some of each).
#[test]
fn power_cut_at_every_byte_of_a_save_leaves_the_old_or_the_new_set() {
    let old = generation_set(1);
    let new = generation_set(2);
    let mut cut_points = 0;
    for budget in 0..2_000u32 {
        let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
        block_on(save(&mut m, &old, &Settings::default())).unwrap();
        let (mut flash, _) = m.destroy();
        flash.bytes_until_shutoff = Some(budget);
        let mut m = map(flash);
        let finished = block_on(save(&mut m, &new, &old)).is_ok();
        let (mut flash, _) = m.destroy();
        flash.bytes_until_shutoff = None;
        let (booted, report) = boot(flash);
        assert!(
            booted == old || booted == new,
            "budget {budget}: a mix ({report:?})"
        );
        if finished {
            assert_eq!(booted, new);
            break;
        }
        cut_points += 1;
    }
    assert!(cut_points > 20, "the save was cut at {cut_points} points");
}

/// xorshift64*: deterministic test randomness.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Several committed generations, then random damage — bit flips, an erased page, a torn
/// (power-cut) save — and a boot: always one whole committed set (or the interrupted one,
/// whole) or the factory set, never a mix. After a torn save an older set never loads
/// unreported. Bit flips and an erased page can bring back the previous generation only when
/// they destroy *both* copies of the newest record (the documented limit): every silent
/// older set after bit flips is checked to need two or more of its flips — each flip alone
/// still boots the newest set.
#[test]
fn random_corruption_never_loads_a_mix() {
    let mut rng = Rng(0x5EED_1234_ABCD_0001);
    let (mut newest_with_problem, mut defaults_seen, mut clean) = (0, 0, 0);
    let mut silent = [0; 3];
    let mut interrupted_but_whole = 0;
    for trial in 0..300 {
        let generations = 1 + rng.below(6) as u32;
        let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
        let mut stored = Settings::default();
        let mut committed = vec![Settings::default()];
        for n in 1..=generations {
            let s = generation_set(n + 10 * trial);
            block_on(save(&mut m, &s, &stored)).unwrap();
            committed.push(s.clone());
            stored = s;
        }
        let (mut flash, _) = m.destroy();
        let undamaged = flash.clone();
        let mut flips = Vec::new();
        let kind = rng.below(3);
        let mut maybe = None;
        match kind {
            0 => {
                for _ in 0..1 + rng.below(4) {
                    let bytes = flash.as_bytes_mut();
                    let at = rng.below(bytes.len());
                    let bit = 1 << rng.below(8);
                    bytes[at] ^= bit;
                    flips.push((at, bit));
                }
            }
            1 => {
                let page = rng.below(4);
                flash.as_bytes_mut()[page * 1024..(page + 1) * 1024].fill(0xFF);
            }
            _ => {
                flash.bytes_until_shutoff = Some(rng.below(600) as u32);
                let mut m = map(flash);
                let next = generation_set(1000 + trial);
                // A cut after the record's last byte can still report a failure (a later
                // step was cut): then the record is whole and loads, which is fine — it is
                // the set that was being saved, complete.
                let ok = block_on(save(&mut m, &next, &stored)).is_ok();
                if ok {
                    committed.push(next);
                } else {
                    maybe = Some(next);
                }
                let (f, _) = m.destroy();
                flash = f;
                flash.bytes_until_shutoff = None;
            }
        }
        // An erased page that held everything leaves a blank area: physically a new board.
        let blank = flash.as_bytes().iter().all(|&b| b == 0xFF);
        let mut m = map(flash);
        let mut booted = Settings::default();
        let report = match block_on(load(&mut m, &mut booted)) {
            Ok(r) => r,
            // The map itself refusing to read: the firmware flies on defaults.
            Err(StoreError::Flash) => {
                defaults_seen += 1;
                continue;
            }
        };
        if maybe.as_ref() == Some(&booted) {
            interrupted_but_whole += 1;
            continue;
        }
        let last = committed.last().unwrap();
        assert!(
            committed.contains(&booted),
            "trial {trial} (damage {kind}): not a committed set ({report:?})"
        );
        if booted != *last {
            if report.problem.is_none() {
                silent[kind] += 1;
                if kind == 0 {
                    // Only damage to both copies may do this: no single flip does.
                    assert!(
                        flips.len() >= 2,
                        "trial {trial}: one flip brought back an older set"
                    );
                    for &(at, bit) in &flips {
                        let mut one = undamaged.clone();
                        one.as_bytes_mut()[at] ^= bit;
                        let (alone, _) = boot(one);
                        assert_eq!(&alone, last, "trial {trial}: the flip at {at} alone");
                    }
                }
            }
            if booted == Settings::default() {
                defaults_seen += 1;
                // Factory settings after a save are never silent: the pilot must hear that
                // the stored set was lost.
                assert!(
                    blank || report.problem.is_some(),
                    "trial {trial} (damage {kind}): stored settings silently replaced by the factory set"
                );
            }
        } else if report.problem.is_some() {
            newest_with_problem += 1;
        } else {
            clean += 1;
        }
    }
    println!(
        "clean {clean}, newest with a problem {newest_with_problem}, defaults {defaults_seen}, silent older {silent:?}, interrupted but whole {interrupted_but_whole}"
    );
    assert_eq!(silent[2], 0, "a torn save brought back an older set");
    assert!(clean > 50);
}

/// After a boot-time problem the pilot's `defaults` + `save` must reach flash although the
/// set equals what `save` believes is stored: `save_whole` writes it, and the next boot
/// loads it cleanly instead of reporting the problem again.
#[test]
fn save_whole_fixes_a_problem_store_with_an_unchanged_set() {
    let mut m = map(Flash::default());
    let mut buf = Buffer::new();
    block_on(m.store_item(&mut buf.0, &500u16, &3u32)).unwrap();
    let defaults = Settings::default();
    assert_eq!(block_on(save(&mut m, &defaults, &defaults)), Ok(0));
    block_on(save_whole(&mut m, &defaults)).unwrap();
    let (flash, _) = m.destroy();
    let (s, report) = boot(flash);
    assert_eq!(s, defaults);
    assert_eq!(report.problem, None);
    assert_eq!(report.generation, 1);
}

/// Both copies damaged so that sequential-storage skips them as if nothing were stored: the
/// boot must report the store corrupt, not fly the factory set as if the board were new.
#[test]
fn two_damaged_copies_are_reported_not_taken_for_a_new_board() {
    let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
    let first = generation_set(1);
    block_on(save(&mut m, &first, &Settings::default())).unwrap();
    block_on(save(&mut m, &generation_set(2), &first)).unwrap();
    let (mut flash, _) = m.destroy();
    // Flip one bit in every 16th byte of the written pages: every item's CRC fails.
    let bytes = flash.as_bytes_mut();
    for (i, b) in bytes.iter_mut().enumerate() {
        if i % 16 == 8 && *b != 0xFF {
            *b ^= 0x10;
        }
    }
    let (s, report) = boot(flash);
    assert_eq!(s, Settings::default());
    assert_eq!(report.problem, Some(LoadProblem::Corrupt), "{report:?}");
}

/// A store the flash driver cannot read at all (here: a map configured past the end of the
/// mock flash, so every read fails) is no error the boot has to handle: `load_at_boot` gives
/// the factory set, whatever was in RAM, reported `Corrupt` (the app then refuses to arm
/// until a save), and the flash error for the log.
#[test]
fn an_unreadable_store_boots_the_factory_set_reported_corrupt() {
    let end = Flash::FULL_FLASH_RANGE.end;
    let config = MapConfig::try_new(end..end + Flash::FULL_FLASH_RANGE.len() as u32).unwrap();
    let flash = Flash::new(WriteCountCheck::OnceOnly, None, true);
    let mut m = MapStorage::new(flash, config, Cache::new_uncached());
    let mut s = generation_set(7);
    assert_eq!(
        block_on(load(&mut m, &mut s.clone())),
        Err(StoreError::Flash),
        "the store must be unreadable for this test"
    );
    let (report, error) = block_on(load_at_boot(&mut m, &mut s));
    assert_eq!(s, Settings::default());
    assert_eq!(report.problem, Some(LoadProblem::Corrupt));
    assert_eq!((report.loaded, report.generation), (0, 0));
    assert_eq!(error, Some(StoreError::Flash));
}

/// A readable store: `load_at_boot` is `load`, with no error beside the report.
#[test]
fn a_readable_store_boots_as_load_reads_it() {
    let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
    block_on(save(&mut m, &generation_set(3), &Settings::default())).unwrap();
    let mut s = Settings::default();
    let (report, error) = block_on(load_at_boot(&mut m, &mut s));
    assert_eq!(error, None);
    assert_eq!(s, generation_set(3));
    assert_eq!(report.problem, None);
    assert_eq!(report.generation, 1);
}

#[test]
fn the_link_key_is_saved_and_loaded_and_a_key_change_alone_is_a_change() {
    let mut m = map(Flash::new(WriteCountCheck::OnceOnly, None, true));
    let defaults = Settings::default();
    let mut s = defaults.clone();
    s.set_link_key(Some(LinkKey::from_bytes([0x4B; 16])));
    assert_eq!(block_on(save(&mut m, &s, &defaults)), Ok(1), "only the key");
    let (flash, _) = m.destroy();
    let (loaded, report) = boot(flash);
    assert_eq!(report.problem, None);
    assert_eq!(loaded.link_key(), Some(LinkKey::from_bytes([0x4B; 16])));
    assert_eq!(loaded, s);
    // Cleared again: a change too, and it loads as no key.
    let mut m = map(flash_of(&s));
    let mut cleared = s.clone();
    cleared.set_link_key(None);
    assert_eq!(block_on(save(&mut m, &cleared, &s)), Ok(1));
    let (flash, _) = m.destroy();
    assert_eq!(boot(flash).0.link_key(), None);
}

fn flash_of(s: &Settings) -> Flash {
    let mut m = map(Flash::default());
    block_on(save_whole(&mut m, s)).unwrap();
    m.destroy().0
}

/// A record as version 2 wrote it (no key field): what a controller updated to this
/// firmware finds in flash.
fn version_2_record(settings: &Settings, generation: u32) -> Vec<u8> {
    old_record(2, settings, generation, None)
}

/// A record of an older `version`, with the key field of version 3 when `key` is given.
fn old_record(version: u8, settings: &Settings, generation: u32, key: Option<[u8; 16]>) -> Vec<u8> {
    let mut body = vec![version];
    body.extend(generation.to_le_bytes());
    body.extend((PARAMS.len() as u16).to_le_bytes());
    for (p, v) in settings.iter() {
        body.extend(p.key.to_le_bytes());
        body.extend(v.to_bits().to_le_bytes());
    }
    if let Some(key) = key {
        body.push(1);
        body.extend(key);
    }
    let crc = crc32(&body);
    body.extend(crc.to_le_bytes());
    body
}

/// Records of versions 2 and 3 were bound by the protocol before the key agreement, and
/// version 3's key is the phrase's bare hash (issue 30, finding 1): their pairs load, the
/// link and the key do not.
#[test]
fn old_records_load_their_pairs_but_no_link_and_no_key() {
    let old = generation_set(3);
    assert_ne!(old.get(super::super::handles::LINK_BIND_ID), 0);
    for record in [
        old_record(2, &old, 9, None),
        old_record(3, &old, 9, Some([0x6C; 16])),
    ] {
        let mut m = map(Flash::default());
        let mut buf = Buffer::new();
        block_on(m.store_item(&mut buf.0, &SLOTS[0], &&record[..])).unwrap();
        let (flash, _) = m.destroy();
        let (loaded, report) = boot(flash);
        assert_eq!(report.problem, None);
        assert_eq!(report.generation, 9);
        assert_eq!(loaded.link_key(), None);
        assert_eq!(
            loaded.get(super::super::handles::LINK_BIND_ID),
            0,
            "unbound"
        );
        assert_eq!(
            loaded.get(super::super::handles::PID_GAINS[0][0]),
            old.get(super::super::handles::PID_GAINS[0][0]),
            "the other pairs as stored"
        );
    }
}

#[test]
fn a_version_2_record_loads_whole_with_no_key() {
    let old = generation_set(3);
    let record = version_2_record(&old, 9);
    let mut m = map(Flash::default());
    let mut buf = Buffer::new();
    block_on(m.store_item(&mut buf.0, &SLOTS[0], &&record[..])).unwrap();
    let (flash, _) = m.destroy();
    let (loaded, report) = boot(flash);
    assert_eq!(report.problem, None);
    assert_eq!(report.generation, 9);
    let mut unbound = old.clone();
    unbound
        .apply(&[super::super::handles::LINK_BIND_ID.to(0)])
        .unwrap();
    assert_eq!(loaded, unbound, "every pair as stored but the link");
    assert_eq!(loaded.link_key(), None);
    // A key field in a version-2 record, or a bad flag in version 3, is no record.
    let mut with_key = version_2_record(&old, 9);
    with_key.truncate(with_key.len() - 4);
    with_key.push(0);
    let crc = crc32(&with_key);
    with_key.extend(crc.to_le_bytes());
    assert!(decode(&with_key).is_none());
    let mut record = [0u8; RECORD_MAX];
    let len = encode(&old, 1, &mut record);
    let flag = len - 5;
    assert_eq!(record[flag], 0);
    record[flag] = 2;
    let crc = crc32(&record[..len - 4]);
    record[len - 4..len].copy_from_slice(&crc.to_le_bytes());
    assert!(decode(&record[..len]).is_none());
}

/// The mode-switch choices a controller stored before the flight mode became the wire's
/// type (ids 0…7 in `params::MODES` order) select the same modes after it: the stored number
/// is `FlightMode::id`, the wire's variant index.
#[test]
fn an_old_records_mode_switch_choices_select_the_same_modes() {
    use crate::pipeline::from_settings;
    use crate::supervisor::FlightMode;
    // The choice names and modes as the settings table and the setup mapped them then.
    let before = [
        ("rate-pid", FlightMode::RatePid),
        ("rate-lqg", FlightMode::RateLqg),
        ("attitude", FlightMode::Attitude),
        ("horizon", FlightMode::Horizon),
        ("sysid", FlightMode::SystemId),
        ("altitude-hold", FlightMode::AltitudeHold),
        ("position-hold", FlightMode::PositionHold),
        ("loiter", FlightMode::Loiter),
    ];
    assert_eq!(telemetry::settings::MODES.len(), before.len());
    for (id, (name, mode)) in (0u32..).zip(before) {
        assert_eq!(telemetry::settings::MODES[id as usize], name);
        let mut old = generation_set(1);
        // Any one of three positions: the others keep their (valid) values.
        let position = ["mode.switch_low", "mode.switch_mid", "mode.switch_high"][id as usize % 3];
        old.set_many(&[(position, Value::U32(id))]).unwrap();
        let mut m = map(Flash::default());
        let mut buf = Buffer::new();
        let record = version_2_record(&old, 5);
        block_on(m.store_item(&mut buf.0, &SLOTS[0], &&record[..])).unwrap();
        let (loaded, report) = boot(m.destroy().0);
        assert_eq!(report.problem, None);
        let modes = from_settings(&loaded).unwrap().loop_config.modes;
        assert_eq!(modes[id as usize % 3], mode, "stored choice {id} ({name})");
        assert_eq!(mode.id() as u32, id);
    }
}
