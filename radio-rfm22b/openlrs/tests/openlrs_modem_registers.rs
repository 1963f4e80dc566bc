//! modem_registers.json: OpenLRSng's modem profile table, `init_rfm(0)` write for write (both
//! generations, all profiles, with and without diversity), `rx_reset`, `tx_packet_async`
//! and `rfmSetPower`.
// Helpers outside #[test] fns are test code too: a malformed vector must fail loudly.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod openlrs_vectors;

use openlrs::BindingVersion;
use openlrs::modem::{self, Purpose, RegOp, Script};
use openlrs_vectors::{bind_data, load, num, nums, report};
use serde_json::Value;

fn writes(script: &Script) -> Vec<[u64; 2]> {
    script
        .iter()
        .filter_map(|op| match *op {
            RegOp::Write { address, value } => Some([u64::from(address), u64::from(value)]),
            RegOp::Read { .. } => None,
        })
        .collect()
}

fn reads(script: &Script) -> Vec<u64> {
    script
        .iter()
        .filter_map(|op| match *op {
            RegOp::Read { address } => Some(u64::from(address)),
            RegOp::Write { .. } => None,
        })
        .collect()
}

fn expected_writes(v: &Value) -> Vec<[u64; 2]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|w| [num(&w[0]), num(&w[1])])
        .collect()
}

fn tree_version(tree: &str) -> BindingVersion {
    match tree {
        "master" => BindingVersion::V39,
        "v3.8.9" => BindingVersion::V38,
        other => panic!("unknown tree {other}"),
    }
}

#[test]
fn modem_profiles_and_register_sequences() {
    let v = load("modem_registers.json");
    let mut count = 0;
    let check_profile = |p: &modem::ModemProfile, json: &Value| {
        assert_eq!(u64::from(p.bps), num(&json["bps"]));
        for (reg, val) in modem::MODEM_REGISTERS.iter().zip(p.values) {
            assert_eq!(
                num(&json["regs"][format!("0x{reg:02x}")]),
                u64::from(val),
                "reg {reg:#x}"
            );
        }
        assert_eq!(
            json["regs"].as_object().unwrap().len(),
            modem::MODEM_REGISTERS.len()
        );
    };
    for row in v["modem_params_table"].as_array().unwrap() {
        let p = modem::profile(num(&row["index"]) as u8).unwrap();
        check_profile(p, row);
        count += 1;
    }
    check_profile(&modem::BIND_PROFILE, &v["bind_params"]);
    count += 1;

    for (tree, cases) in v["init_rfm_normal"].as_object().unwrap() {
        let version = tree_version(tree);
        for case in cases.as_array().unwrap() {
            let data = bind_data(&case["bind_data"]);
            assert_eq!(data.modem_profile as u64, num(&case["modem_params"]));
            let script =
                modem::init_script(version, data.band().unwrap(), &data, Purpose::Link).unwrap();
            assert_eq!(
                writes(&script),
                expected_writes(&case["writes"]),
                "{tree} {data:?}"
            );
            assert_eq!(reads(&script), nums(&case["reads"]));
            // final_state: last value per register.
            let mut last = std::collections::BTreeMap::new();
            for [a, val] in writes(&script) {
                last.insert(format!("0x{a:02x}"), val);
            }
            let fin = case["final_state"].as_object().unwrap();
            assert_eq!(last.len(), fin.len());
            for (reg, val) in fin {
                assert_eq!(last[reg], num(val), "{tree} final {reg}");
            }
            count += 1;
        }
    }

    for (tree, seq) in v["rx_reset"].as_object().unwrap() {
        let script = modem::rx_reset_script(tree_version(tree), false).unwrap();
        assert_eq!(
            writes(&script),
            expected_writes(&seq["writes"]),
            "rx_reset {tree}"
        );
        assert_eq!(reads(&script), nums(&seq["reads"]));
        count += 1;
    }
    for (tree, seq) in v["tx_packet_async_3_bytes_001122"].as_object().unwrap() {
        let script = modem::tx_packet_script(&[0x00, 0x11, 0x22]).unwrap();
        assert_eq!(
            writes(&script),
            expected_writes(&seq["writes"]),
            "tx_packet {tree}"
        );
        assert_eq!(reads(&script), nums(&seq["reads"]));
        count += 1;
    }
    let mut power = Script::new();
    power.push(modem::power_write(5)).unwrap();
    assert_eq!(
        writes(&power),
        expected_writes(&v["rfmSetPower_5"]["writes"])
    );
    count += 1;
    report("modem_registers", count);
}
