//! The table against its schema, the record layout and the device tool's rows.

use super::*;
use crate::params::{HANDSET_FOLDER, OPENLRS_FOLDER, PARAMETER_COUNT, RECEIVER_FOLDER};
use crate::settings::openlrs::OpenLrsSettings;
use crate::settings::{
    DEFAULT_INPUT_TIMEOUT_MS, DEFAULT_TELEMETRY_RATIO, INPUT_TIMEOUT_MS, RECORD_LEN,
};
use telemetry::settings::module::MODULE_PARAMS;

fn name(row: &Row) -> &'static str {
    row.param().unwrap().name
}

#[test]
fn the_rows_bind_the_schema_in_its_order() {
    assert_eq!(ROWS.len(), MODULE_PARAMS.len());
    for (row, param) in ROWS.iter().zip(MODULE_PARAMS) {
        assert_eq!(row.param(), Some(param));
        assert_eq!(row.default, param.default.to_bits(), "{}", param.name);
        match param.kind {
            Kind::U32 { min, max } => assert_eq!((row.min, row.max), (min, max)),
            Kind::Choice(words) => assert_eq!((row.min, row.max as usize), (0, words.len() - 1)),
            Kind::F32 { .. } => panic!("{}: no real settings", param.name),
        }
    }
}

/// The factory set the module shipped before the table (spelt out field by field).
#[test]
fn the_factory_values_are_the_schemas_and_unchanged() {
    let factory = Settings::default();
    for row in &ROWS {
        assert_eq!((row.get)(&factory), row.default, "{}", name(row));
        assert!(
            row.assign(&mut factory.clone(), row.default),
            "{}",
            name(row)
        );
    }
    assert_eq!(
        factory,
        Settings {
            role: Role::Transmitter,
            rate: RateMode::L50,
            input: InputProtocol::Ppm,
            output: OutputProtocol::SPort,
            band: Band::Mhz433,
            tx_power: 7,
            failsafe: FailsafeOutput::StopPulses,
            bind_id: 0,
            input_timeout_ms: 500,
            telemetry_ratio: 4,
            model_match: false,
            bound_models: 0,
            protocol: LinkProtocol::TauLink,
            openlrs: OpenLrsSettings::default(),
            link_key: None,
            phrase_salt: [0; 8],
            phrase_prs: None,
            plain: false,
            dynamic_power: true,
            ble_pin: None,
        }
    );
    assert_eq!(INPUT_TIMEOUT_MS, 100..=2_000);
    assert_eq!(DEFAULT_INPUT_TIMEOUT_MS, 500);
    assert_eq!(DEFAULT_TELEMETRY_RATIO, 4);
}

#[test]
fn the_record_fields_follow_each_other_inside_the_record() {
    let mut end = 1;
    for row in &ROWS {
        let range = row.stored.range();
        assert!(range.start >= end, "{} overlaps", name(row));
        assert!(range.end <= RECORD_LEN, "{}", name(row));
        // The field holds the row's largest value.
        let largest = match row.param().unwrap().kind {
            Kind::U32 { max, .. } => max,
            Kind::Choice(words) => words.len() as u32,
            Kind::F32 { .. } => panic!("{}: no real settings", name(row)),
        };
        let bits = 8 * range.len() as u32;
        assert!(bits >= 32 || largest < 1 << bits, "{}", name(row));
        end = range.end;
    }
}

#[test]
fn every_value_a_row_holds_survives_the_record() {
    for row in &ROWS {
        let candidates: Vec<u32> = match row.param().unwrap().kind {
            Kind::Choice(words) => (0..words.len() as u32).collect(),
            Kind::U32 { min, max } => vec![min, max, row.default, min.saturating_add(1)],
            Kind::F32 { .. } => panic!("{}: no real settings", name(row)),
        };
        let mut held = 0;
        for value in candidates {
            let mut s = Settings::default();
            if !row.assign(&mut s, value) {
                continue;
            }
            held += 1;
            let back = Settings::from_record(&s.to_record()).unwrap();
            assert_eq!((row.get)(&back), value, "{}", name(row));
        }
        assert!(held >= 2, "{} holds fewer than two values", name(row));
    }
}

#[test]
fn a_row_refuses_what_its_field_cannot_take() {
    let (ratio, _) = by_name("telemetry_ratio").unwrap();
    let (carrier, _) = by_name("olrs_frequency_hz").unwrap();
    let mut s = Settings::default();
    // In the schema's range, but no ratio the link runs / no module's carrier.
    assert!(ratio.in_range(3) && !ratio.assign(&mut s, 3));
    assert!(carrier.in_range(1_000_000_000) && !carrier.assign(&mut s, 1_000_000_000));
    // Past the range: refused before the field is asked.
    assert!(!by_name("tx_power").unwrap().0.assign(&mut s, 8));
    assert!(!by_name("input_timeout_ms").unwrap().0.assign(&mut s, 99));
    assert_eq!(s, Settings::default(), "nothing changed");
}

#[test]
fn stored_fields_encode_as_the_record_says() {
    let mut field = [0u8; 4];
    word(8).encode(0xDEAD_BEEF, &mut field);
    assert_eq!(field, [0xEF, 0xBE, 0xAD, 0xDE]);
    assert_eq!(word(8).decode(&field), Some(0xDEAD_BEEF));
    let channels = Stored::FromOne { offset: 26 };
    let mut byte = [0u8; 1];
    channels.encode(5, &mut byte);
    assert_eq!(byte, [6], "channel mode 6 (16 channels) is choice 5");
    assert_eq!(channels.decode(&[0]), None, "no channel mode 0");
}

#[test]
fn the_device_tool_rows_are_numbered_once_with_one_label_per_option() {
    let folders = [0, HANDSET_FOLDER, RECEIVER_FOLDER, OPENLRS_FOLDER];
    let mut seen = Vec::new();
    for row in &ROWS {
        let Some(crsf) = row.crsf else { continue };
        assert!((1..=PARAMETER_COUNT).contains(&crsf.number));
        assert!(!seen.contains(&crsf.number), "{} twice", crsf.number);
        seen.push(crsf.number);
        assert!(folders.contains(&crsf.folder), "{}", crsf.label);
        assert_eq!(by_crsf(crsf.number).map(|(r, _)| r.key), Some(row.key));
        let options = match (crsf.options, row.param().unwrap().kind) {
            (Options::Labels(labels), Kind::Choice(words)) => (labels.len(), words.len()),
            (Options::Labels(labels), Kind::U32 { min, max }) => {
                (labels.len(), (max - min + 1) as usize)
            }
            (Options::Values(labels, values), _) => (labels.len(), values.len()),
            (Options::Uint16(_), Kind::U32 { max, .. }) => (usize::from(max <= 0xFFFF), 1),
            (options, kind) => panic!("{options:?} for {kind:?}"),
        };
        assert_eq!(options.0, options.1, "{}", crsf.label);
    }
    assert_eq!(seen.len(), 14, "the settings among the 24 rows");
}
