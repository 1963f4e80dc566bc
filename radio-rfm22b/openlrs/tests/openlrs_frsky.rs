//! frsky.json: FrSky hub link and user-data frames and S.Port slots, byte for byte.

mod openlrs_vectors;

use openlrs::frsky::{self, HubEncoder, SmartPortInputs};
use openlrs_vectors::{hex, load, num, report};

#[test]
fn frsky_frames_match() {
    let v = load("frsky.json");
    let mut count = 0;
    for case in v["hub_link_frames"].as_array().unwrap() {
        let f = frsky::hub_link_frame(
            num(&case["a1"]) as u8,
            num(&case["a2"]) as u8,
            num(&case["rx"]) as u8,
            num(&case["tx"]) as u8,
        );
        assert_eq!(f.to_vec(), hex(case["bytes"].as_str().unwrap()));
        count += 1;
    }
    for case in v["hub_userdata_frames"].as_array().unwrap() {
        let mut enc = HubEncoder::default();
        assert_eq!(enc.push_serial(&hex(case["queued"].as_str().unwrap())), 0);
        for want in case["consecutive_frames"].as_array().unwrap() {
            assert_eq!(enc.user_frame().to_vec(), hex(want.as_str().unwrap()));
            count += 1;
        }
    }
    for case in v["smartport_frames"].as_array().unwrap() {
        let inputs = SmartPortInputs {
            a1: num(&case["a1"]) as u8,
            a2: num(&case["a2"]) as u8,
            rssi: num(&case["rssi"]) as u8,
            profile: num(&case["profile"]) as u8,
        };
        let f = frsky::smartport_slot(num(&case["slot"]) as u8, &inputs);
        assert_eq!(f.to_vec(), hex(case["bytes"].as_str().unwrap()), "{case}");
        count += 1;
    }
    report("frsky", count);
}
