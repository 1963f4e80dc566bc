//! Conversions from the plain-unit reports to CRSF payloads (rounding and saturation here,
//! once).

use super::sensors::{
    Attitude, Battery, FLIGHT_MODE_VISIBLE_LEN, FlightModeFrame, Gps, LinkStatistics,
};
use super::sensors::{radians_to_100urad, tx_power_index};
use crate::report::{
    AttitudeReport, BatteryReport, FlightModeReport, GpsReport, LinkReport, scaled_u16,
};

fn dbm_i8(dbm: i16) -> i8 {
    dbm.clamp(i16::from(i8::MIN), i16::from(i8::MAX)) as i8
}

impl From<&LinkReport> for LinkStatistics {
    fn from(link: &LinkReport) -> Self {
        Self {
            uplink_rssi1_dbm: dbm_i8(link.uplink_rssi_dbm),
            uplink_rssi2_dbm: 0,
            uplink_lq_percent: link.uplink_lq_percent.min(100),
            uplink_snr_db: link.uplink_snr_db,
            active_antenna: 0,
            rf_mode: link.rf_mode,
            uplink_tx_power_index: tx_power_index(link.tx_power_mw),
            downlink_rssi_dbm: dbm_i8(link.downlink_rssi_dbm),
            downlink_lq_percent: link.downlink_lq_percent.min(100),
            downlink_snr_db: link.downlink_snr_db,
        }
    }
}

impl From<&BatteryReport> for Battery {
    fn from(battery: &BatteryReport) -> Self {
        Self {
            voltage_dv: scaled_u16(battery.voltage_mv, 100),
            current_da: scaled_u16(battery.current_ma, 100),
            used_capacity_mah: battery.used_capacity_mah.min(0xFF_FFFF),
            remaining_percent: battery.remaining_percent.min(100),
        }
    }
}

impl From<&AttitudeReport> for Attitude {
    fn from(attitude: &AttitudeReport) -> Self {
        Self {
            pitch_100urad: radians_to_100urad(attitude.pitch_rad),
            roll_100urad: radians_to_100urad(attitude.roll_rad),
            yaw_100urad: radians_to_100urad(attitude.yaw_rad),
        }
    }
}

impl From<&FlightModeReport> for FlightModeFrame {
    /// Keeps the characters EdgeTX can show (13 bytes, cut at a character boundary).
    fn from(mode: &FlightModeReport) -> Self {
        let mut name = heapless::String::new();
        for c in mode.name.chars().filter(|&c| c != '\0') {
            if name.len() + c.len_utf8() > FLIGHT_MODE_VISIBLE_LEN || name.push(c).is_err() {
                break;
            }
        }
        Self { name }
    }
}

impl From<&GpsReport> for Gps {
    fn from(gps: &GpsReport) -> Self {
        // 1 cm/s = 0.036 km/h = 0.36 units of 0.1 km/h.
        let groundspeed_dkmh = scaled_u16(gps.groundspeed_cm_s.saturating_mul(36), 100);
        let altitude = gps
            .altitude_m
            .saturating_add(1000)
            .clamp(0, i32::from(u16::MAX));
        Self {
            latitude_e7: gps.latitude_e7,
            longitude_e7: gps.longitude_e7,
            groundspeed_dkmh,
            heading_cdeg: gps.course_cdeg,
            altitude_m_plus_1000: altitude as u16,
            satellites: gps.satellites,
        }
    }
}
