//! crc16.json: `CRC16_add()` (CCITT 0x1021, init 0).

mod openlrs_vectors;

use openlrs::crc16::crc16;
use openlrs_vectors::{hex, load, num, report};

#[test]
fn crc16_matches() {
    let v = load("crc16.json");
    let mut count = 0;
    for case in v["vectors"].as_array().unwrap() {
        assert_eq!(
            u64::from(crc16(&hex(case["data"].as_str().unwrap()))),
            num(&case["crc"])
        );
        count += 1;
    }
    report("crc16", count);
}
