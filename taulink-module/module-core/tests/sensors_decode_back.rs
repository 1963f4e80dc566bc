//! The flight side's vario, barometric altitude and cell count, and the module's own supply,
//! through the module's handset codecs (`handset::Handset`, as the JR-line task drives it) and
//! back out of the line bytes with EdgeTX's own decoding rules (`edgetx-decode`, written from
//! the protocol, not with our encoders): CRSF 0x07 / 0x09 (`crossfire.cpp`), S.Port ALT
//! 0x0100, VARIO 0x0110, CELLS 0x0300 and A2 (`frsky_sport.cpp`), FrSky D hub BARO_ALT
//! 0x10/0x21 and VARIO 0x30 (`frsky_d.cpp`).

#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use edgetx_decode::{
    crc8_d5, crsf_baro_altitude_cm, crsf_frames, crsf_vario_cm_s, hub_altitude_cm, hub_records,
    hub_stream, sport_cells, sport_frames,
};
use module_core::handset::{Handset, MAX_LINE_BURST};
use module_core::ports::{HandsetOutput, LinkStats};
use module_core::records;
use module_core::settings::{InputProtocol, OutputProtocol, Settings};
use telemetry::messages::{Battery, Cells, Message, Vertical};

/// The flight side's values.
const ALTITUDE_CM: i32 = 12_340;
const VARIO_CM_S: i16 = -250;
const PACK_MV: u16 = 11_870;
const CELLS: u8 = 3;
const MODULE_MV: u16 = 7_400;

fn handset(input: InputProtocol, output: OutputProtocol, altitude_cm: i32) -> Handset {
    let settings = Settings {
        input,
        output,
        ..Settings::default()
    };
    let mut handset = Handset::new(&settings);
    for message in [
        Message::Battery(Battery {
            voltage_mv: PACK_MV,
            current_ca: 100,
            used_mah: 10,
            remaining_percent: 50,
        }),
        Message::Vertical(Vertical {
            altitude_cm,
            vario_cm_s: VARIO_CM_S,
        }),
        Message::Cells(Cells { count: CELLS }),
    ] {
        let mut record = [0u8; 64];
        let n = records::encode(&message, &mut record).unwrap().len();
        handset.on_telemetry(&record[..n]);
    }
    handset.on_link_stats(&LinkStats {
        connected: true,
        rssi_dbm: -70,
        link_quality_percent: 100,
        remote_link_quality_percent: Some(100),
        ..LinkStats::default()
    });
    handset.on_module_battery(MODULE_MV);
    handset
}

// ---- CRSF ----

fn rc_frame() -> Vec<u8> {
    let mut frame = vec![0xEE, 24, 0x16];
    frame.extend([0u8; 22]);
    let crc = crc8_d5(&frame[2..]);
    frame.push(crc);
    frame
}

/// EdgeTX's CRSF values: (VSpd cm/s, Alt cm).
fn crsf_values(altitude_cm: i32) -> (Vec<i32>, Vec<i32>) {
    let mut handset = handset(InputProtocol::Crsf, OutputProtocol::Crsf, altitude_cm);
    let (mut vspd, mut alt) = (Vec::new(), Vec::new());
    let mut out = [0u8; MAX_LINE_BURST];
    for k in 0..500u64 {
        let now = 10_000 + k * 4_000;
        handset.on_line_bytes(now, &rc_frame());
        let n = handset.next_line_bytes(now + 20, &mut out).len();
        for (kind, payload) in crsf_frames(&out[..n]) {
            match kind {
                0x07 => vspd.push(crsf_vario_cm_s(&payload)),
                0x09 => alt.push(crsf_baro_altitude_cm(&payload)),
                _ => {}
            }
        }
    }
    (vspd, alt)
}

#[test]
fn crsf_vario_and_baro_altitude_decode_back() {
    let (vspd, alt) = crsf_values(ALTITUDE_CM);
    assert!(vspd.len() >= 5, "5 Hz for 2 s: {}", vspd.len());
    assert!(vspd.iter().all(|v| *v == i32::from(VARIO_CM_S)));
    assert!(alt.len() >= 5);
    assert!(alt.iter().all(|a| *a == ALTITUDE_CM));
    // Below ground and above the decimetre range (2276.7 m): metres.
    let (_, alt) = crsf_values(-4_560);
    assert!(alt.iter().all(|a| *a == -4_560));
    let (_, alt) = crsf_values(300_049);
    assert!(alt.iter().all(|a| *a == 300_000), "{alt:?}");
}

// ---- S.Port ----

#[test]
fn sport_altitude_vario_cells_and_module_battery_decode_back() {
    let mut handset = handset(InputProtocol::Ppm, OutputProtocol::SPort, ALTITUDE_CM);
    let mut out = [0u8; MAX_LINE_BURST];
    let mut frames = Vec::new();
    for k in 0..500u64 {
        let n = handset.next_line_bytes(k * 12_000, &mut out).len();
        frames.extend(sport_frames(&out[..n]));
    }
    let values = |id: u16| -> Vec<u32> {
        frames
            .iter()
            .filter(|(i, _)| *i == id)
            .map(|(_, v)| *v)
            .collect()
    };
    let alt = values(0x0100);
    assert!(!alt.is_empty());
    assert!(alt.iter().all(|v| *v as i32 == ALTITUDE_CM), "Alt in cm");
    let vspd = values(0x0110);
    assert!(!vspd.is_empty());
    assert!(vspd.iter().all(|v| *v as i32 == i32::from(VARIO_CM_S)));
    // Cells, as EdgeTX unpacks them: count = bits 4–7, index = bits 0–3, then two cells of
    // 12 bits each in 2 mV, shown as raw / 5 in 0.01 V.
    let mut cells = std::collections::BTreeMap::new();
    for v in values(0x0300) {
        let (count, first, [a, b]) = sport_cells(v);
        assert_eq!(count, u32::from(CELLS));
        cells.insert(first, a / 5);
        if first + 1 < count {
            cells.insert(first + 1, b / 5);
        }
    }
    let per_cell_cv = u32::from(PACK_MV / u16::from(CELLS)) / 10;
    assert_eq!(cells.len(), usize::from(CELLS), "every cell: {cells:?}");
    assert!(cells.values().all(|c| *c == per_cell_cv), "{cells:?}");
    // The module's supply as A2: raw × 13.2 V / 255 within one step (52 mV).
    let a2 = values(0xF103);
    assert!(!a2.is_empty());
    for raw in a2 {
        let mv = raw * 13_200 / 255;
        assert!(u32::from(MODULE_MV).abs_diff(mv) <= 52, "{mv} mV");
    }
}

// ---- FrSky D hub ----

fn hub_altitudes(altitude_cm: i32) -> (Vec<i32>, Vec<i32>) {
    let mut handset = handset(InputProtocol::Ppm, OutputProtocol::FrskyHub, altitude_cm);
    let mut out = [0u8; MAX_LINE_BURST];
    let mut stream = Vec::new();
    for k in 0..200u64 {
        let n = handset.next_line_bytes(k * 30_000, &mut out).len();
        hub_stream(&out[..n], &mut stream);
    }
    let (mut alt, mut vspd, mut bp) = (Vec::new(), Vec::new(), None);
    for (id, value) in hub_records(&stream) {
        match id {
            0x10 => bp = Some(value),
            0x21 => alt.push(hub_altitude_cm(bp.unwrap(), value)),
            0x30 => vspd.push(i32::from(value)),
            _ => {}
        }
    }
    (alt, vspd)
}

#[test]
fn frsky_hub_altitude_and_vario_decode_back() {
    let (alt, vspd) = hub_altitudes(ALTITUDE_CM);
    assert!(!alt.is_empty());
    assert!(alt.iter().all(|a| *a == ALTITUDE_CM), "{alt:?}");
    assert!(!vspd.is_empty());
    assert!(vspd.iter().all(|v| *v == i32::from(VARIO_CM_S)));
    let (alt, _) = hub_altitudes(-4_560);
    assert!(alt.iter().all(|a| *a == -4_560), "{alt:?}");
    // 10 cm resolution: −0.5 m has no encoding and goes as 0.
    let (alt, _) = hub_altitudes(-50);
    assert!(alt.iter().all(|a| *a == 0), "{alt:?}");
}
