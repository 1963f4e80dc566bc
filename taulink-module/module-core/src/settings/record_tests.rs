//! The record's layout, every version's decode and the bytes no writer produces.

use super::*;
use crate::ppm::FailsafeOutput;
use crate::settings::openlrs::{LinkProtocol, OpenLrsSettings};
use crate::settings::{
    Band, DEFAULT_INPUT_TIMEOUT_MS, DEFAULT_TELEMETRY_RATIO, InputProtocol, OutputProtocol, Role,
};

#[test]
fn record_round_trip_and_layout() {
    let settings = Settings {
        role: Role::Receiver,
        rate: RateMode::F500,
        input: InputProtocol::Crsf,
        output: OutputProtocol::FrskyHub,
        band: Band::Mhz915,
        tx_power: 5,
        failsafe: FailsafeOutput::StopPulses,
        bind_id: 0xDEAD_BEEF,
        input_timeout_ms: 750,
        telemetry_ratio: 16,
        model_match: true,
        bound_models: (1 << 63) | (1 << 3),
        protocol: LinkProtocol::OpenLrs39,
        openlrs: OpenLrsSettings {
            frequency_hz: 0x3456_7890,
            profile: 4,
            channel_mode: 6,
            telemetry: false,
            hop_seed: 0xCAFE_F00D,
        },
        link_key: Some(LinkKey::from_bytes(core::array::from_fn(|i| {
            0xA0 + i as u8
        }))),
        phrase_salt: [0x51; 8],
        phrase_prs: Some([0x52; 32]),
        plain: true,
        dynamic_power: false,
        ble_pin: Pin::new(42_917),
    };
    let record = settings.to_record();
    assert_eq!(
        record[..RECORD_V5_LEN],
        [
            8, 1, 3, 1, 3, 2, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16, 1, 0x08, 0, 0, 0, 0, 0,
            0, 0x80, 2, 4, 6, 0, 0x90, 0x78, 0x56, 0x34, 0x0D, 0xF0, 0xFE, 0xCA
        ]
    );
    assert!(settings.model_bound(3) && settings.model_bound(63));
    assert!(!settings.model_bound(4) && !settings.model_bound(64));
    assert_eq!(
        record[RECORD_V5_LEN..RECORD_V5_LEN + 1 + 16],
        core::array::from_fn::<u8, 17, _>(|i| if i == 0 { 1 } else { 0xA0 + i as u8 - 1 })
    );
    assert_eq!(
        record[RECORD_V5_LEN + 17..RECORD_V6_LEN],
        42_917u32.to_le_bytes()
    );
    assert_eq!(record[RECORD_V6_LEN], 1, "a phrase");
    assert_eq!(record[RECORD_V6_LEN + 1..RECORD_V6_LEN + 9], [0x51; 8]);
    assert_eq!(record[RECORD_V6_LEN + 9..RECORD_V6_LEN + 41], [0x52; 32]);
    assert_eq!(record[RECORD_V6_LEN + 41], 1, "plain");
    assert_eq!(record[RECORD_V7_LEN], 0, "dynamic power off");
    assert_eq!(
        Settings::default().to_record()[RECORD_V7_LEN],
        1,
        "factory: on"
    );
    assert_eq!(Settings::from_record(&record), Ok(settings));
    assert_eq!(
        Settings::from_record(&Settings::default().to_record()),
        Ok(Settings::default())
    );
    // Every link rate mode is stored as its own code.
    for rate in RateMode::ALL {
        let s = Settings { rate, ..settings };
        assert_eq!(s.to_record()[2], rate.code());
        assert_eq!(Settings::from_record(&s.to_record()), Ok(s));
    }
    // The slower CRSF rate is input code 2 (older records never hold it).
    let slow = Settings {
        input: InputProtocol::Crsf115200,
        ..settings
    };
    assert_eq!(slow.to_record()[3], 2);
    assert_eq!(Settings::from_record(&slow.to_record()), Ok(slow));
    let fast = Settings {
        input: InputProtocol::Crsf921600,
        ..settings
    };
    assert_eq!(fast.to_record()[3], 3);
    assert_eq!(Settings::from_record(&fast.to_record()), Ok(fast));
}

#[test]
fn bad_records_are_errors() {
    assert_eq!(
        Settings::from_record(&[]),
        Err(DecodeError::Length { found: 0 })
    );
    assert_eq!(
        Settings::from_record(&[9; 100]),
        Err(DecodeError::Version { found: 9 })
    );
    // Each version with the length of the one before it.
    for (version, len) in [
        (8, 99),
        (7, 57),
        (6, 36),
        (5, 24),
        (4, 15),
        (3, 14),
        (2, 12),
        (1, 11),
    ] {
        assert_eq!(
            Settings::from_record(&vec![version; len]),
            Err(DecodeError::Length { found: len }),
            "version {version}, {len} bytes"
        );
    }
    // Model match is 0 or 1.
    let mut record = Settings::default().to_record();
    record[RECORD_V3_LEN] = 2;
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field {
            offset: RECORD_V3_LEN
        })
    );
    // A version 3 record loads with model match off and no models bound.
    let mut v3 = [0u8; RECORD_V3_LEN];
    v3.copy_from_slice(&Settings::default().to_record()[..RECORD_V3_LEN]);
    v3[0] = 3;
    assert_eq!(Settings::from_record(&v3), Ok(Settings::default()));
    let mut record = Settings::default().to_record();
    record[6] = 8;
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field { offset: 6 })
    );
    record[6] = 7;
    // Rate code 4 was 125 000 bit/s in version 2; in version 3 it is F700, and there is
    // no mode 5.
    record[2] = 4;
    assert_eq!(Settings::from_record(&record).unwrap().rate, RateMode::F700);
    record[2] = 5;
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field { offset: 2 })
    );
    record[2] = 2;
    for (timeout, ok) in [(99u16, false), (100, true), (2_000, true), (2_001, false)] {
        record[12..14].copy_from_slice(&timeout.to_le_bytes());
        assert_eq!(
            Settings::from_record(&record).map(|s| s.input_timeout_ms),
            if ok {
                Ok(timeout)
            } else {
                Err(DecodeError::Field { offset: 12 })
            }
        );
    }
    record[12..14].copy_from_slice(&500u16.to_le_bytes());
    for (ratio, ok) in [(0u8, false), (1, false), (2, true), (3, false), (128, true)] {
        record[14] = ratio;
        assert_eq!(
            Settings::from_record(&record).map(|s| s.telemetry_ratio),
            if ok {
                Ok(ratio)
            } else {
                Err(DecodeError::Field { offset: 14 })
            }
        );
    }
}

#[test]
fn version_3_records_load_as_taulink_and_the_link_tail_is_checked() {
    // A version-3 record as the previous firmware wrote it.
    let v3 = [
        3, 0, 3, 1, 2, 1, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16,
    ];
    let settings = Settings::from_record(&v3).unwrap();
    assert_eq!(settings.protocol, LinkProtocol::TauLink);
    assert_eq!(settings.openlrs, OpenLrsSettings::default());
    assert_eq!(
        (settings.rate, settings.band),
        (RateMode::F500, Band::Mhz868)
    );
    // Re-saved, every version-3 field keeps its byte but the bind ID (bound before the key
    // agreement: unbound now).
    assert_eq!(settings.to_record()[1..8], v3[1..8]);
    assert_eq!(settings.to_record()[8..12], [0; 4]);
    assert_eq!(settings.to_record()[12..RECORD_V3_LEN], v3[12..]);
    let mut record = Settings {
        protocol: LinkProtocol::OpenLrs38,
        ..Settings::default()
    }
    .to_record();
    assert_eq!(record[RECORD_V4_LEN..RECORD_V4_LEN + 4], [1, 2, 2, 1]);
    for (offset, bad) in [(24, 3u8), (25, 5), (26, 0), (26, 7), (27, 2)] {
        let mut r = record;
        r[offset] = bad;
        assert_eq!(
            Settings::from_record(&r),
            Err(DecodeError::Field { offset }),
            "byte {offset} = {bad}"
        );
    }
    // A carrier outside every OpenLRSng module range (1 GHz) is refused; 0 (band
    // default) and 868 MHz load.
    for (hz, ok) in [(1_000_000_000u32, false), (0, true), (868_000_000, true)] {
        record[28..32].copy_from_slice(&hz.to_le_bytes());
        assert_eq!(Settings::from_record(&record).is_ok(), ok, "{hz}");
    }
}

#[test]
fn the_ism_433_plan_is_band_3_in_version_3_only() {
    let ism = Settings {
        band: Band::Ism433,
        ..Settings::default()
    };
    assert_eq!(ism.to_record()[5], 3);
    assert_eq!(Settings::from_record(&ism.to_record()), Ok(ism));
    assert_eq!(
        Settings::default().band,
        Band::Mhz433,
        "factory: the amateur plan"
    );
    let v2 = [2, 0, 2, 0, 2, 3, 7, 1, 1, 0, 0, 0, 0xF4, 0x01];
    assert_eq!(
        Settings::from_record(&v2),
        Err(DecodeError::Field { offset: 5 })
    );
}

#[test]
fn old_bit_rates_map_to_the_link_mode_they_ran_as() {
    // Version 2 records (14 bytes) in the bit-rate vocabulary: 4800/9600/19 200 → L50,
    // 57 600 → M100, 125 000 → F250; the ratio is the factory one.
    let v2 = |rate: u8| {
        [
            2, 0, rate, 0, 2, 0, 7, 1, 0x78, 0x56, 0x34, 0x12, 0xF4, 0x01,
        ]
    };
    for (code, mode) in [
        (0, RateMode::L50),
        (1, RateMode::L50),
        (2, RateMode::L50),
        (3, RateMode::M100),
        (4, RateMode::F250),
    ] {
        let settings = Settings::from_record(&v2(code)).unwrap();
        assert_eq!(settings.rate, mode, "v2 code {code}");
        assert_eq!(settings.telemetry_ratio, DEFAULT_TELEMETRY_RATIO);
        assert_eq!(settings.input_timeout_ms, 500);
        assert_eq!(
            settings.bind_id, 0,
            "bound before the key agreement: unbound"
        );
        // Re-saved as the current version, the same settings come back.
        assert_eq!(settings.to_record()[0], RECORD_VERSION);
        assert_eq!(Settings::from_record(&settings.to_record()), Ok(settings));
    }
    assert_eq!(
        Settings::from_record(&v2(5)),
        Err(DecodeError::Field { offset: 2 })
    );
}

#[test]
fn the_factory_failsafe_stops_pulses_and_old_records_keep_their_meaning() {
    assert_eq!(Settings::default().failsafe, FailsafeOutput::StopPulses);
    assert_eq!(Settings::default().input_timeout_ms, 500);
    assert_eq!(Settings::default().rate, RateMode::L50);
    // Version-1 records as the first firmware wrote them: hold last (its default) stays
    // hold last, stop pulses stays stop pulses, and the input timeout is the default.
    let v1_hold = [1, 0, 2, 0, 2, 0, 7, 0, 0x78, 0x56, 0x34, 0x12];
    let settings = Settings::from_record(&v1_hold).unwrap();
    assert_eq!(settings.failsafe, FailsafeOutput::HoldLast);
    assert_eq!(
        settings.bind_id, 0,
        "bound before the key agreement: unbound"
    );
    assert_eq!(settings.rate, RateMode::L50, "19 200 bit/s ran as L50");
    assert_eq!(settings.input_timeout_ms, DEFAULT_INPUT_TIMEOUT_MS);
    let mut v1_stop = v1_hold;
    v1_stop[7] = 1;
    assert_eq!(
        Settings::from_record(&v1_stop).unwrap().failsafe,
        FailsafeOutput::StopPulses
    );
    // Re-saved, they become the current version with the same values.
    let upgraded = settings.to_record();
    assert_eq!(upgraded[0], RECORD_VERSION);
    assert_eq!(Settings::from_record(&upgraded), Ok(settings));
}

#[test]
fn a_version_3_record_loads_unbound_with_no_phrase_and_the_factory_pin() {
    let v3 = [
        3, 1, 3, 1, 3, 3, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16,
    ];
    let settings = Settings::from_record(&v3).unwrap();
    assert_eq!(settings.link_key, None);
    assert_eq!(settings.phrase(), None);
    assert_eq!(settings.ble_pin, None);
    assert_eq!(
        (
            settings.rate,
            settings.band,
            settings.bind_id,
            settings.telemetry_ratio
        ),
        (RateMode::F500, Band::Ism433, 0, 16)
    );
    let upgraded = settings.to_record();
    assert_eq!(upgraded[0], RECORD_VERSION);
    assert_eq!(upgraded[1..8], v3[1..8]);
    assert_eq!(Settings::from_record(&upgraded), Ok(settings));
}

/// Version 7 had no dynamic power: it loads with the factory value (on), its link and key
/// kept.
#[test]
fn a_version_7_record_keeps_its_link_and_gets_dynamic_power() {
    let bound = Settings {
        bind_id: 0xDEAD_BEEF,
        link_key: Some(LinkKey::from_bytes([0x6C; 16])),
        tx_power: 5,
        dynamic_power: false,
        ..Settings::default()
    };
    let mut v7 = bound.to_record()[..RECORD_V7_LEN].to_vec();
    v7[0] = 7;
    let settings = Settings::from_record(&v7).unwrap();
    assert_eq!(
        settings,
        Settings {
            dynamic_power: true,
            ..bound
        }
    );
}

/// Version 6 held a key hashed from the phrase alone (issue 30, finding 1): it loads
/// unbound, without its key or models, its other fields and PIN kept.
#[test]
fn a_version_6_record_loads_without_its_link_and_key() {
    let mut v6 = Settings {
        bind_id: 0xDEAD_BEEF,
        bound_models: 1 << 3,
        link_key: Some(LinkKey::from_bytes([0x6C; 16])),
        ble_pin: Pin::new(123_456),
        rate: RateMode::F250,
        ..Settings::default()
    }
    .to_record()[..RECORD_V6_LEN]
        .to_vec();
    v6[0] = 6;
    let settings = Settings::from_record(&v6).unwrap();
    assert_eq!(
        (settings.bind_id, settings.bound_models, settings.link_key),
        (0, 0, None)
    );
    assert_eq!(
        (settings.rate, settings.ble_pin),
        (RateMode::F250, Pin::new(123_456))
    );
}

#[test]
fn the_key_phrase_and_pin_fields_take_only_what_a_writer_produces() {
    let keyed = Settings {
        link_key: Some(LinkKey::from_bytes([0x61; 16])),
        ..Settings::default()
    };
    let mut record = keyed.to_record();
    assert_eq!(Settings::from_record(&record), Ok(keyed));
    let (flag, pin) = (RECORD_V5_LEN, RECORD_V5_LEN + 17);
    record[flag] = 2;
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field { offset: flag })
    );
    // No key, yet key bytes: not a record any writer makes.
    record[flag] = 0;
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field { offset: flag + 1 })
    );
    let mut record = Settings::default().to_record();
    assert_eq!(record[pin..pin + 4], [0xFF; 4], "the factory PIN");
    record[pin..pin + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
    assert_eq!(
        Settings::from_record(&record),
        Err(DecodeError::Field { offset: pin })
    );
    record[pin..pin + 4].copy_from_slice(&0u32.to_le_bytes());
    assert_eq!(
        Settings::from_record(&record).map(|s| s.ble_pin),
        Ok(Pin::new(0)),
        "000000 set on purpose stays possible"
    );
    // The phrase flag, derivation bytes without a phrase, and the plain byte.
    let phrase_flag = RECORD_V6_LEN;
    for (at, value, offset) in [
        (phrase_flag, 2, phrase_flag),
        (phrase_flag + 9, 1, phrase_flag + 9),
        (phrase_flag + 41, 2, phrase_flag + 41),
        (RECORD_V7_LEN, 2, RECORD_V7_LEN),
    ] {
        let mut record = Settings::default().to_record();
        record[at] = value;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset }),
            "byte {at}"
        );
    }
}

proptest::proptest! {
    #[test]
    fn any_bytes_decode_or_error(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..64)) {
        if let Ok(settings) = Settings::from_record(&bytes) {
            // A current record re-encodes to itself; an older one to its upgrade, which
            // decodes to the same settings.
            let record = settings.to_record();
            if bytes.first() == Some(&RECORD_VERSION) {
                proptest::prop_assert_eq!(&record[..], &bytes[..]);
            } else {
                proptest::prop_assert_eq!(Settings::from_record(&record), Ok(settings));
                proptest::prop_assert_eq!(&record[3..8], &bytes[3..8]);
            }
        }
    }
}
