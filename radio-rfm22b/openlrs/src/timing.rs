//! Packet timing: `getInterval()` (airtime of the uplink plus the optional 9-byte reply,
//! rounded up to whole ms), the RX timeouts derived from it, and the `delayInMs` encoding of
//! failsafe and beacon delays.

use super::bind::BindData;
use super::modem;
use super::telemetry::DOWNLINK_FRAME_LEN;

/// Guard added after the uplink airtime (µs), `getInterval`.
pub const UPLINK_GUARD_US: u32 = 2000;
/// Guard added after the telemetry airtime (µs).
pub const TELEMETRY_GUARD_US: u32 = 1000;

/// OpenLRSng's empirical airtime: `(bytes + 15, or + 20 with diversity) · 8 200 000 / bps`
/// µs — the constant covers preamble, sync, header, length, CRC and ramp.
pub fn airtime_us(bytes: usize, bps: u32, diversity: bool) -> u32 {
    let overhead = if diversity { 20 } else { 15 };
    (bytes as u32 + overhead) * 8_200_000 / bps
}

/// `getInterval()`: the uplink packet period in µs. `None` for an unknown modem profile.
pub fn interval_us(data: &BindData) -> Option<u32> {
    let bps = modem::profile(data.modem_profile)?.bps;
    let mut us =
        airtime_us(data.channel_mode().packet_size(), bps, data.diversity()) + UPLINK_GUARD_US;
    if data.telemetry_enabled() {
        us += airtime_us(DOWNLINK_FRAME_LEN, bps, data.diversity()) + TELEMETRY_GUARD_US;
    }
    Some(us.div_ceil(1000) * 1000)
}

/// The RX's "packet missed" deadline after the previous packet: interval + 1000 µs.
pub const fn rx_hop_timeout_us(interval_us: u32) -> u32 {
    interval_us + 1000
}

/// When the RX samples RSSI after a packet, i.e. while the next one is in the air:
/// interval − 1500 µs.
pub const fn rx_rssi_sample_delay_us(interval_us: u32) -> u32 {
    interval_us.saturating_sub(1500)
}

/// `delayInMs(d)`: 0..99 in 100 ms steps, 100..189 in 1 s, 190..209 in 10 s, 210.. in 1 min.
pub const fn delay_in_ms(d: u16) -> u32 {
    let d = d as u32;
    let tenths = if d < 100 {
        d
    } else if d < 190 {
        (d - 90) * 10
    } else if d < 210 {
        (d - 180) * 100
    } else {
        (d - 205) * 600
    };
    tenths * 100
}

/// `delayInMsLong(d)` = `delayInMs(d + 100)`: the beacon dead time and interval encodings.
pub const fn delay_in_ms_long(d: u8) -> u32 {
    delay_in_ms(d as u16 + 100)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BindingVersion, RfmType};

    #[test]
    fn default_link_is_40_hz() {
        let d = BindData::defaults(BindingVersion::V38, RfmType::Mhz433);
        assert_eq!(interval_us(&d), Some(25_000));
        assert_eq!(delay_in_ms(10), 1000);
        assert_eq!(delay_in_ms_long(0), 10_000);
    }
}
