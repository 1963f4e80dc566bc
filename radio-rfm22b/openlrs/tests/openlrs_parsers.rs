//! Robustness of every OpenLRSng parser of outside bytes: random and truncated inputs never
//! panic and are classified, and packing round-trips for every mode (deterministic xorshift
//! inputs, so a failure reproduces).

use openlrs::bind::{BindReception, receive_bind_packet};
use openlrs::channels::{self, ChannelMode};
use openlrs::rx::{Config, Receiver};
use openlrs::telemetry::{self, Downlink};
use openlrs::tx::{Received, Transmitter};
use openlrs::uplink::{self, Uplink};
use openlrs::{BindData, BindingVersion, RfmType};

struct XorShift(u32);

impl XorShift {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    fn bytes(&mut self, max_len: usize) -> Vec<u8> {
        let len = self.next() as usize % (max_len + 1);
        (0..len).map(|_| self.next() as u8).collect()
    }
}

#[test]
fn random_bytes_are_classified_never_panic() {
    let mut rng = XorShift(0x1234_5678);
    let mut seen = [0usize; 4];
    for _ in 0..20_000 {
        let bytes = rng.bytes(48);
        for m in 0..8 {
            match uplink::parse(ChannelMode::from_flags(m), &bytes) {
                Uplink::Servo { channels_bits, .. } => {
                    assert_eq!(
                        channels_bits.len(),
                        ChannelMode::from_flags(m).channel_count()
                    );
                    assert!(channels_bits.iter().all(|&c| c < 1024));
                    seen[0] += 1;
                }
                Uplink::Serial { data, .. } => {
                    assert!((1..=8).contains(&data.len()));
                    seen[1] += 1;
                }
                Uplink::Unknown { .. } => seen[2] += 1,
                Uplink::Truncated { len } => {
                    assert_eq!(len, bytes.len());
                    seen[3] += 1;
                }
            }
        }
        match telemetry::parse(&bytes) {
            Downlink::WrongLength { len } => assert_ne!(len, 9),
            _ => assert_eq!(bytes.len(), 9),
        }
        match receive_bind_packet(&bytes, BindingVersion::V38, RfmType::Mhz433) {
            BindReception::Accepted(d) => assert!(d.validate_for(RfmType::Mhz433).is_ok()),
            BindReception::TooShort { len } => assert!(len < 42),
            _ => {}
        }
    }
    // Every outcome occurred.
    assert!(seen.iter().all(|&n| n > 100), "{seen:?}");
}

#[test]
fn state_machines_survive_random_packets() {
    let mut rng = XorShift(42);
    let data = BindData::defaults(BindingVersion::V39, RfmType::Mhz915);
    let mut rx = Receiver::new(
        Config {
            bind_window_us: None,
            ..Config::new(BindingVersion::V39, RfmType::Mhz915)
        },
        Some(data),
    );
    rx.start(0);
    let mut tx = Transmitter::new(data, 0).unwrap();
    let mut now = 0u64;
    for _ in 0..20_000 {
        now += u64::from(rng.next() % 30_000);
        let bytes = rng.bytes(24);
        let reception = rx.on_packet(now, &bytes);
        if let Some(reply) = reception.reply {
            assert_eq!(reply.len(), 9);
            assert!(!matches!(tx.on_downlink(&reply), Received::Invalid(_)));
        }
        let _ = tx.on_downlink(&bytes);
        let _ = rx.poll(now + 1_000_000);
        assert!(rx.hop_index() < 6);
        if let Some(send) = tx.poll(now) {
            assert_eq!(send.packet.len(), data.channel_mode().packet_size());
        }
    }
}

#[test]
fn pack_unpack_round_trips_every_mode() {
    let mut rng = XorShift(7);
    for m in 0..8 {
        let mode = ChannelMode::from_flags(m);
        for _ in 0..2_000 {
            let values: Vec<u16> = (0..mode.channel_count())
                .map(|_| (rng.next() % 1024) as u16)
                .collect();
            let mut payload = [0u8; 21];
            let len = channels::pack(mode, &values, &mut payload).unwrap();
            assert_eq!(len, mode.packet_size() - 1);
            let mut out = [0u16; 20];
            assert_eq!(
                channels::unpack(mode, &payload, &mut out).unwrap(),
                values.len()
            );
            let full = mode.full_groups() * 4;
            assert_eq!(&out[..full], &values[..full]);
            for (o, v) in out[full..values.len()].iter().zip(&values[full..]) {
                assert_eq!(*o, channels::switch_to_bits(channels::two_bitfy(*v)));
            }
        }
    }
}
