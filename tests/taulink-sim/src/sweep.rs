//! The sweep's scenario per rate mode: what `--sweep` and the generated doc tables
//! ([`crate::docs`]) run each mode with, so both measure the same link.

use telemetry::channels::ChannelFormat;
use telemetry::link::RateMode;

use crate::scenario::Scenario;

/// `base` at `mode`: L50 carries 8 channels (as OpenLRSng does at that rate) to leave room
/// for uplink telemetry, the others 16; F700 is the stick mode, its 16 channels in the stick
/// format at the 1:8 telemetry ratio it is laid out for (spec §4.1), whatever `base` says.
#[must_use]
pub fn scenario(base: &Scenario, mode: RateMode) -> Scenario {
    let mut s = base.clone();
    s.rate = mode;
    if mode == RateMode::L50 {
        s.format = ChannelFormat::Compact8;
    }
    if mode == RateMode::F700 {
        s.format = ChannelFormat::Sticks16;
        s.telemetry_ratio = 8;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn l50_carries_8_channels_and_f700_is_the_stick_mode_at_1_to_8() {
        let base = Scenario::default();
        assert_eq!(
            scenario(&base, RateMode::L50).format,
            ChannelFormat::Compact8
        );
        let f700 = scenario(&base, RateMode::F700);
        assert_eq!(f700.format, ChannelFormat::Sticks16);
        assert_eq!(f700.telemetry_ratio, 8);
        let f250 = scenario(&base, RateMode::F250);
        assert_eq!(f250.format, ChannelFormat::Full16);
        assert_eq!(f250.telemetry_ratio, base.telemetry_ratio);
    }
}
