//! bind_randomize.json: avr-libc `random()`, `bindRandomize(true)` per `micros()` seed and
//! the adaptive channel picker.

mod openlrs_vectors;

use openlrs::random::{AvrRandom, bind_randomize, choose_channels_per_rssi};
use openlrs::{BindData, BindingVersion, RfmType};
use openlrs_vectors::{load, num, nums, report};

#[test]
fn randomisation_matches() {
    let v = load("bind_randomize.json");
    let mut count = 0;
    for variant in v["variants"].as_array().unwrap() {
        let band = RfmType::from_rfm_type(num(&variant["rfmtype"]) as u16).unwrap();
        for case in variant["avr_random"].as_array().unwrap() {
            let mut rng = AvrRandom::new(num(&case["seed"]) as u32);
            let got: Vec<u64> = (0..12).map(|_| u64::from(rng.next_u31())).collect();
            assert_eq!(got, nums(&case["first_12"]), "seed {}", case["seed"]);
            count += 1;
        }
        for case in variant["bindRandomize_true"].as_array().unwrap() {
            let defaults = BindData::defaults(BindingVersion::V39, band);
            let mut data = defaults;
            bind_randomize(
                &mut data,
                num(&case["micros_seed"]) as u32,
                true,
                band.max_frequency_hz(),
                &defaults,
            );
            assert_eq!(u64::from(data.rf_magic), num(&case["rf_magic"]));
            let hops: Vec<u64> = data.hop_channels[..data.hop_count()]
                .iter()
                .map(|&h| u64::from(h))
                .collect();
            assert_eq!(hops, nums(&case["hopchannel"]));
            count += 1;
        }
        for case in variant["chooseChannelsPerRSSI"].as_array().unwrap() {
            let n = num(&case["n"]) as usize;
            let mut data = BindData::defaults(BindingVersion::V39, band);
            data.hop_channels = [0; 24];
            data.hop_channels[..n].fill(1);
            data.rf_frequency_hz = num(&case["rf_frequency"]) as u32;
            data.rf_channel_spacing = num(&case["rf_channel_spacing"]) as u8;
            let rssi: Vec<u8> = nums(&case["max_rssi_for_channel_1_to_254"])
                .iter()
                .map(|&r| r as u8)
                .collect();
            choose_channels_per_rssi(
                &mut data,
                &rssi.try_into().unwrap(),
                num(&case["max_frequency"]) as u32,
            );
            let picked: Vec<u64> = data.hop_channels[..n]
                .iter()
                .map(|&h| u64::from(h))
                .collect();
            assert_eq!(picked, nums(&case["picked"]));
            count += 1;
        }
    }
    report("bind_randomize", count);
}
