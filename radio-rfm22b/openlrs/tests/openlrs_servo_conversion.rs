//! servo_conversion.json: full tables of `servoUs2Bits`, `servoBits2Us`, `twoBitfy` and the
//! switch byte 0xE4 decoded.

mod openlrs_vectors;

use openlrs::channels::{bits_to_us, switch_to_bits, two_bitfy, us_to_bits};
use openlrs_vectors::{load, num, nums, report};

#[test]
fn conversion_tables_match() {
    let v = load("servo_conversion.json");
    let mut count = 0;
    let first = num(&v["servoUs2Bits"]["first_input_us"]);
    for (i, want) in nums(&v["servoUs2Bits"]["values"]).into_iter().enumerate() {
        assert_eq!(
            u64::from(us_to_bits((first + i as u64) as u16)),
            want,
            "us {}",
            first + i as u64
        );
        count += 1;
    }
    let first = num(&v["servoBits2Us"]["first_input_bits"]);
    for (i, want) in nums(&v["servoBits2Us"]["values"]).into_iter().enumerate() {
        assert_eq!(
            u64::from(bits_to_us((first + i as u64) as u16)),
            want,
            "bits {}",
            first + i as u64
        );
        count += 1;
    }
    let first = num(&v["twoBitfy"]["first_input_bits"]);
    for (i, want) in nums(&v["twoBitfy"]["values"]).into_iter().enumerate() {
        assert_eq!(u64::from(two_bitfy((first + i as u64) as u16)), want);
        count += 1;
    }
    let decoded: Vec<u64> = (0..4)
        .map(|k| u64::from(switch_to_bits(0xE4 >> (6 - 2 * k))))
        .collect();
    assert_eq!(decoded, nums(&v["switch_unpack_values_for_byte_0xE4"]));
    count += 1;
    report("servo_conversion", count);
}
