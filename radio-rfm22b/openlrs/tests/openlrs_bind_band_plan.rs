//! Bind data is checked against the band plan before anything is tuned or sent (issue 14):
//! a bind that passed `validate()` used to overflow `hop_frequency_hz` (a panic in debug, a
//! wrapped frequency in release) or tune the radio outside its band.

use openlrs::bind::BindData;
use openlrs::modem;
use openlrs::{BindingVersion, RfmType};

fn defaults() -> BindData {
    BindData::defaults(BindingVersion::V38, RfmType::Mhz433)
}

#[test]
fn a_carrier_that_overflows_the_hop_frequency_is_refused() {
    let mut data = defaults();
    data.rf_frequency_hz = u32::MAX - 1_000;
    data.rf_channel_spacing = 255;
    data.hop_channels[0] = 254;
    assert!(data.validate().is_err());
    // Describing the hop must not overflow either.
    assert_eq!(modem::hop_frequency_hz(&data, 0), None);
}

#[test]
fn hops_above_the_band_are_refused() {
    // Carrier in the 433 MHz plan, but channel 254 × 2.55 MHz puts the hop at 1082.7 MHz.
    let mut data = defaults();
    data.rf_channel_spacing = 255;
    data.hop_channels[3] = 254;
    assert!(data.validate().is_err());
    // The same list with the default 50 kHz spacing stays inside 413..=463 MHz.
    data.rf_channel_spacing = 5;
    assert_eq!(data.validate(), Ok(()));
}

#[test]
fn a_carrier_outside_every_band_is_refused() {
    let mut data = defaults();
    data.rf_frequency_hz = 100_000_000;
    assert!(data.validate().is_err());
    data.rf_frequency_hz = 470_000_000; // between the 433 and 868 plans
    assert!(data.validate().is_err());
}

#[test]
fn every_band_default_is_valid() {
    for band in [RfmType::Mhz433, RfmType::Mhz868, RfmType::Mhz915] {
        for version in [BindingVersion::V38, BindingVersion::V39] {
            assert_eq!(BindData::defaults(version, band).validate(), Ok(()));
        }
    }
}

#[test]
fn the_link_is_never_configured_outside_the_band() {
    let mut data = defaults();
    data.rf_channel_spacing = 255;
    data.hop_channels[0] = 254;
    assert!(
        modem::init_script(
            BindingVersion::V38,
            RfmType::Mhz433,
            &data,
            modem::Purpose::Link
        )
        .is_err()
    );
    // A valid 868 MHz link is refused by a 433 MHz module.
    let data = BindData::defaults(BindingVersion::V38, RfmType::Mhz868);
    assert!(
        modem::init_script(
            BindingVersion::V38,
            RfmType::Mhz433,
            &data,
            modem::Purpose::Link
        )
        .is_err()
    );
    assert!(
        modem::init_script(
            BindingVersion::V38,
            RfmType::Mhz868,
            &data,
            modem::Purpose::Link
        )
        .is_ok()
    );
}
