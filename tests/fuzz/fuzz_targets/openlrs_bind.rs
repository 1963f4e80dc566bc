//! OpenLRSng bind packets (`openlrs::bind`) as an RX of either generation and
//! any band classifies them, and what an accepted bind then drives: the hop schedule, the
//! link's register script, the packet interval and a TX built on it.
//!
//! Invariants: the struct round-trips for every 41-byte pattern; an accepted packet is
//! exactly the bind packet of what was stored; everything an accepted bind makes the radio
//! tune lies inside the RX's band plan and the link can be configured and run.
#![no_main]

use libfuzzer_sys::fuzz_target;
use openlrs::RfmType;
use openlrs::bind::{BIND_DATA_LEN, BIND_PACKET_LEN, BindData, BindReception, receive_bind_packet};
use openlrs::modem::{self, Purpose};
use openlrs::{BindingVersion, hopping, timing, tx::Transmitter};

fuzz_target!(|packet: &[u8]| {
    if let Some(bytes) = packet.first_chunk::<BIND_DATA_LEN>() {
        assert_eq!(&BindData::from_bytes(bytes).to_bytes(), bytes);
    }
    for version in [BindingVersion::V38, BindingVersion::V39] {
        for band in [RfmType::Mhz433, RfmType::Mhz868, RfmType::Mhz915] {
            match receive_bind_packet(packet, version, band) {
                BindReception::Accepted(data) => accepted(&data, packet, version, band),
                BindReception::TooShort { len } => assert!(len < BIND_PACKET_LEN),
                BindReception::WrongVersion { found } => assert_ne!(found, version.byte()),
                BindReception::Invalid(_) | BindReception::NotBind { .. } => {}
            }
        }
    }
});

fn accepted(data: &BindData, packet: &[u8], version: BindingVersion, band: RfmType) {
    assert_eq!(&data.bind_packet()[..], &packet[..BIND_PACKET_LEN]);
    assert_eq!(data.version, version.byte());
    let hops = data.hop_count();
    assert!((1..=24).contains(&hops));
    for hop in hopping::Schedule::new(data).take(hops * 2) {
        assert!(usize::from(hop.index) < hops);
        let hz = u64::from(hop.frequency_hz);
        assert!(
            hz >= u64::from(band.min_frequency_hz()) && hz <= u64::from(band.max_frequency_hz()),
            "hop {hop:?} outside {band:?}"
        );
    }
    modem::init_script(version, band, data, Purpose::Link).expect("an accepted bind configures");
    assert!(timing::interval_us(data).is_some_and(|us| us > 0));
    Transmitter::new(*data, 0).expect("an accepted bind runs a TX");
}
