//! What the handset is told: the flight side's latest telemetry messages and the link's own
//! statistics, turned into `taulink_handset::HandsetTelemetry` (plain units) for the CRSF
//! responder and the S.Port / FrSky D schedulers.

use heapless::String;
use taulink_handset::HandsetTelemetry;
use taulink_handset::report::{
    AttitudeReport, BatteryReport, FlightModeReport, GpsReport, LinkReport, LinkSecurityReport,
    VerticalReport,
};
use telemetry::messages::{self, GpsFix, Message};

use crate::ports::{LinkStats, TagFailures};

/// RFM22B output power per step of register 0x6D (+1, +2, +5, +8, +11, +14, +17, +20 dBm),
/// in mW rounded, for CRSF's TX-power field.
const TX_POWER_MW: [u16; 8] = [1, 2, 3, 6, 13, 25, 50, 100];

/// Radians per centidegree (π / 18 000).
const RAD_PER_CDEG: f32 = core::f32::consts::PI / 18_000.0;

/// The flight-mode name and number the handset shows for `mode`: the mode's own short name
/// (`FlightMode::name`, what CRSF FLIGHT_MODE shows in EdgeTX) and stable id
/// (`FlightMode::id`, what S.Port DIY ID 0x5101 and the FrSky hub's Temp1 carry, having no
/// text).
pub fn flight_mode_report(mode: messages::FlightMode) -> FlightModeReport {
    FlightModeReport {
        // Kept default: every name is a constant of at most 5 characters, below the capacity.
        name: String::try_from(mode.name()).unwrap_or_default(),
        number: mode.id(),
    }
}

/// The latest of everything, as the handset sees it.
#[derive(Debug, Clone, Default)]
pub struct FlightState {
    link: LinkStats,
    tx_power_mw: u16,
    battery: Option<messages::Battery>,
    attitude: Option<messages::Attitude>,
    flight_mode: Option<messages::FlightMode>,
    gps: Option<messages::Gps>,
    vertical: Option<messages::Vertical>,
    cells: Option<u8>,
    module_battery_mv: Option<u16>,
    /// A keyed link's tag failures at both ends and the alert.
    tag_failures: Option<TagFailures>,
    /// The flight side's own view of the link (uplink RSSI/LQ), from its LinkStats message.
    flight_link: Option<messages::LinkStats>,
    /// Records that held no message this firmware knows.
    pub unknown_records: u32,
}

impl FlightState {
    /// Nothing known yet; `tx_power_step` is the RFM22B power setting 0…7.
    pub fn new(tx_power_step: u8) -> Self {
        Self {
            tx_power_mw: TX_POWER_MW
                .get(usize::from(tx_power_step))
                .copied()
                .unwrap_or(100),
            ..Self::default()
        }
    }

    /// A record from the link.
    pub fn on_record(&mut self, record: &[u8]) {
        match crate::records::decode(record) {
            Ok(message) => self.on_message(&message),
            Err(_) => self.unknown_records = self.unknown_records.saturating_add(1),
        }
    }

    /// A message from the flight side.
    pub fn on_message(&mut self, message: &Message) {
        match *message {
            Message::Battery(b) => self.battery = Some(b),
            Message::Attitude(a) => self.attitude = Some(a),
            Message::FlightMode(m) => self.flight_mode = Some(m),
            Message::Gps(g) => self.gps = Some(g),
            Message::LinkStats(l) => self.flight_link = Some(l),
            Message::Vertical(v) => self.vertical = Some(v),
            Message::Cells(c) => self.cells = (c.count > 0).then_some(c.count),
            Message::ArmState(_)
            | Message::SysIdResult(_)
            | Message::SettingChange(_)
            | Message::SignedChange(_)
            | Message::ChangeRefused(_)
            // The tag failures reach the handset through the core's device-tool row.
            | Message::LinkSecurity(_)
            // No handset protocol here carries a home (CRSF, S.Port, FrSky D); the phone does.
            | Message::Home(_)
            // The flight firmware's health: the phone shows it, the handset has no sensor.
            | Message::Health(_)
            // An older flight side's mode: its numbers meant other modes, so none is shown.
            | Message::RetiredFlightMode(_) => {}
        }
    }

    /// The module's own supply (the radio battery on JR pin 3), mV.
    pub fn on_module_battery(&mut self, millivolts: u16) {
        self.module_battery_mv = Some(millivolts);
    }

    /// A keyed link's tag failures at both ends and the alert (the core's count and alarm).
    pub fn on_tag_failures(&mut self, failures: TagFailures) {
        self.tag_failures = Some(failures);
    }

    /// The link's statistics; a running link's power step is the TX power shown from now.
    pub fn on_link_stats(&mut self, stats: &LinkStats) {
        self.link = *stats;
        if let Some(mw) = stats
            .tx_power_step
            .and_then(|s| TX_POWER_MW.get(usize::from(s)))
        {
            self.tx_power_mw = *mw;
        }
    }

    /// The link report: ours for the downlink; for the uplink the other end's report in the
    /// air frames, else its LinkStats message, else (before either arrived) our downlink LQ —
    /// the follower only answers while it hears us, so a heard downlink means a working
    /// uplink and EdgeTX must not see LQ 0 then (it would drop every sensor).
    pub fn link_report(&self) -> Option<LinkReport> {
        if !self.link.connected {
            return None;
        }
        let (uplink_rssi_dbm, uplink_lq_percent) =
            match (self.link.remote_link_quality_percent, self.flight_link) {
                (Some(lq), _) => (self.link.remote_rssi_dbm, lq),
                (None, Some(flight)) => (i16::from(flight.uplink_rssi_dbm), flight.uplink_lq),
                (None, None) => (self.link.rssi_dbm, self.link.link_quality_percent),
            };
        Some(LinkReport {
            uplink_rssi_dbm,
            uplink_lq_percent: uplink_lq_percent.max(1),
            uplink_snr_db: 0,
            downlink_rssi_dbm: self.link.rssi_dbm,
            downlink_lq_percent: self.link.link_quality_percent,
            downlink_snr_db: 0,
            tx_power_mw: self.tx_power_mw,
            rf_mode: self.link.rate_code,
        })
    }

    /// Everything for the handset encoders.
    pub fn report(&self) -> HandsetTelemetry {
        HandsetTelemetry {
            link: self.link_report(),
            battery: self.battery.map(|b| BatteryReport {
                voltage_mv: u32::from(b.voltage_mv),
                // 10 mA units; charging (negative) shows as 0 on the handset.
                current_ma: u32::try_from(i32::from(b.current_ca).max(0) * 10).unwrap_or(0),
                used_capacity_mah: u32::from(b.used_mah),
                remaining_percent: b.remaining_percent,
            }),
            attitude: self.attitude.map(|a| AttitudeReport {
                roll_rad: f32::from(a.roll_cdeg) * RAD_PER_CDEG,
                pitch_rad: f32::from(a.pitch_cdeg) * RAD_PER_CDEG,
                yaw_rad: f32::from(a.yaw_cdeg) * RAD_PER_CDEG,
            }),
            flight_mode: self.flight_mode.map(flight_mode_report),
            gps: self
                .gps
                .filter(|g| g.fix != GpsFix::None)
                .map(|g| GpsReport {
                    latitude_e7: g.latitude_e7,
                    longitude_e7: g.longitude_e7,
                    groundspeed_cm_s: u32::from(g.ground_speed_cm_s),
                    course_cdeg: g.course_cdeg,
                    altitude_m: g.altitude_cm / 100,
                    satellites: g.satellites,
                }),
            vertical: self.vertical.map(|v| VerticalReport {
                altitude_cm: v.altitude_cm,
                vario_cm_s: v.vario_cm_s,
            }),
            cells: self.cells,
            module_battery_mv: self.module_battery_mv,
            link_security: self.tag_failures.map(|t| LinkSecurityReport {
                tag_failures: t.down.saturating_add(t.up),
                alert: t.alert,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn up() -> LinkStats {
        LinkStats {
            connected: true,
            rssi_dbm: -71,
            link_quality_percent: 87,
            rate_code: 2,
            ..LinkStats::default()
        }
    }

    #[test]
    fn units_convert_to_the_report() {
        let mut state = FlightState::new(3);
        state.on_link_stats(&up());
        state.on_message(&Message::Battery(messages::Battery {
            voltage_mv: 16_020,
            current_ca: -40,
            used_mah: 900,
            remaining_percent: 20,
        }));
        state.on_message(&Message::Attitude(messages::Attitude {
            roll_cdeg: 18_000,
            pitch_cdeg: -9_000,
            yaw_cdeg: 0,
        }));
        state.on_message(&Message::Gps(messages::Gps {
            latitude_e7: 1,
            longitude_e7: 2,
            altitude_cm: -250,
            ground_speed_cm_s: 3,
            course_cdeg: 4,
            satellites: 5,
            fix: GpsFix::None,
        }));
        let report = state.report();
        let battery = report.battery.unwrap();
        assert_eq!(battery.voltage_mv, 16_020);
        assert_eq!(battery.current_ma, 0, "charging shows as 0 A");
        let attitude = report.attitude.unwrap();
        assert!((attitude.roll_rad - core::f32::consts::PI).abs() < 1e-6);
        assert!((attitude.pitch_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-6);
        assert_eq!(report.gps, None, "no fix, no GPS frame");
        let link = report.link.unwrap();
        assert_eq!(link.tx_power_mw, 6, "+8 dBm");
        assert_eq!(link.rf_mode, 2);
        assert_eq!(
            (link.downlink_rssi_dbm, link.downlink_lq_percent),
            (-71, 87)
        );
    }

    #[test]
    fn uplink_lq_prefers_the_air_report_then_the_message_then_the_downlink() {
        let mut state = FlightState::new(7);
        state.on_link_stats(&up());
        // Nothing from the other end yet: the downlink stands in.
        assert_eq!(state.link_report().unwrap().uplink_lq_percent, 87);
        state.on_message(&Message::LinkStats(messages::LinkStats {
            uplink_rssi_dbm: -80,
            uplink_lq: 64,
            downlink_rssi_dbm: 0,
            downlink_lq: 0,
            rate_mode: 2,
            received: 0,
            missed: 0,
            failsafes: 0,
        }));
        let link = state.link_report().unwrap();
        assert_eq!((link.uplink_rssi_dbm, link.uplink_lq_percent), (-80, 64));
        state.on_link_stats(&LinkStats {
            remote_rssi_dbm: -90,
            remote_link_quality_percent: Some(0),
            ..up()
        });
        // The air report wins, and a connected link never shows LQ 0.
        let link = state.link_report().unwrap();
        assert_eq!((link.uplink_rssi_dbm, link.uplink_lq_percent), (-90, 1));
        state.on_link_stats(&LinkStats::default());
        assert_eq!(state.report().link, None);
    }

    #[test]
    fn tag_failures_of_both_ends_are_summed_for_the_radio() {
        let mut state = FlightState::new(3);
        assert_eq!(state.report().link_security, None, "unkeyed: no sensor");
        state.on_tag_failures(TagFailures {
            down: 25,
            up: 3,
            alert: true,
        });
        assert_eq!(
            state.report().link_security,
            Some(LinkSecurityReport {
                tag_failures: 28,
                alert: true
            })
        );
    }

    #[test]
    fn flight_modes_have_names_and_numbers() {
        let report = flight_mode_report(messages::FlightMode::Loiter);
        assert_eq!((report.name.as_str(), report.number), ("LOIT", 7));
        let report = flight_mode_report(messages::FlightMode::Attitude);
        assert_eq!((report.name.as_str(), report.number), ("ANGL", 2));
        for mode in messages::FlightMode::ALL {
            assert_eq!(flight_mode_report(mode).name.as_str(), mode.name());
        }
    }
}
