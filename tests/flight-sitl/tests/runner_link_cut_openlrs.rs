//! Issue 21's acceptance in the scenario runner: `link-cut` with both ends on OpenLRSng (the
//! module's OpenLRSng transmitter, the flight controller's OpenLRSng receiver, through the
//! virtual chips), at OpenLRSng's default profile (19 200 bit/s, 8 channels) and its
//! fastest (125 000 bit/s, 16 channels), 3.8 and 3.9, from 30 m: the same criteria as
//! TauLink's link cut (`acceptance::check`: no watchdog reset at either end during the
//! search after the cut, motors never stopped in the air, landed and disarmed by the
//! touchdown detector) and failsafe ≤ 1 s after the cut.

#![allow(clippy::unwrap_used)]

use flight_sitl::runner::Options;
use flight_sitl::runner::acceptance::{check, link_cuts_with};
use flight_sitl::runner::bound_module_settings;
use module_core::settings::{LinkProtocol, OpenLrsSettings};

fn link_cut(protocol: LinkProtocol, flight: &str, profile: u8, channel_mode: u8) {
    let mut opts = Options::factory();
    opts.settings.set_text("link.protocol", flight).unwrap();
    let module = bound_module_settings(opts.rate);
    opts.module_settings = Some(module_core::settings::Settings {
        protocol,
        openlrs: OpenLrsSettings {
            profile,
            channel_mode,
            ..OpenLrsSettings::default()
        },
        ..module
    });
    let outcomes = link_cuts_with(&opts, &[30.0]).unwrap();
    for o in &outcomes {
        let r = &o.report;
        println!("{protocol:?} profile {profile}: {}", r.to_json());
        let bad = check(r);
        assert!(bad.is_empty(), "{protocol:?} profile {profile}: {bad:?}");
        let delay = r.failsafe_delay_s.unwrap();
        assert!(delay <= 1.0, "failsafe {delay} s after the cut");
        // The OpenLRSng link flew: the pilot climbed through it to the cut.
        assert!(r.max_altitude_m > 29.0, "{}", r.max_altitude_m);
    }
}

#[test]
fn openlrs39_default_profile_link_cut_lands_and_disarms() {
    link_cut(LinkProtocol::OpenLrs39, "openlrs39", 2, 2);
}

#[test]
fn openlrs38_default_profile_link_cut_lands_and_disarms() {
    link_cut(LinkProtocol::OpenLrs38, "openlrs38", 2, 2);
}

#[test]
fn openlrs39_fastest_profile_16_channels_link_cut_lands_and_disarms() {
    link_cut(LinkProtocol::OpenLrs39, "openlrs39", 4, 6);
}
