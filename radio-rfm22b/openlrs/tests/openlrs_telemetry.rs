//! telemetry.json: composite RSSI, RSSI2Bits, countSetBits, link-info and serial frames.

mod openlrs_vectors;

use openlrs::telemetry::{
    self, Downlink, LinkInfo, LinkQuality, composite_rssi, count_set_bits, rssi_to_bits,
};
use openlrs_vectors::{hex, load, num, nums, report};

#[test]
fn telemetry_matches() {
    let v = load("telemetry.json");
    let mut count = 0;
    for (lq, row) in v["compositeRSSI"].as_array().unwrap().iter().enumerate() {
        for (rssi, want) in nums(row).into_iter().enumerate() {
            assert_eq!(
                u64::from(composite_rssi(lq as u8, rssi as u8)),
                want,
                "lq {lq} rssi {rssi}"
            );
            count += 1;
        }
    }
    for (rssi, want) in nums(&v["RSSI2Bits"]).into_iter().enumerate() {
        assert_eq!(u64::from(rssi_to_bits(rssi as u8)), want);
        count += 1;
    }
    for case in v["countSetBits"].as_array().unwrap() {
        assert_eq!(
            u64::from(count_set_bits(num(&case["x"]) as u16)),
            num(&case["bits"])
        );
        count += 1;
    }
    for case in v["downlink_linkinfo_frames"].as_array().unwrap() {
        let info = LinkInfo {
            rssi: num(&case["rssi"]) as u8,
            analog0: num(&case["ain0"]) as u8,
            analog1: num(&case["ain1"]) as u8,
            afc: num(&case["afcc"]) as u16,
            link_quality: LinkQuality(num(&case["linkQuality_reg"]) as u16).rx_quality(),
        };
        let seq = num(&case["seq_bits"]) as u8;
        let frame = telemetry::link_info_frame(seq, &info);
        assert_eq!(frame.to_vec(), hex(case["frame"].as_str().unwrap()));
        assert_eq!(
            telemetry::parse(&frame),
            Downlink::LinkInfo {
                sequence_bits: seq,
                info
            }
        );
        count += 1;
    }
    for case in v["serial_data_frames"].as_array().unwrap() {
        let n = num(&case["n_bytes"]) as usize;
        let seq = num(&case["seq_bits"]) as u8;
        let want = hex(case["frame_first_n_plus_1"].as_str().unwrap());
        // The harness fills byte i with (0x37 + n) + 7·i.
        let data: Vec<u8> = (0..n).map(|i| 0x37 + n as u8 + 7 * i as u8).collect();
        let frame = telemetry::serial_frame(seq, &data).unwrap();
        assert_eq!(u64::from(frame[0]), num(&case["header"]));
        assert_eq!(frame[..=n].to_vec(), want);
        let Downlink::Serial {
            sequence_bits,
            data: got,
        } = telemetry::parse(&frame)
        else {
            panic!()
        };
        assert_eq!((sequence_bits, got.to_vec()), (seq, data));
        count += 1;
    }
    report("telemetry", count);
}
