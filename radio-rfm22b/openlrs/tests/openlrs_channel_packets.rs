//! channel_packets.json (modes 1..6) and channel_packets_dronin_ext.json (modes 0 and 7):
//! packed servo packets byte for byte, unpacked values and their µs.
// Helpers outside #[test] fns are test code too: a malformed vector must fail loudly.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod openlrs_vectors;

use openlrs::channels::{ChannelMode, bits_to_us, us_to_bits};
use openlrs::uplink::{self, Uplink};
use openlrs_vectors::{hex, load, num, nums, report};

fn check_file(name: &str) -> usize {
    let v = load(name);
    let mut count = 0;
    for m in v["modes"].as_array().unwrap() {
        let mode = ChannelMode::from_flags(num(&m["flags_low3"]) as u8);
        assert_eq!(u64::from(mode.number()), num(&m["mode"]));
        assert_eq!(mode.channel_count() as u64, num(&m["channel_count"]));
        assert_eq!(mode.packet_size() as u64, num(&m["packet_size"]));
        assert_eq!(mode.full_groups() as u64 * 4, num(&m["full_channels"]));
        assert_eq!(
            if mode.has_switch_byte() { 4 } else { 0 },
            num(&m["switch_channels"])
        );
        for case in m["vectors"].as_array().unwrap() {
            let bits: Vec<u16> = nums(&case["channels_bits"])
                .iter()
                .map(|&b| b as u16)
                .collect();
            if case.get("channels_us").is_some() {
                let from_us: Vec<u16> = nums(&case["channels_us"])
                    .iter()
                    .map(|&us| us_to_bits(us as u16))
                    .collect();
                assert_eq!(from_us, bits);
            }
            let header = num(&case["header"]) as u8;
            let packet = uplink::servo_packet(mode, header & 0xC0, header & 1 != 0, &bits).unwrap();
            assert_eq!(packet[0], header);
            assert_eq!(
                packet.to_vec(),
                hex(case["packet"].as_str().unwrap()),
                "mode {} {bits:?}",
                mode.number()
            );
            let Uplink::Servo {
                channels_bits,
                sequence_bits,
                save_failsafe,
            } = uplink::parse(mode, &packet)
            else {
                panic!("not a servo packet")
            };
            assert_eq!(sequence_bits, header & 0xC0);
            assert_eq!(save_failsafe, header & 1 != 0);
            let unpacked: Vec<u64> = channels_bits.iter().map(|&b| u64::from(b)).collect();
            assert_eq!(unpacked, nums(&case["unpacked_bits"]));
            let us: Vec<u64> = channels_bits
                .iter()
                .map(|&b| u64::from(bits_to_us(b)))
                .collect();
            assert_eq!(us, nums(&case["unpacked_us"]));
            count += 1;
        }
    }
    count
}

#[test]
fn openlrsng_modes_1_to_6() {
    report("channel_packets", check_file("channel_packets.json"));
}

#[test]
fn dronin_modes_0_and_7() {
    report(
        "channel_packets_dronin_ext",
        check_file("channel_packets_dronin_ext.json"),
    );
}
