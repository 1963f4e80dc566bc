use super::table::{DOCS, handle_rows};
use super::*;
use crate::link::{Band, RateMode};

#[test]
fn table_is_consistent() {
    assert_eq!(DOCS.len(), COUNT, "one doc line per row");
    for (i, p) in PARAMS.iter().enumerate() {
        assert_eq!(
            p.check(p.default),
            Ok(p.default),
            "{} default out of range",
            p.name
        );
        assert!(!p.doc().is_empty(), "{} has no doc", p.name);
        for q in &PARAMS[i + 1..] {
            assert_ne!(p.key, q.key, "duplicate key");
            assert_ne!(p.name, q.name, "duplicate name");
        }
    }
}

#[test]
fn every_handle_names_a_row_of_its_type() {
    let rows = handle_rows();
    assert_eq!(rows.len(), COUNT, "one handle per row");
    for (i, (ident, index, fits)) in rows.into_iter().enumerate() {
        assert_eq!(index, i, "{ident} is not in table order");
        let p = &PARAMS[index];
        assert_eq!(
            ident,
            p.name.to_uppercase().replace('.', "_"),
            "{ident} names another row"
        );
        assert!(fits, "{ident}'s type does not match {}'s kind", p.name);
    }
    assert_eq!(
        handles::PID_GAINS[2][0].param().map(|p| p.name),
        Some("pid.yaw.kp")
    );
    assert_eq!(
        handles::LQG_LN_BETA1[1].param().map(|p| p.name),
        Some("lqg.ln_beta1.pitch")
    );
    assert_eq!(
        handles::LINK_OLRS_HOPS[5].param().map(|p| p.name),
        Some("link.olrs_hops_5")
    );
    assert_eq!(
        handles::MAG_CALIBRATION[6].param().map(|p| p.name),
        Some("mag.xy")
    );
    let mut bits: Bits = [0; COUNT];
    bits[handles::RATE_MAX_DPS.index()] = 720.0f32.to_bits();
    assert_eq!(handles::RATE_MAX_DPS.read(&bits), 720.0);
}

#[test]
fn units_docs_and_ranges_as_a_tool_shows_them() {
    let unit = |name: &str| find(name).map(|(_, p)| p.unit());
    assert_eq!(unit("rate.max_dps"), Some("°/s"));
    assert_eq!(unit("battery.current_mv_per_a"), Some("mV/A"));
    assert_eq!(unit("battery.cell_warning_mv"), Some("mV"));
    assert_eq!(unit("arm.idle_disarm_ms"), Some("ms"));
    assert_eq!(unit("output.min_us"), Some("µs"));
    assert_eq!(unit("output.rate_hz"), Some("Hz"));
    assert_eq!(unit("link.olrs_frequency_hz"), Some("Hz"));
    assert_eq!(unit("lqg.tau_s"), Some("s"));
    assert_eq!(unit("failsafe.descent_mps"), Some("m/s"));
    assert_eq!(unit("mag.declination_deg"), Some("°"));
    assert_eq!(unit("pid.roll.kp"), Some(""));
    // A choice's name ends in a unit word, its value is a name.
    assert_eq!(unit("loop.rate_hz"), Some(""));
    let (id, rate) = find("rate.max_dps").unwrap();
    assert_eq!(by_id(id as u16), Some(rate));
    assert_eq!(
        rate.kind,
        Kind::F32 {
            min: 30.0,
            max: 2000.0
        }
    );
    assert_eq!(rate.doc(), "Rate modes: the rate full stick commands.");
    assert_eq!(by_id(COUNT as u16), None);
}

#[test]
fn choices_are_read_in_any_case_and_checked() {
    let (_, protocol) = find("link.protocol").unwrap();
    assert_eq!(protocol.choice("openlrs38"), Ok(Value::U32(1)));
    assert_eq!(protocol.choice("OpenLRS39"), Ok(Value::U32(2)));
    assert_eq!(protocol.choice("olrs38"), Err(ValueError::Unparsable));
    let (_, rate) = find("link.rate").unwrap();
    assert_eq!(rate.choice("f500"), Ok(Value::U32(3)));
    assert_eq!(rate.from_bits(5), Err(ValueError::OutOfRange));
    let (_, kp) = find("pid.roll.kp").unwrap();
    assert_eq!(kp.choice("1"), Err(ValueError::Unparsable));
    assert_eq!(
        kp.from_bits(f32::NAN.to_bits()),
        Err(ValueError::OutOfRange)
    );
    assert_eq!(
        kp.check(Value::U32(0)),
        Err(ValueError::OutOfRange),
        "wrong kind"
    );
    assert_eq!(
        Change::by_name("pid.roll.kp", Value::F32(0.004)).map(|c| c.index()),
        Some(handles::PID_ROLL_KP.index())
    );
    assert_eq!(Change::by_name("no.such", Value::U32(0)), None);
}

#[test]
fn link_choices_follow_the_link_types() {
    assert_eq!(RATES.len(), RateMode::ALL.len());
    for (name, mode) in RATES.iter().zip(RateMode::ALL) {
        assert_eq!(*name, format!("{mode:?}"));
    }
    let bands = [Band::Mhz433, Band::Mhz868, Band::Mhz915, Band::Ism433];
    assert_eq!(BANDS.len(), bands.len());
    for (i, band) in bands.into_iter().enumerate() {
        assert_eq!(
            band as usize, i,
            "{:?} is the {i}th band word, {}",
            band, BANDS[i]
        );
    }
}
