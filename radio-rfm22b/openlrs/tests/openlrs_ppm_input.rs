//! ppm_input.json: TX PPM pulse-train decoding (`processPulse`).

mod openlrs_vectors;

use openlrs::ppm::{PpmDecoder, Pulse};
use openlrs_vectors::{load, num, nums, report};

#[test]
fn ppm_frames_match() {
    let v = load("ppm_input.json");
    let mut count = 0;
    for case in v["cases"].as_array().unwrap() {
        let mut dec = PpmDecoder::new(num(&case["minch"]) as u8);
        let mut accepted = false;
        for w in nums(&case["pulses_us"]) {
            accepted |= matches!(dec.pulse(w as u16), Pulse::FrameAccepted { .. });
        }
        assert_eq!(
            accepted,
            case["frame_accepted"].as_bool().unwrap(),
            "{}",
            case["name"]
        );
        let got: Vec<u64> = dec.channels().iter().map(|&c| u64::from(c)).collect();
        assert_eq!(got, nums(&case["PPM_bits_after"]), "{}", case["name"]);
        count += 1;
    }
    report("ppm_input", count);
}
