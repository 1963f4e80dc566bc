//! Module → radio telemetry payloads: LINK_STATISTICS 0x14, BATTERY_SENSOR 0x08, ATTITUDE
//! 0x1E, FLIGHT_MODE 0x21, GPS 0x02, VARIO 0x07, BARO_ALTITUDE 0x09 (all multi-byte fields
//! big-endian).

use heapless::{String, Vec};

use super::frame::{Error, MAX_PAYLOAD_LEN, be_bytes, frame_type};

/// Longest flight-mode text this module carries.
pub const FLIGHT_MODE_MAX_LEN: usize = 16;
/// EdgeTX shows at most this many characters of a flight mode (it terminates the string at
/// index `min(16, len)` of the frame), so senders should not exceed it.
pub const FLIGHT_MODE_VISIBLE_LEN: usize = 13;

fn exact<const N: usize>(frame_type: u8, payload: &[u8]) -> Result<[u8; N], Error> {
    match payload.try_into() {
        Ok(bytes) => Ok(bytes),
        Err(_) => Err(Error::PayloadLength {
            frame_type,
            length: payload.len(),
        }),
    }
}

/// LINK_STATISTICS (0x14), 10 bytes. RSSI bytes carry the (negative) dBm as a signed byte,
/// as ExpressLRS sends and EdgeTX sign-extends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStatistics {
    /// Uplink RSSI at the receiver, antenna 1.
    pub uplink_rssi1_dbm: i8,
    /// Uplink RSSI at the receiver, antenna 2 (0 if none).
    pub uplink_rssi2_dbm: i8,
    /// Uplink link quality; 0 tells EdgeTX the link is lost.
    pub uplink_lq_percent: u8,
    /// Uplink SNR.
    pub uplink_snr_db: i8,
    /// Receiver antenna in use (0 or 1).
    pub active_antenna: u8,
    /// RF mode index (the packet-rate profile).
    pub rf_mode: u8,
    /// Index into the power table 0, 10, 25, 100, 500, 1000, 2000, 250, 50 mW.
    pub uplink_tx_power_index: u8,
    /// Downlink RSSI at the module.
    pub downlink_rssi_dbm: i8,
    /// Downlink link quality.
    pub downlink_lq_percent: u8,
    /// Downlink SNR.
    pub downlink_snr_db: i8,
}

/// The CRSF power table, milliwatts by index.
pub const TX_POWER_TABLE_MW: [u16; 9] = [0, 10, 25, 100, 500, 1000, 2000, 250, 50];

/// Index of the largest table entry not above `power_mw`; a transmitter below 10 mW reports
/// 10 mW, EdgeTX's lowest non-zero entry (index 0 reads as 0 mW: off). The RFM22B's steps
/// (1, 2, 3, 6, 13, 25, 50, 100 mW) thus show as 10, 10, 10, 10, 10, 25, 50, 100 mW.
pub fn tx_power_index(power_mw: u16) -> u8 {
    if power_mw == 0 {
        return 0;
    }
    let mut best = (1u8, 10u16);
    for (index, &table_mw) in (0u8..).zip(TX_POWER_TABLE_MW.iter()) {
        if table_mw <= power_mw && table_mw >= best.1 {
            best = (index, table_mw);
        }
    }
    best.0
}

impl LinkStatistics {
    /// The 10-byte payload.
    pub fn to_payload(&self) -> [u8; 10] {
        [
            self.uplink_rssi1_dbm as u8,
            self.uplink_rssi2_dbm as u8,
            self.uplink_lq_percent,
            self.uplink_snr_db as u8,
            self.active_antenna,
            self.rf_mode,
            self.uplink_tx_power_index,
            self.downlink_rssi_dbm as u8,
            self.downlink_lq_percent,
            self.downlink_snr_db as u8,
        ]
    }

    /// Reads the 10-byte payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let [
            r1,
            r2,
            lq,
            snr,
            antenna,
            mode,
            power,
            down_rssi,
            down_lq,
            down_snr,
        ] = exact::<10>(frame_type::LINK_STATISTICS, payload)?;
        Ok(Self {
            uplink_rssi1_dbm: r1 as i8,
            uplink_rssi2_dbm: r2 as i8,
            uplink_lq_percent: lq,
            uplink_snr_db: snr as i8,
            active_antenna: antenna,
            rf_mode: mode,
            uplink_tx_power_index: power,
            downlink_rssi_dbm: down_rssi as i8,
            downlink_lq_percent: down_lq,
            downlink_snr_db: down_snr as i8,
        })
    }
}

/// BATTERY_SENSOR (0x08), 8 bytes. 0.1 V / 0.1 A as EdgeTX, ExpressLRS and Betaflight read
/// it (the TBS text's "10 µV" is not what radios do).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Battery {
    /// Voltage in 0.1 V.
    pub voltage_dv: u16,
    /// Current in 0.1 A.
    pub current_da: u16,
    /// Used capacity in mAh (24 bit on the wire; larger values saturate).
    pub used_capacity_mah: u32,
    /// Remaining charge.
    pub remaining_percent: u8,
}

impl Battery {
    /// The 8-byte payload.
    pub fn to_payload(&self) -> [u8; 8] {
        let [v0, v1] = self.voltage_dv.to_be_bytes();
        let [c0, c1] = self.current_da.to_be_bytes();
        let [_, a0, a1, a2] = self.used_capacity_mah.min(0xFF_FFFF).to_be_bytes();
        [v0, v1, c0, c1, a0, a1, a2, self.remaining_percent]
    }

    /// Reads the 8-byte payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let [v0, v1, c0, c1, a0, a1, a2, remaining] =
            exact::<8>(frame_type::BATTERY_SENSOR, payload)?;
        Ok(Self {
            voltage_dv: u16::from_be_bytes([v0, v1]),
            current_da: u16::from_be_bytes([c0, c1]),
            used_capacity_mah: u32::from_be_bytes([0, a0, a1, a2]),
            remaining_percent: remaining,
        })
    }
}

/// ATTITUDE (0x1E), 6 bytes: angles in 100 µrad (rad × 10 000).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Attitude {
    /// Pitch, 100 µrad.
    pub pitch_100urad: i16,
    /// Roll, 100 µrad.
    pub roll_100urad: i16,
    /// Yaw, 100 µrad.
    pub yaw_100urad: i16,
}

/// Radians → 100 µrad, rounded half away from zero and saturated (NaN → 0). ±π fits: 31 416.
pub fn radians_to_100urad(angle_rad: f32) -> i16 {
    let scaled = angle_rad * 10_000.0;
    let rounded = if scaled >= 0.0 {
        scaled + 0.5
    } else {
        scaled - 0.5
    };
    // `as` saturates and maps NaN to 0.
    rounded as i16
}

impl Attitude {
    /// From angles in radians (keep them within ±π, the spec's ±180°).
    pub fn from_radians(pitch_rad: f32, roll_rad: f32, yaw_rad: f32) -> Self {
        Self {
            pitch_100urad: radians_to_100urad(pitch_rad),
            roll_100urad: radians_to_100urad(roll_rad),
            yaw_100urad: radians_to_100urad(yaw_rad),
        }
    }

    /// The 6-byte payload.
    pub fn to_payload(&self) -> [u8; 6] {
        let [p0, p1] = self.pitch_100urad.to_be_bytes();
        let [r0, r1] = self.roll_100urad.to_be_bytes();
        let [y0, y1] = self.yaw_100urad.to_be_bytes();
        [p0, p1, r0, r1, y0, y1]
    }

    /// Reads the 6-byte payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let [p0, p1, r0, r1, y0, y1] = exact::<6>(frame_type::ATTITUDE, payload)?;
        Ok(Self {
            pitch_100urad: i16::from_be_bytes([p0, p1]),
            roll_100urad: i16::from_be_bytes([r0, r1]),
            yaw_100urad: i16::from_be_bytes([y0, y1]),
        })
    }
}

/// FLIGHT_MODE (0x21): NUL-terminated text.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlightModeFrame {
    /// The mode name (no NUL inside).
    pub name: String<FLIGHT_MODE_MAX_LEN>,
}

impl FlightModeFrame {
    /// From text; fails on an interior NUL or more than 16 bytes.
    pub fn new(name: &str) -> Result<Self, Error> {
        if name.contains('\0') {
            return Err(Error::BadString);
        }
        let name = String::try_from(name).map_err(|_| Error::BadString)?;
        Ok(Self { name })
    }

    /// Name followed by its NUL.
    pub fn to_payload(&self) -> Vec<u8, MAX_PAYLOAD_LEN> {
        let mut payload = Vec::new();
        // ≤ 16 + 1 bytes always fit 60.
        let _ = payload.extend_from_slice(self.name.as_bytes());
        let _ = payload.push(0);
        payload
    }

    /// Reads text up to the first NUL; bytes after it are ignored.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let end = payload
            .iter()
            .position(|&b| b == 0)
            .ok_or(Error::Unterminated)?;
        let text = payload.get(..end).ok_or(Error::Unterminated)?;
        let text = core::str::from_utf8(text).map_err(|_| Error::BadString)?;
        Self::new(text)
    }
}

/// GPS (0x02), 15 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gps {
    /// Latitude, degrees × 10⁷.
    pub latitude_e7: i32,
    /// Longitude, degrees × 10⁷.
    pub longitude_e7: i32,
    /// Ground speed in 0.1 km/h.
    pub groundspeed_dkmh: u16,
    /// Course over ground in 0.01°.
    pub heading_cdeg: u16,
    /// Altitude in metres plus 1000 (so −1000 m … 64 535 m).
    pub altitude_m_plus_1000: u16,
    /// Satellites in use.
    pub satellites: u8,
}

impl Gps {
    /// The 15-byte payload.
    pub fn to_payload(&self) -> [u8; 15] {
        let mut out = [0u8; 15];
        let fields = self
            .latitude_e7
            .to_be_bytes()
            .into_iter()
            .chain(self.longitude_e7.to_be_bytes())
            .chain(self.groundspeed_dkmh.to_be_bytes())
            .chain(self.heading_cdeg.to_be_bytes())
            .chain(self.altitude_m_plus_1000.to_be_bytes())
            .chain([self.satellites]);
        for (slot, byte) in out.iter_mut().zip(fields) {
            *slot = byte;
        }
        out
    }

    /// Reads the 15-byte payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let bytes = exact::<15>(frame_type::GPS, payload)?;
        let field_error = Error::PayloadLength {
            frame_type: frame_type::GPS,
            length: payload.len(),
        };
        let [satellites] = be_bytes::<1>(&bytes, 14).ok_or(field_error)?;
        Ok(Self {
            latitude_e7: i32::from_be_bytes(be_bytes(&bytes, 0).ok_or(field_error)?),
            longitude_e7: i32::from_be_bytes(be_bytes(&bytes, 4).ok_or(field_error)?),
            groundspeed_dkmh: u16::from_be_bytes(be_bytes(&bytes, 8).ok_or(field_error)?),
            heading_cdeg: u16::from_be_bytes(be_bytes(&bytes, 10).ok_or(field_error)?),
            altitude_m_plus_1000: u16::from_be_bytes(be_bytes(&bytes, 12).ok_or(field_error)?),
            satellites,
        })
    }
}

/// VARIO (0x07): vertical speed, i16 cm/s; EdgeTX shows it as "VSpd" in m/s with 2 decimals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vario {
    /// Climb positive.
    pub vertical_speed_cm_s: i16,
}

impl Vario {
    /// The 2-byte payload.
    pub fn to_payload(&self) -> [u8; 2] {
        self.vertical_speed_cm_s.to_be_bytes()
    }

    /// Reads the payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        Ok(Self {
            vertical_speed_cm_s: i16::from_be_bytes(exact(frame_type::VARIO, payload)?),
        })
    }
}

/// BARO_ALTITUDE (0x09): altitude packed in a u16 as EdgeTX unpacks it: bit 15 clear →
/// decimetres + 10 000 (−1000.0 … +2276.7 m, 10 cm steps), bit 15 set → whole metres
/// (0 … 32 767 m).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BaroAltitude {
    /// The packed value.
    pub packed: u16,
}

impl BaroAltitude {
    /// Packs `altitude_cm` (rounded to 10 cm in the decimetre range, to 1 m above it;
    /// clamped to −1000 m below).
    pub fn from_cm(altitude_cm: i32) -> Self {
        let dm = (i64::from(altitude_cm) + if altitude_cm >= 0 { 5 } else { -5 }) / 10;
        let packed = if dm + 10_000 <= 0x7FFF {
            (dm + 10_000).max(0) as u16
        } else {
            let m = (i64::from(altitude_cm) + 50) / 100;
            0x8000 | (m.min(0x7FFF) as u16)
        };
        Self { packed }
    }

    /// The altitude EdgeTX shows, cm.
    pub fn to_cm(&self) -> i32 {
        if self.packed & 0x8000 != 0 {
            i32::from(self.packed & 0x7FFF) * 100
        } else {
            (i32::from(self.packed) - 10_000) * 10
        }
    }

    /// The 2-byte payload.
    pub fn to_payload(&self) -> [u8; 2] {
        self.packed.to_be_bytes()
    }

    /// Reads the payload (a trailing packed vario byte, which TBS adds, is ignored).
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [high, low, ..] if payload.len() <= 4 => Ok(Self {
                packed: u16::from_be_bytes([*high, *low]),
            }),
            _ => Err(Error::PayloadLength {
                frame_type: frame_type::BARO_ALTITUDE,
                length: payload.len(),
            }),
        }
    }
}
