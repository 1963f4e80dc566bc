//! timing.json: `getInterval()` for every profile × mode × telemetry × diversity, the RX
//! timeouts derived from it, and the `delayInMs`/`delayInMsLong` tables.

mod openlrs_vectors;

use openlrs::{BindData, BindingVersion, RfmType, modem, timing};
use openlrs_vectors::{load, num, nums, report};

#[test]
fn intervals_and_delays_match() {
    let v = load("timing.json");
    let mut count = 0;
    for case in v["getInterval"].as_array().unwrap() {
        let mut data = BindData::defaults(BindingVersion::V38, RfmType::Mhz433);
        data.modem_profile = num(&case["modem_params"]) as u8;
        data.flags = num(&case["flags"]) as u8;
        assert_eq!(
            u64::from(modem::profile(data.modem_profile).unwrap().bps),
            num(&case["bps"])
        );
        assert_eq!(
            data.channel_mode().packet_size() as u64,
            num(&case["packet_size"])
        );
        let interval = timing::interval_us(&data).unwrap();
        assert_eq!(u64::from(interval), num(&case["interval_us"]), "{case}");
        assert_eq!(
            u64::from(timing::rx_hop_timeout_us(interval)),
            num(&case["rx_hopTimeout_us"])
        );
        assert_eq!(
            u64::from(timing::rx_rssi_sample_delay_us(interval)),
            num(&case["rx_RSSI_timeout_us"])
        );
        count += 1;
    }
    for (d, want) in nums(&v["delayInMs"]).into_iter().enumerate() {
        assert_eq!(
            u64::from(timing::delay_in_ms(d as u16)),
            want,
            "delayInMs({d})"
        );
        count += 1;
    }
    for (d, want) in nums(&v["delayInMsLong"]).into_iter().enumerate() {
        assert_eq!(
            u64::from(timing::delay_in_ms_long(d as u8)),
            want,
            "delayInMsLong({d})"
        );
        count += 1;
    }
    report("timing", count);
}
