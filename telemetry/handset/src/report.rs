//! What the module knows about the link and the aircraft, in plain units, independent of the
//! link's own types: the input of the CRSF responder and of the S.Port / FrSky D encoders.

use heapless::String;

/// Longest flight-mode name carried.
pub const FLIGHT_MODE_NAME_MAX_LEN: usize = 16;

/// Link health both ways. `None` in [`HandsetTelemetry::link`] means no link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkReport {
    /// Uplink (module → aircraft) RSSI measured on the aircraft.
    pub uplink_rssi_dbm: i16,
    /// Uplink packets received, percent of sent.
    pub uplink_lq_percent: u8,
    /// Uplink SNR on the aircraft.
    pub uplink_snr_db: i8,
    /// Downlink (aircraft → module) RSSI measured on the module.
    pub downlink_rssi_dbm: i16,
    /// Downlink packets received, percent.
    pub downlink_lq_percent: u8,
    /// Downlink SNR on the module.
    pub downlink_snr_db: i8,
    /// Module transmit power.
    pub tx_power_mw: u16,
    /// Rate-mode index of the link.
    pub rf_mode: u8,
}

/// Flight battery.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BatteryReport {
    /// Pack voltage.
    pub voltage_mv: u32,
    /// Current drawn.
    pub current_ma: u32,
    /// Charge used since power-up.
    pub used_capacity_mah: u32,
    /// Estimated charge left.
    pub remaining_percent: u8,
}

/// Aircraft attitude, radians, each within ±π.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AttitudeReport {
    /// Roll, right wing down positive.
    pub roll_rad: f32,
    /// Pitch, nose up positive.
    pub pitch_rad: f32,
    /// Yaw (heading), clockwise from north positive.
    pub yaw_rad: f32,
}

/// Flight mode: a name for CRSF and a number for the S.Port/hub sensors, which carry no text.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlightModeReport {
    /// Short name, e.g. "ANGL" (CRSF shows 13 characters).
    pub name: String<FLIGHT_MODE_NAME_MAX_LEN>,
    /// Mode number for numeric sensors.
    pub number: u8,
}

/// GPS fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GpsReport {
    /// Latitude, degrees × 10⁷.
    pub latitude_e7: i32,
    /// Longitude, degrees × 10⁷.
    pub longitude_e7: i32,
    /// Ground speed.
    pub groundspeed_cm_s: u32,
    /// Course over ground, 0.01°.
    pub course_cdeg: u16,
    /// Altitude above mean sea level.
    pub altitude_m: i32,
    /// Satellites used.
    pub satellites: u8,
}

/// Barometric altitude and vertical speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VerticalReport {
    /// Altitude above the power-up point, cm.
    pub altitude_cm: i32,
    /// Vertical speed, cm/s, climb positive.
    pub vario_cm_s: i16,
}

/// The keyed link's authentication failures (spec §12.2): frames whose tag failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkSecurityReport {
    /// Tag failures at both ends (the module's count and the flight side's last report).
    pub tag_failures: u32,
    /// They run above what noise explains (a forger or replayer on air).
    pub alert: bool,
}

/// The flight-mode text shown while [`LinkSecurityReport::alert`] stands (CRSF's FM
/// sensor; EdgeTX shows 13 characters).
pub const TAG_ALERT_TEXT: &str = "TAG ALERT";

/// Everything the handset may be told. Absent parts are simply not sent.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HandsetTelemetry {
    /// Link health; `None` = link down.
    pub link: Option<LinkReport>,
    /// Flight battery.
    pub battery: Option<BatteryReport>,
    /// Attitude.
    pub attitude: Option<AttitudeReport>,
    /// Flight mode.
    pub flight_mode: Option<FlightModeReport>,
    /// GPS fix.
    pub gps: Option<GpsReport>,
    /// Barometric altitude and vario.
    pub vertical: Option<VerticalReport>,
    /// Flight battery cells in series (with `battery`, the per-cell voltage).
    pub cells: Option<u8>,
    /// The module's own supply, mV.
    pub module_battery_mv: Option<u16>,
    /// The keyed link's tag failures.
    pub link_security: Option<LinkSecurityReport>,
}

impl HandsetTelemetry {
    /// The average cell voltage, mV, when the pack voltage and a non-zero cell count are known.
    pub fn cell_mv(&self) -> Option<u16> {
        let count = u32::from(self.cells.filter(|c| *c > 0)?);
        let battery = self.battery?;
        u16::try_from(battery.voltage_mv / count).ok()
    }

    /// The flight mode to show: the tag alert's text over the mode while the alert stands
    /// (the number stays the mode's, or 0), so the pilot sees it on the FM sensor.
    pub fn flight_mode_shown(&self) -> Option<FlightModeReport> {
        if self.link_security.is_some_and(|s| s.alert) {
            let mut name = String::new();
            let _ = name.push_str(TAG_ALERT_TEXT);
            let number = self.flight_mode.as_ref().map_or(0, |m| m.number);
            return Some(FlightModeReport { name, number });
        }
        self.flight_mode.clone()
    }

    /// True if the link is up with a non-zero uplink LQ: the radio then accepts sensor values
    /// (EdgeTX drops all of them while the LQ / RSSI it sees is 0).
    pub fn link_streaming(&self) -> bool {
        self.link.is_some_and(|link| link.uplink_lq_percent > 0)
    }
}

/// `value / divisor` rounded to nearest, saturated to u16.
pub(crate) fn scaled_u16(value: u32, divisor: u32) -> u16 {
    let rounded = value.saturating_add(divisor / 2) / divisor.max(1);
    u16::try_from(rounded).unwrap_or(u16::MAX)
}
