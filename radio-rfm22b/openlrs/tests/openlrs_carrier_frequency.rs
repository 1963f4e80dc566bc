//! carrier_frequency.json: `rfmSetCarrierFrequency(f)` → registers 0x75..0x77.

mod openlrs_vectors;

use openlrs::modem::carrier_registers;
use openlrs_vectors::{load, num, report};

#[test]
fn carrier_registers_match() {
    let v = load("carrier_frequency.json");
    let mut count = 0;
    for case in v["vectors"].as_array().unwrap() {
        let f = num(&case["frequency_hz"]) as u32;
        let expected = [
            (0x75, num(&case["reg_0x75"]) as u8),
            (0x76, num(&case["reg_0x76"]) as u8),
            (0x77, num(&case["reg_0x77"]) as u8),
        ];
        assert_eq!(carrier_registers(f), expected, "{f} Hz");
        count += 1;
    }
    report("carrier_frequency", count);
}
