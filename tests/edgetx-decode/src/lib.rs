//! The telemetry the handset receives, decoded with EdgeTX's own rules: CRSF VARIO 0x07 and
//! BARO_ALTITUDE 0x09 (`crossfire.cpp`), the S.Port push stream and its CELLS value
//! (`frsky_sport.cpp`), the FrSky D hub user frames and records, BARO_ALT 0x10/0x21 and CELLS
//! 0x06 (`frsky_d.cpp`, `parseTelemHubByte`, `processHubPacket`). Written from the protocol
//! and EdgeTX's sources, never with the workspace's encoders, so a test that decodes our line
//! bytes with it checks them against the radio, not against ourselves. The one such decoder
//! of module-core's `sensors_decode_back` and flight-sitl's `handset` tests; a
//! dev-dependency only.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Test support: a malformed frame (wrong CRC, cut short) fails the test, said loudly.
#![allow(clippy::panic, clippy::indexing_slicing)]

/// CRSF's CRC-8, polynomial 0xD5, over type and payload.
pub fn crc8_d5(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0xD5
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// (type, payload) of every CRSF frame (`addr len type payload… crc`) in one burst, the CRC
/// checked.
pub fn crsf_frames(burst: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut frames = Vec::new();
    let mut bytes = burst;
    while bytes.len() >= 4 {
        let len = bytes[1] as usize;
        let (frame, rest) = bytes.split_at(2 + len);
        assert_eq!(crc8_d5(&frame[2..1 + len]), frame[1 + len], "CRSF CRC");
        frames.push((frame[2], frame[3..1 + len].to_vec()));
        bytes = rest;
    }
    frames
}

/// CF_VARIO_ID (0x07): int16 BE, cm/s.
pub fn crsf_vario_cm_s(payload: &[u8]) -> i32 {
    i32::from(i16::from_be_bytes([payload[0], payload[1]]))
}

/// BARO_ALT_ID (0x09), cm: bit 15 set → metres in bits 0–14, else decimetres + 10 000.
pub fn crsf_baro_altitude_cm(payload: &[u8]) -> i32 {
    let v = i32::from(u16::from_be_bytes([payload[0], payload[1]]));
    if v & 0x8000 != 0 {
        (v & 0x7FFF) * 100
    } else {
        (v - 10_000) * 10
    }
}

/// (value ID, value) of the S.Port data frames in pushed bytes: `7E phys 10 idLo idHi v0..v3
/// crc`, 0x7D-stuffed, EdgeTX's checksum (the byte sum folded, crc included, is 0xFF)
/// checked.
pub fn sport_frames(bytes: &[u8]) -> Vec<(u16, u32)> {
    let mut frames = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != 0x7E {
            i += 1;
            continue;
        }
        let mut body = Vec::new();
        let mut j = i + 2;
        while body.len() < 8 && j < bytes.len() {
            let b = if bytes[j] == 0x7D {
                j += 1;
                bytes[j] ^ 0x20
            } else {
                bytes[j]
            };
            body.push(b);
            j += 1;
        }
        let mut sum = 0u16;
        for b in &body {
            sum += u16::from(*b);
            sum += sum >> 8;
            sum &= 0xFF;
        }
        assert_eq!(sum, 0xFF, "S.Port CRC");
        assert_eq!(body[0], 0x10);
        frames.push((
            u16::from_le_bytes([body[1], body[2]]),
            u32::from_le_bytes([body[3], body[4], body[5], body[6]]),
        ));
        i = j;
    }
    frames
}

/// CELLS_FIRST_ID (0x0300) as EdgeTX unpacks it: (cell count = bits 4–7, index of the first
/// cell = bits 0–3, the two cells' raw 12-bit values in 2 mV).
pub fn sport_cells(value: u32) -> (u32, u32, [u32; 2]) {
    (
        (value >> 4) & 0xF,
        value & 0xF,
        [(value >> 8) & 0xFFF, (value >> 20) & 0xFFF],
    )
}

/// Appends the hub bytes of the FrSky D user frames (`7E FD n 00 data… 7E`, 0x7D-stuffed) in
/// pushed bytes to `stream`.
pub fn hub_stream(bytes: &[u8], stream: &mut Vec<u8>) {
    // Frames between raw 0x7E bytes (a stuffed 0x7E is `7D 5E`), then unstuffed.
    for segment in bytes.split(|b| *b == 0x7E) {
        let mut unstuffed = Vec::new();
        let mut i = 0;
        while i < segment.len() {
            if segment[i] == 0x7D {
                unstuffed.push(segment[i + 1] ^ 0x20);
                i += 2;
            } else {
                unstuffed.push(segment[i]);
                i += 1;
            }
        }
        if unstuffed.first() == Some(&0xFD) {
            let n = usize::from(unstuffed[1]);
            stream.extend_from_slice(&unstuffed[3..3 + n]);
        }
    }
}

/// EdgeTX's hub records (`5E id lo hi`) in a hub byte stream, as `parseTelemHubByte` reads
/// them: a raw 0x5E starts a record (also in the middle of one: a cut record is dropped),
/// 0x5D escapes the next byte (xor 0x60), IDs above 0x3F are dropped.
pub fn hub_records(stream: &[u8]) -> Vec<(u8, i16)> {
    let mut records = Vec::new();
    let (mut at, mut escape, mut record) = (None::<usize>, false, [0u8; 3]);
    for &raw in stream {
        if raw == 0x5E {
            (at, escape) = (Some(0), false);
            continue;
        }
        if raw == 0x5D {
            escape = true;
            continue;
        }
        let byte = if escape { raw ^ 0x60 } else { raw };
        escape = false;
        let Some(k) = at else { continue };
        record[k] = byte;
        at = if k == 2 {
            if record[0] <= 0x3F {
                records.push((record[0], i16::from_le_bytes([record[1], record[2]])));
            }
            None
        } else {
            Some(k + 1)
        };
    }
    records
}

/// The altitude of a BARO_ALT pair, cm: metres BP (0x10) and decimetres AP (0x21, ≤ 9),
/// `100·BP ± 10·AP` by the sign of BP.
pub fn hub_altitude_cm(bp: i16, ap: i16) -> i32 {
    let (bp, ap) = (i32::from(bp), i32::from(ap) * 10);
    100 * bp + if bp >= 0 { ap } else { -ap }
}

/// CELLS_ID (0x06) as `processHubPacket` unpacks it: (cell index = bits 4–7, the cell in mV:
/// the 1/500 V value = bits 8–15 plus bits 0–3 as its top nibble).
pub fn hub_cell(value: i16) -> (u16, u32) {
    let v = value as u16;
    let raw = u32::from((v >> 8) + ((v & 0x0F) << 8));
    ((v >> 4) & 0x0F, raw * 2)
}
