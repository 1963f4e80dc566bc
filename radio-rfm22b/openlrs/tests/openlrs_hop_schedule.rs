//! hop_schedule.json: 2·hopcount+3 consecutive TX packets per configuration — hop index,
//! channel register, XORed header byte, the 4 header bytes and the frequency.

mod openlrs_vectors;

use openlrs::hopping::Schedule;
use openlrs::modem;
use openlrs_vectors::{bind_data, hex, load, num, report};

#[test]
fn hop_schedules_match() {
    let v = load("hop_schedule.json");
    let mut count = 0;
    for variant in v["variants"].as_array().unwrap() {
        for case in variant["cases"].as_array().unwrap() {
            let data = bind_data(&case["bind_data"]);
            assert_eq!(data.hop_count() as u64, num(&case["hopcount"]));
            let packets = case["packets"].as_array().unwrap();
            for (p, hop) in packets.iter().zip(Schedule::new(&data)) {
                assert_eq!(u64::from(hop.index), num(&p["hop_index"]));
                let regs = modem::hop_registers(&data, hop.index).unwrap();
                assert_eq!(
                    regs,
                    [
                        (0x79, num(&p["reg_0x79"]) as u8),
                        (0x3D, num(&p["reg_0x3d"]) as u8),
                        (0x42, num(&p["reg_0x42"]) as u8),
                    ]
                );
                assert_eq!(hop.channel, regs[0].1);
                assert_eq!(hop.header.to_vec(), hex(p["header"].as_str().unwrap()));
                assert_eq!(u64::from(hop.frequency_hz), num(&p["frequency_hz"]));
                count += 1;
            }
        }
    }
    report("hop_schedule", count);
}
