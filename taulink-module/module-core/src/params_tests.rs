//! Tests of the CRSF parameter table: every row's entry, reads and writes, commands.

use super::*;
use crate::settings::{Band, LinkProtocol, RateMode};

#[test]
fn every_parameter_has_an_entry_and_no_more() {
    let settings = Settings::default();
    let commands = Commands::default();
    for number in 1..=PARAMETER_COUNT {
        assert!(entry(number, &settings, &commands).is_some(), "{number}");
    }
    assert!(entry(0, &settings, &commands).is_none());
    assert!(entry(PARAMETER_COUNT + 1, &settings, &commands).is_none());
}

#[test]
fn rate_writes_restart_the_link_once() {
    let mut settings = Settings::default();
    let mut commands = Commands::default();
    assert_eq!(
        write(PACKET_RATE, &[3], &mut settings, &mut commands),
        Effect::RestartLink
    );
    assert_eq!(settings.rate, RateMode::F500);
    assert_eq!(commands.restarted_by, Some(PACKET_RATE));
    assert_eq!(
        write(PACKET_RATE, &[3], &mut settings, &mut commands),
        Effect::None
    );
    assert_eq!(
        write(PACKET_RATE, &[9], &mut settings, &mut commands),
        Effect::None
    );
    assert_eq!(settings.rate, RateMode::F500);
    assert_eq!(
        write(TELEMETRY_RATIO, &[3], &mut settings, &mut commands),
        Effect::RestartLink
    );
    assert_eq!(settings.telemetry_ratio, 16);
    assert_eq!(
        write(INPUT_TIMEOUT, &[0x03, 0x20], &mut settings, &mut commands),
        Effect::InputTimeout
    );
    assert_eq!(settings.input_timeout_ms, 800);
    assert_eq!(
        write(INPUT_TIMEOUT, &[0x00, 0x10], &mut settings, &mut commands),
        Effect::None
    );
    assert_eq!(settings.input_timeout_ms, 800);
}

/// The entry's option text (a SELECT's options follow its name).
fn entry_text(number: u8, settings: &Settings) -> std::string::String {
    let entry = entry(number, settings, &Commands::default()).unwrap();
    std::string::String::from_utf8_lossy(&entry).into_owned()
}

#[test]
fn the_protocol_choice_labels_openlrsng_unauthenticated_and_restarts_the_link() {
    let text = entry_text(PROTOCOL, &Settings::default());
    assert!(text.contains("Protocol"), "{text}");
    assert!(
        text.contains("TauLink;OLRSng3.8 (no auth);OLRSng3.9 (no auth)"),
        "{text}"
    );
    let mut settings = Settings::default();
    let mut commands = Commands::default();
    assert_eq!(
        write(PROTOCOL, &[2], &mut settings, &mut commands),
        Effect::RestartLink
    );
    assert_eq!(settings.protocol, LinkProtocol::OpenLrs39);
    assert_eq!(commands.restarted_by, Some(PROTOCOL));
    assert_eq!(
        write(PROTOCOL, &[3], &mut settings, &mut commands),
        Effect::None
    );
    assert_eq!(settings.protocol, LinkProtocol::OpenLrs39);
    // The bind parameters: 125 kbit/s, 16 channels, telemetry off.
    for (number, value) in [
        (OPENLRS_RATE, 4),
        (OPENLRS_CHANNELS, 5),
        (OPENLRS_TELEMETRY, 0),
    ] {
        assert_eq!(
            write(number, &[value], &mut settings, &mut commands),
            Effect::RestartLink
        );
    }
    assert_eq!(settings.openlrs.profile, 4);
    assert_eq!(settings.openlrs.channel_mode, 6);
    assert!(!settings.openlrs.telemetry);
    for (number, value) in [
        (OPENLRS_RATE, 5),
        (OPENLRS_CHANNELS, 6),
        (OPENLRS_TELEMETRY, 2),
    ] {
        let before = settings;
        assert_eq!(
            write(number, &[value], &mut settings, &mut commands),
            Effect::None
        );
        assert_eq!(settings, before);
    }
    // The 433 ISM sub-band cannot hold OpenLRSng's bind channel: the band write is
    // refused while OpenLRSng is selected, and OpenLRSng while on that band.
    assert_eq!(
        write(BAND, &[3], &mut settings, &mut commands),
        Effect::None
    );
    assert_eq!(settings.band, Band::Mhz433);
    let mut ism = Settings {
        band: Band::Ism433,
        ..Settings::default()
    };
    assert_eq!(write(PROTOCOL, &[1], &mut ism, &mut commands), Effect::None);
    assert_eq!(ism.protocol, LinkProtocol::TauLink);
    // With TauLink flying, an OpenLRSng parameter does not restart the link.
    let mut taulink = Settings::default();
    assert_eq!(
        write(OPENLRS_RATE, &[4], &mut taulink, &mut commands),
        Effect::None
    );
    assert_eq!(taulink.openlrs.profile, 4);
    let rate = entry_text(OPENLRS_RATE, &taulink);
    assert!(rate.contains("125kbps"), "{rate}");
    // A set that is already unusable (only a damaged record can hold OpenLRSng on the
    // ISM sub-band) stays editable: an unrelated change is taken, then the repair.
    let mut broken = Settings {
        band: Band::Ism433,
        protocol: LinkProtocol::OpenLrs39,
        ..Settings::default()
    };
    assert!(broken.validate().is_err());
    assert_eq!(
        write(TX_POWER, &[2], &mut broken, &mut commands),
        Effect::TxPower
    );
    assert_eq!(broken.tx_power, 2, "editable while broken");
    assert_eq!(
        write(BAND, &[0], &mut broken, &mut commands),
        Effect::RestartLink
    );
    assert!(broken.validate().is_ok());
}

fn info_text(entry: &[u8]) -> std::string::String {
    // parent, type, name NUL, text NUL.
    let name_end = entry[2..].iter().position(|b| *b == 0).unwrap() + 2;
    std::string::String::from_utf8(entry[name_end + 1..entry.len() - 1].to_vec()).unwrap()
}

#[test]
fn the_phrase_is_a_string_row_and_the_key_row_shows_the_fingerprint_or_why() {
    let commands = Commands::default();
    // STRING: parent, type 0x0A, name NUL, the (always empty) value NUL, max length.
    let row = entry(BIND_PHRASE, &Settings::default(), &commands).unwrap();
    assert_eq!(row.as_slice(), b"\x00\x0ABind Phrase\x00\x00\x38");
    let unbound = entry(LINK_KEY, &Settings::default(), &commands).unwrap();
    assert_eq!(info_text(&unbound), "not bound no phrase");

    let key = telemetry::link::LinkKey::from_bytes([0x44; 16]);
    let mut settings = Settings {
        bind_id: 0x0102_0304,
        link_key: Some(key),
        ..Settings::default()
    };
    let mut commands = Commands::default();
    let row = entry(LINK_KEY, &settings, &commands).unwrap();
    assert_eq!(
        info_text(&row),
        format!("{} no phrase", key.for_link(0x0102_0304).fingerprint())
    );
    let phrase = b"amber kettle under the oak\0";
    assert_eq!(
        write(BIND_PHRASE, phrase, &mut settings, &mut commands),
        Effect::DerivePhrase,
        "the core derives it"
    );
    assert_eq!(commands.phrase_note, Some(PhraseNote::Deriving));
    // The row never shows the phrase.
    let row = entry(BIND_PHRASE, &settings, &commands).unwrap();
    assert!(!row.windows(5).any(|w| w == b"amber"));

    // Refusals keep the phrase and say why.
    for (value, armed, why) in [
        (
            &b"amber kettle under the oak\0"[..],
            true,
            "refused: quad armed",
        ),
        (b"   \0", false, "empty: phrase kept"),
        (b"bell\x07ringing loud\0", false, "refused: bad character"),
        (b"\xFF\xFE\0", false, "refused: bad character"),
        (b"short one\0", false, "refused: < 12 chars"),
    ] {
        commands.flight_armed = armed;
        assert_eq!(
            write(BIND_PHRASE, value, &mut settings, &mut commands),
            Effect::None
        );
        assert_eq!(settings.phrase_prs, None);
        assert_eq!(
            info_text(&entry(LINK_KEY, &settings, &commands).unwrap()),
            why
        );
    }
    let pin = Commands {
        ble_pin: crate::hm10::at::Pin::new(4_217),
        ..Commands::default()
    };
    assert_eq!(
        info_text(&entry(BLE_PIN, &settings, &pin).unwrap()),
        "004217"
    );
}

#[test]
fn save_needs_a_confirmation() {
    let mut settings = Settings::default();
    let mut commands = Commands::default();
    assert_eq!(
        write(SAVE, &[4], &mut settings, &mut commands),
        Effect::CommandStatus,
        "a confirm without a start saves nothing"
    );
    assert_eq!(
        write(SAVE, &[1], &mut settings, &mut commands),
        Effect::CommandStatus
    );
    assert!(commands.save_confirming);
    assert_eq!(
        write(SAVE, &[4], &mut settings, &mut commands),
        Effect::Save
    );
    assert!(commands.saved && !commands.save_confirming);
}

#[test]
fn saving_ppm_input_warns_that_the_menu_goes_away() {
    let info = |settings: &Settings| {
        let commands = Commands {
            save_confirming: true,
            ..Commands::default()
        };
        let entry = entry(SAVE, settings, &commands).unwrap();
        // parent, type, "Save" NUL, status, timeout, info, NUL.
        std::string::String::from_utf8(entry[9..entry.len() - 1].to_vec()).unwrap()
    };
    let crsf = Settings {
        input: InputProtocol::Crsf,
        ..Settings::default()
    };
    assert_eq!(info(&crsf), "Save settings?");
    let ppm = Settings {
        input: InputProtocol::Ppm,
        ..crsf
    };
    assert_eq!(info(&ppm), "Save? PPM input ends this menu");
}
