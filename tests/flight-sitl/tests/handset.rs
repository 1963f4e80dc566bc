//! Issue 15's acceptance, end to end at chip level: the flight application's baro altitude,
//! vario and cell count cross the air (virtual Si4432s) to the module's application, which
//! sends them to the handset on the JR line; decoded back out of those line bytes with
//! EdgeTX's own rules (`edgetx-decode`, written from the protocol, not with our encoders) — CRSF VARIO
//! 0x07 and BARO_ALTITUDE 0x09 (`crossfire.cpp`), S.Port ALT 0x0100, VARIO 0x0110 and CELLS
//! 0x0300 (`frsky_sport.cpp`), FrSky D hub BARO_ALT 0x10/0x21, VARIO 0x30 and CELLS 0x06
//! (`frsky_d.cpp`) — they are the flight side's values. CRSF has no per-cell frame (EdgeTX
//! shows CRSF cells only through the BATTERY frame's pack voltage).

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use std::collections::BTreeSet;

use common::*;
use edgetx_decode::{
    crsf_baro_altitude_cm, crsf_vario_cm_s, hub_altitude_cm, hub_cell, hub_stream, sport_cells,
};
use flight_sitl::scenario::default_airframe;
use flight_sitl::{Scenario, Sitl, run};
use module_core::settings::{InputProtocol, OutputProtocol, Settings as ModuleSettings};
use telemetry::messages::{Message, Vertical};

/// Take-off and 6.5 s of cruise, the module's JR line speaking `input` / `output`.
fn hover_with(input: InputProtocol, output: OutputProtocol) -> Sitl {
    let (quad, settings) = default_airframe();
    run(Scenario {
        module_settings: Some(ModuleSettings {
            input,
            output,
            ..ModuleSettings::default()
        }),
        ..Scenario::new(settings, quad, 10.0, pilot(-1.0, |_| cruise(-1.0)))
    })
}

/// What the flight side sent (as the module received it): altitude/vario pairs, and the
/// cell counts and pack voltages.
fn sent(sitl: &Sitl) -> (Vec<Vertical>, BTreeSet<u8>, BTreeSet<u16>) {
    let mut vertical = Vec::new();
    let mut cells = BTreeSet::new();
    let mut packs = BTreeSet::new();
    for (_, m) in &sitl.module_rx {
        match m {
            Message::Vertical(v) => vertical.push(*v),
            Message::Cells(c) => {
                cells.insert(c.count);
            }
            Message::Battery(b) => {
                packs.insert(b.voltage_mv);
            }
            _ => {}
        }
    }
    (vertical, cells, packs)
}

/// The flight side's values are the flight's: from 5 s on (1.5 s after the take-off
/// throttle, the quad climbing at ≈ 2.5 m/s on the cruise throttle) the altitude it sent is
/// the quad's (within the tracker's smoothing of the baro's 0.1 m noise) and the vario its
/// climb rate (the estimator blends the baro rate in with a 1 s time constant, so it lags a
/// change of climb rate by up to ≈ 0.6 m/s right after the throttle step).
fn check_sent_values_are_the_flight(sitl: &Sitl) -> Vec<Vertical> {
    let (vertical, _, _) = sent(sitl);
    assert!(vertical.len() > 30, "{}", vertical.len());
    let flying: Vec<_> = sitl
        .module_rx
        .iter()
        .filter_map(|(t, m)| match m {
            Message::Vertical(v) if *t > 5.0 => Some((*t, *v)),
            _ => None,
        })
        .collect();
    assert!(flying.len() > 20, "{}", flying.len());
    let (mut worst_alt, mut worst_vario) = (0.0f64, 0.0f64);
    for (t, v) in &flying {
        // The message left the flight side up to a downlink latency before the module had it.
        let truth = sitl.samples.iter().rfind(|s| s.t_s <= *t - 0.01).unwrap();
        worst_alt = worst_alt.max((f64::from(v.altitude_cm) / 100.0 - truth.altitude_m).abs());
        worst_vario = worst_vario.max((f64::from(v.vario_cm_s) / 100.0 - truth.climb_mps).abs());
    }
    println!("sent vs truth: altitude within {worst_alt:.3} m, vario within {worst_vario:.3} m/s");
    assert!(worst_alt < 0.3, "{worst_alt}");
    assert!(worst_vario < 0.25, "{worst_vario}");
    // The quad climbed: the altitudes the handset gets are not a constant.
    let max = vertical.iter().map(|v| v.altitude_cm).max().unwrap();
    assert!(max > 100, "{max}");
    vertical
}

// ---- CRSF ----

/// (type, payload) of every CRSF frame in the module's replies, CRC checked.
fn crsf_frames(sitl: &Sitl) -> Vec<(u8, Vec<u8>)> {
    let mut frames = Vec::new();
    for (_, burst) in &sitl.handset_tx {
        frames.extend(edgetx_decode::crsf_frames(burst));
    }
    frames
}

#[test]
fn crsf_vario_and_baro_altitude_are_the_flight_sides() {
    let sitl = hover_with(InputProtocol::Crsf, OutputProtocol::Crsf);
    let vertical = check_sent_values_are_the_flight(&sitl);
    let frames = crsf_frames(&sitl);
    // EdgeTX: CF_VARIO_ID int16 BE cm/s; BARO_ALT_ID bit 15 → metres, else dm + 10 000.
    let vspd: Vec<i32> = frames
        .iter()
        .filter(|(t, _)| *t == 0x07)
        .map(|(_, p)| crsf_vario_cm_s(p))
        .collect();
    let alt: Vec<i32> = frames
        .iter()
        .filter(|(t, _)| *t == 0x09)
        .map(|(_, p)| crsf_baro_altitude_cm(p))
        .collect();
    println!(
        "CRSF: {} vario, {} altitude frames from {} Vertical messages",
        vspd.len(),
        alt.len(),
        vertical.len()
    );
    // The responder sends each sensor at 5 Hz once the flight side's values are there.
    assert!(
        vspd.len() > 25 && alt.len() > 25,
        "{} {}",
        vspd.len(),
        alt.len()
    );
    let sent_vario: BTreeSet<i32> = vertical.iter().map(|v| i32::from(v.vario_cm_s)).collect();
    assert!(vspd.iter().all(|v| sent_vario.contains(v)), "{vspd:?}");
    // Decimetres on the wire: each shown altitude is a sent one rounded to 10 cm.
    let sent_dm: BTreeSet<i32> = vertical
        .iter()
        .map(|v| (f64::from(v.altitude_cm) / 10.0).round() as i32 * 10)
        .collect();
    assert!(alt.iter().all(|a| sent_dm.contains(a)), "{alt:?}");
    assert!(alt.iter().collect::<BTreeSet<_>>().len() > 5, "{alt:?}");
}

// ---- S.Port ----

/// (value ID, value) of the S.Port data frames in the pushed bytes: `7E phys 10 idLo idHi
/// v0..v3 crc`, 0x7D-stuffed, EdgeTX's checksum checked.
fn sport_frames(sitl: &Sitl) -> Vec<(u16, u32)> {
    let mut frames = Vec::new();
    for (_, bytes) in &sitl.handset_tx {
        frames.extend(edgetx_decode::sport_frames(bytes));
    }
    frames
}

#[test]
fn sport_altitude_vario_and_cells_are_the_flight_sides() {
    let sitl = hover_with(InputProtocol::Ppm, OutputProtocol::SPort);
    let vertical = check_sent_values_are_the_flight(&sitl);
    let (_, counts, packs) = sent(&sitl);
    let frames = sport_frames(&sitl);
    let values = |id: u16| -> Vec<u32> {
        frames
            .iter()
            .filter(|(i, _)| *i == id)
            .map(|(_, v)| *v)
            .collect()
    };
    // ALT_FIRST_ID and VARIO_FIRST_ID: int32 in cm and cm/s.
    let alt: Vec<i32> = values(0x0100).into_iter().map(|v| v as i32).collect();
    let vspd: Vec<i32> = values(0x0110).into_iter().map(|v| v as i32).collect();
    println!("S.Port: {} Alt, {} VSpd", alt.len(), vspd.len());
    assert!(alt.len() > 25 && vspd.len() > 25);
    let sent_alt: BTreeSet<i32> = vertical.iter().map(|v| v.altitude_cm).collect();
    let sent_vario: BTreeSet<i32> = vertical.iter().map(|v| i32::from(v.vario_cm_s)).collect();
    assert!(alt.iter().all(|a| sent_alt.contains(a)), "{alt:?}");
    assert!(vspd.iter().all(|v| sent_vario.contains(v)), "{vspd:?}");
    assert!(alt.iter().collect::<BTreeSet<_>>().len() > 5);
    // CELLS_FIRST_ID, as EdgeTX unpacks it: count = bits 4–7, index = bits 0–3, two cells of
    // 12 bits in 2 mV. The flight side's count and its pack voltage over it.
    let cells = values(0x0300);
    assert!(!cells.is_empty());
    // The world's pack is a 1S (4.15 V): the battery monitor counts one cell.
    assert_eq!(counts.iter().copied().collect::<Vec<_>>(), vec![1]);
    for v in cells {
        let (count, first, [cell, _]) = sport_cells(v);
        assert_eq!((count, first), (1, 0));
        let cell_mv = cell * 2;
        assert!(
            packs.iter().any(|p| u32::from(*p) / 2 * 2 == cell_mv),
            "{cell_mv} mV of {packs:?}"
        );
    }
}

// ---- FrSky D ----

/// EdgeTX's hub records (`5E id lo hi`, 0x5D-stuffed) out of the user frames (`7E FD n 00
/// data… 7E`, 0x7D-stuffed) in the pushed bytes.
fn hub_records(sitl: &Sitl) -> Vec<(u8, i16)> {
    let mut stream = Vec::new();
    for (_, bytes) in &sitl.handset_tx {
        hub_stream(bytes, &mut stream);
    }
    edgetx_decode::hub_records(&stream)
}

#[test]
fn frsky_d_altitude_vario_and_cells_are_the_flight_sides() {
    let sitl = hover_with(InputProtocol::Ppm, OutputProtocol::FrskyHub);
    let vertical = check_sent_values_are_the_flight(&sitl);
    let (_, counts, packs) = sent(&sitl);
    let (mut alt, mut vspd, mut bp, mut cells) = (Vec::new(), Vec::new(), None, Vec::new());
    for (id, value) in hub_records(&sitl) {
        match id {
            // CELLS_ID as EdgeTX's `processHubPacket` unpacks it: index = bits 4–7, the
            // 1/500 V value = bits 8–15 plus bits 0–3 as its top nibble.
            0x06 => cells.push(hub_cell(value)),
            0x10 => bp = Some(value),
            0x21 => alt.push(hub_altitude_cm(bp.unwrap(), value)),
            0x30 => vspd.push(i32::from(value)),
            _ => {}
        }
    }
    println!("FrSky D: {} Alt, {} VSpd", alt.len(), vspd.len());
    assert!(
        alt.len() > 10 && vspd.len() > 10,
        "{} {}",
        alt.len(),
        vspd.len()
    );
    let sent_vario: BTreeSet<i32> = vertical.iter().map(|v| i32::from(v.vario_cm_s)).collect();
    assert!(vspd.iter().all(|v| sent_vario.contains(v)), "{vspd:?}");
    // Decimetres on the wire, cut towards zero (−0.9…−0.1 m has no encoding: 0).
    let sent_dm: BTreeSet<i32> = vertical
        .iter()
        .map(|v| {
            let dm = v.altitude_cm / 10;
            if (-9..0).contains(&dm) { 0 } else { dm * 10 }
        })
        .collect();
    assert!(alt.iter().all(|a| sent_dm.contains(a)), "{alt:?}");
    assert!(alt.iter().collect::<BTreeSet<_>>().len() > 5, "{alt:?}");
    // The world's pack is a 1S: EdgeTX counts cells by the highest index (+ 1), so every
    // index is 0, and each cell is the flight side's pack voltage over its count, in 2 mV.
    println!("FrSky D: {} Cels", cells.len());
    assert!(cells.len() > 10, "{}", cells.len());
    assert_eq!(counts.iter().copied().collect::<Vec<_>>(), vec![1]);
    for (index, cell_mv) in cells {
        assert_eq!(index, 0);
        assert!(
            packs.iter().any(|p| u32::from(*p) / 2 * 2 == cell_mv),
            "{cell_mv} mV of {packs:?}"
        );
    }
}
