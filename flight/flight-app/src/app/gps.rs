//! The GPS port: what the firmware's GPS task moves between the receiver's UART and the
//! app. Bytes in go through the UBX parser; a NAV-PVT goes to the estimator (fused while the
//! full INS flies, `ins.mode ins`) and, once a second, to telemetry as the `Gps` message;
//! the estimator's home goes to telemetry as the `Home` message at once when it is set or
//! moves, then every [`HOME_REPORT_PERIOD_MS`] (a ground station that joins late learns it);
//! ACK/NAKs go to the boot configuration, whose frames the task writes back.
//!
//! Boot, as the task runs it: at each baud a receiver may be at on power-up
//! ([`GPS_BOOT_BAUDS`]) it writes both generations' baud-rate messages
//! ([`gps_baud_messages`]), then switches to [`GPS_BAUD`] and writes what
//! [`FlightApp::gps_to_send`] hands out: the M9/M10 CFG-VALSET first; a receiver that NAKs
//! it is an M8 and gets the legacy CFG messages instead. A receiver that answers nothing
//! is reported (`status`) and simply listened to: an already configured one still sends
//! NAV-PVTs. The GPS task does not check in with the watchdog: no GPS (or a dead one) must
//! not reset a flying frame; its loss shows as a lost fix.

use heapless::Deque;
use telemetry::messages::{Gps, GpsFix, Home as WireHome, Message as WireMessage};
use ubx::config::{self, Bytes};
use ubx::{Configurator, FixType, Generation, Message, NavPvt, Parser, Status};

use super::FlightApp;
use crate::estimation::ins::aiding::gps::{GpsUpdate, Home};

/// The receiver's baud after configuration.
pub const GPS_BAUD: u32 = 115_200;
/// Bauds a receiver may be at on power-up: u-blox 8 defaults to 9600, 9/10 to 38400, and
/// one configured before (and not power-cycled) is at [`GPS_BAUD`].
pub const GPS_BOOT_BAUDS: [u32; 3] = [9_600, 38_400, GPS_BAUD];
/// Period of the telemetry `Gps` message, ms.
pub const GPS_REPORT_PERIOD_MS: u32 = 1_000;
/// Period of the telemetry `Home` message once the home is known, ms (a change goes out at
/// once): the home rarely moves, so a slow repeat is enough for a late listener.
pub const HOME_REPORT_PERIOD_MS: u32 = 5_000;

/// The receiver settings asked for: [`GPS_BAUD`], 5 Hz, airborne < 2 g.
fn receiver_settings() -> config::Settings {
    config::Settings {
        baud: GPS_BAUD,
        meas_period_ms: 200,
        ..config::Settings::default()
    }
}

/// Both generations' baud-rate messages (M9/M10, then M8), to write at each of
/// [`GPS_BOOT_BAUDS`] before switching the UART to [`GPS_BAUD`].
pub fn gps_baud_messages() -> [Bytes; 2] {
    let s = receiver_settings();
    [
        config::baud_message(Generation::M9M10, &s),
        config::baud_message(Generation::M8, &s),
    ]
}

/// The port's state.
#[derive(Debug, Clone)]
pub(super) struct GpsPort {
    parser: Parser,
    configurator: Configurator,
    generation: Generation,
    last_pvt: Option<NavPvt>,
    last_report_ms: Option<u32>,
    report: Option<Gps>,
    last_update: Option<GpsUpdate>,
    /// Fixes for the loop's INS, oldest first (it fuses one per step).
    pending: Deque<NavPvt, 4>,
    /// The home last queued for telemetry, and when.
    last_home: Option<(Home, u32)>,
    home_report: Option<WireHome>,
}

impl GpsPort {
    pub(super) fn new() -> Self {
        Self {
            parser: Parser::new(),
            configurator: Configurator::new(Generation::M9M10, &receiver_settings()),
            generation: Generation::M9M10,
            last_pvt: None,
            last_report_ms: None,
            report: None,
            last_update: None,
            pending: Deque::new(),
            last_home: None,
            home_report: None,
        }
    }

    /// The next fix for the loop's INS.
    pub(super) fn next_pvt(&mut self) -> Option<NavPvt> {
        self.pending.pop_front()
    }

    /// The loop fused a fix (`update`: what came of it), and the home is now `home`.
    pub(super) fn on_fused(&mut self, now_ms: u32, update: Option<GpsUpdate>, home: Option<Home>) {
        self.last_update = update;
        self.on_home(now_ms, home);
    }

    /// The `Gps` telemetry message due, once.
    pub(super) fn take_report(&mut self) -> Option<Gps> {
        self.report.take()
    }

    /// Queues the `Home` message if `home` is new or moved, or the period ran out.
    pub(super) fn on_home(&mut self, now_ms: u32, home: Option<Home>) {
        let Some(home) = home else { return };
        let due = self.last_home.is_none_or(|(last, t)| {
            last != home || now_ms.wrapping_sub(t) >= HOME_REPORT_PERIOD_MS
        });
        if due {
            self.last_home = Some((home, now_ms));
            self.home_report = Some(home_message(&home));
        }
    }
}

/// The wire's `Home` message for the estimator's home.
pub fn home_message(home: &Home) -> WireHome {
    WireHome {
        latitude_e7: home.lat_e7,
        longitude_e7: home.lon_e7,
        altitude_cm: home.h_msl_mm / 10,
        set: true,
    }
}

/// The wire's `Gps` message for a NAV-PVT.
pub fn gps_message(pvt: &NavPvt) -> Gps {
    let fix = match pvt.fix_type {
        _ if pvt.flags & NavPvt::FLAG_GNSS_FIX_OK == 0 => GpsFix::None,
        FixType::Fix3D | FixType::GnssDeadReckoning => GpsFix::Fix3d,
        FixType::Fix2D => GpsFix::Fix2d,
        _ => GpsFix::None,
    };
    // headMot is 1e-5 degree, −180…180 or 0…360 depending on the receiver.
    let course_cdeg = (pvt.head_mot_e5 / 1_000).rem_euclid(36_000);
    Gps {
        latitude_e7: pvt.lat_e7,
        longitude_e7: pvt.lon_e7,
        altitude_cm: pvt.h_msl_mm / 10,
        ground_speed_cm_s: u16::try_from((pvt.g_speed_mmps / 10).max(0)).unwrap_or(u16::MAX),
        course_cdeg: u16::try_from(course_cdeg).unwrap_or(0),
        satellites: pvt.num_sv,
        fix,
    }
}

impl FlightApp {
    /// Bytes from the GPS UART at `now_ms`: each NAV-PVT goes to the flight log, is queued
    /// for the loop's INS (it fuses one per step; more than four behind, the oldest go) and
    /// becomes the telemetry's fix when one is due.
    pub fn on_gps_bytes(&mut self, now_ms: u32, bytes: &[u8]) {
        let GpsPort {
            parser,
            configurator,
            pending,
            last_pvt,
            last_report_ms,
            report,
            ..
        } = &mut self.gps;
        let log = &mut self.log;
        parser.feed(bytes, |frame| {
            let message = Message::from_frame(&frame);
            configurator.on_message(&message);
            if let Message::NavPvt(pvt) = message {
                log.on_gps(now_ms, &pvt);
                if pending.is_full() {
                    pending.pop_front();
                }
                let _ = pending.push_back(pvt);
                *last_pvt = Some(pvt);
                if last_report_ms.is_none_or(|t| now_ms.wrapping_sub(t) >= GPS_REPORT_PERIOD_MS) {
                    *last_report_ms = Some(now_ms);
                    *report = Some(gps_message(&pvt));
                }
            }
        });
    }

    /// The configuration frame the GPS task should write now (at [`GPS_BAUD`]), if any.
    pub fn gps_to_send(&mut self, now_ms: u32) -> Option<&[u8]> {
        if self.gps.generation == Generation::M9M10
            && matches!(self.gps.configurator.status(), Status::Refused { .. })
        {
            // A receiver that refuses CFG-VALSET is a u-blox 8.
            self.gps.generation = Generation::M8;
            self.gps.configurator = Configurator::new(Generation::M8, &receiver_settings());
        }
        self.gps.configurator.poll(now_ms)
    }

    /// Where the receiver's boot configuration stands, and for which generation.
    pub fn gps_config_status(&self) -> (Generation, Status) {
        (self.gps.generation, self.gps.configurator.status())
    }

    /// The latest NAV-PVT and what the estimator did with it.
    pub fn gps_latest(&self) -> Option<(NavPvt, Option<GpsUpdate>)> {
        self.gps.last_pvt.map(|p| (p, self.gps.last_update))
    }

    /// The telemetry message for the latest fix, due once a second (the link's report
    /// takes it).
    pub(super) fn take_gps_report(&mut self) -> Option<WireMessage> {
        self.gps.take_report().map(WireMessage::Gps)
    }

    /// The `Home` message, due when the home is set or moves and then every
    /// [`HOME_REPORT_PERIOD_MS`] (the link's report takes it).
    pub(super) fn take_home_report(&mut self) -> Option<WireMessage> {
        self.gps.home_report.take().map(WireMessage::Home)
    }
}
