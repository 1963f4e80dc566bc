//! bind_packets.json: 42-byte bind packets, the struct, derived size/count/interval, the
//! 'B' acknowledgement and `init_rfm(1)` for v3.8.9 and master on every band.

mod openlrs_vectors;

use openlrs::bind::{self, BindReception, receive_bind_packet};
use openlrs::modem::{self, Purpose, RegOp};
use openlrs::{BindingVersion, RfmType, timing};
use openlrs_vectors::{bind_data, hex, load, num, report};

#[test]
fn bind_packets_match_byte_for_byte() {
    let v = load("bind_packets.json");
    let mut count = 0;
    let mut accepted = 0;
    let mut refused = 0;
    for variant in v["variants"].as_array().unwrap() {
        let version = BindingVersion::from_byte(num(&variant["binding_version"]) as u8).unwrap();
        let band = RfmType::from_rfm_type(num(&variant["rfmtype"]) as u16).unwrap();
        assert_eq!(u64::from(version.bind_magic()), num(&variant["bind_magic"]));
        assert_eq!(
            u64::from(band.binding_frequency_hz()),
            num(&variant["binding_frequency"])
        );
        assert_eq!(
            u64::from(band.default_carrier_frequency_hz()),
            num(&variant["default_carrier_frequency"])
        );
        assert_eq!(
            u64::from(band.min_frequency_hz()),
            num(&variant["min_rfm_frequency"])
        );
        assert_eq!(
            u64::from(band.max_frequency_hz()),
            num(&variant["max_rfm_frequency"])
        );
        assert_eq!(
            u64::from(modem::BINDING_POWER),
            num(&variant["binding_power"])
        );
        assert_eq!(
            bind::BIND_DATA_LEN as u64,
            num(&variant["sizeof_bind_data"])
        );
        assert_eq!(
            hex(variant["bind_ack_packet"].as_str().unwrap()),
            vec![bind::BIND_ACK]
        );

        for case in variant["cases"].as_array().unwrap() {
            let name = case["name"].as_str().unwrap();
            let data = bind_data(&case["fields"]);
            if name == "defaults" {
                assert_eq!(data, bind::BindData::defaults(version, band), "{name}");
            }
            let packet = hex(case["packet"].as_str().unwrap());
            assert_eq!(data.bind_packet().to_vec(), packet, "{name}");
            assert_eq!(
                data.to_bytes().to_vec(),
                hex(case["bind_data_struct"].as_str().unwrap())
            );
            assert_eq!(packet.len() as u64, num(&case["packet_length"]));
            // The RX of the same generation stores exactly these fields, unless a hop lies
            // above the band plan (custom cases with 2.5 MHz steps, or 1 MHz steps from 1.25 MHz
            // above the default carrier), which OpenLRSng would tune and we refuse (issue 14); the
            // other generation refuses them all.
            let top_hop_hz = data
                .hop_channels
                .iter()
                .take_while(|&&ch| ch != 0)
                .map(|&ch| {
                    u64::from(data.rf_frequency_hz)
                        + u64::from(ch) * u64::from(data.rf_channel_spacing) * 10_000
                })
                .max()
                .unwrap();
            match receive_bind_packet(&packet, version, band) {
                BindReception::Accepted(stored) => {
                    assert_eq!(stored, data, "{name}");
                    assert!(top_hop_hz <= u64::from(band.max_frequency_hz()), "{name}");
                    accepted += 1;
                }
                BindReception::Invalid(bind::Error::HopOutOfBand { .. }) => {
                    assert!(top_hop_hz > u64::from(band.max_frequency_hz()), "{name}");
                    refused += 1;
                }
                other => panic!("{name}: {other:?}"),
            }
            let other = match version {
                BindingVersion::V38 => BindingVersion::V39,
                BindingVersion::V39 => BindingVersion::V38,
            };
            assert_eq!(
                receive_bind_packet(&packet, other, band),
                BindReception::WrongVersion {
                    found: version.byte()
                }
            );
            let mode = data.channel_mode();
            assert_eq!(
                mode.packet_size() as u64,
                num(&case["packet_size"]),
                "{name}"
            );
            assert_eq!(
                mode.channel_count() as u64,
                num(&case["channel_count"]),
                "{name}"
            );
            assert_eq!(
                u64::from(timing::interval_us(&data).unwrap()),
                num(&case["interval_us"]),
                "{name}"
            );
            count += 1;
        }

        // init_rfm(1) with the default bind data of this build.
        let defaults = bind::BindData::defaults(version, band);
        let script = modem::init_script(version, band, &defaults, Purpose::Bind).unwrap();
        let writes: Vec<[u64; 2]> = script
            .iter()
            .filter_map(|op| match *op {
                RegOp::Write { address, value } => Some([u64::from(address), u64::from(value)]),
                RegOp::Read { .. } => None,
            })
            .collect();
        let expected: Vec<[u64; 2]> = variant["init_rfm_bind"]["writes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| [num(&w[0]), num(&w[1])])
            .collect();
        assert_eq!(writes, expected, "init_rfm(1) {version:?} {band:?}");
        count += 1;
    }
    // Both outcomes occur (each case was checked against its own top hop above).
    assert!(
        accepted > 0 && refused > 0,
        "{accepted} accepted, {refused} refused"
    );
    report("bind_packets", count);
}
