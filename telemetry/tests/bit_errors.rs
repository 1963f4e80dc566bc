//! 10^6 corrupted packets, none accepted: frames of every kind and size get bit errors
//! injected on air (header, length, payload and chip CRC, as the Si4432 sends them), then
//! pass the chip's checks as the receiver applies them (header compare, CRC-16/CCITT) and
//! the link decoder (version, keyed CRC-16/CMS, field checks). Every accepted packet must be
//! bit-identical to what was sent.
// Test helpers outside `#[test]` fns: the project allows panicking shortcuts in tests.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use telemetry::channels::{ChannelFormat, pack};
use telemetry::checksum::crc16;
use telemetry::frame::{
    Downlink, Frame, LinkReport, Received, StreamHeader, Uplink, decode, encode,
};
use telemetry::mock::SplitMix64;

const KEY: u32 = 0x5EED_1234;
const HEADER: [u8; 4] = [0x91, 0x3C, 0x07, 0xE2];

/// Encodes a random frame; returns its length.
fn random_frame(rng: &mut SplitMix64, buf: &mut [u8; 64]) -> usize {
    let mut channels = [0u16; 16];
    for c in channels.iter_mut() {
        *c = rng.below(2048) as u16;
    }
    let mut data = [0u8; 40];
    for d in data.iter_mut() {
        *d = rng.next_u64() as u8;
    }
    let stream = StreamHeader {
        seq: rng.next_u64() as u8,
        ack: rng.next_u64() as u8,
    };
    let report = rng.chance(0.5).then(|| LinkReport {
        rssi_dbm: -(rng.below(120) as i8),
        lq_percent: rng.below(101) as u8,
    });
    let frame_data = &data[..rng.below(6) as usize];
    if rng.chance(0.5) {
        let format = if rng.chance(0.5) {
            ChannelFormat::Full16
        } else {
            ChannelFormat::Compact8
        };
        let mut packed = [0u8; 22];
        let packed = &mut packed[..format.packed_bytes()];
        pack(&channels, format, packed);
        let up = Uplink {
            slot: rng.next_u64() as u8,
            stream,
            report,
            save_failsafe: false,
            input_lost: false,
            format,
            packed_channels: packed,
            data: frame_data,
        };
        encode(&Frame::Uplink(up), KEY, buf).unwrap()
    } else {
        let down = Downlink {
            slot: rng.next_u64() as u8,
            stream,
            report,
            data: &data[..rng.below(40) as usize],
        };
        encode(&Frame::Downlink(down), KEY, buf).unwrap()
    }
}

#[test]
fn a_million_corrupted_packets_none_accepted() {
    let mut rng = SplitMix64::new(2026);
    let mut buf = [0u8; 64];
    let (mut chip_rejected, mut link_rejected, mut header_rejected) = (0u64, 0u64, 0u64);
    const PACKETS: u64 = 1_000_000;
    for i in 0..PACKETS {
        let n = random_frame(&mut rng, &mut buf);
        // On air after sync: header, length, frame, chip CRC.
        let mut air = Vec::with_capacity(n + 7);
        air.extend_from_slice(&HEADER);
        air.push(n as u8);
        air.extend_from_slice(&buf[..n]);
        let chip = crc16(&air);
        air.extend_from_slice(&chip.to_be_bytes());
        let sent = air.clone();
        // Half with 1..=3 flipped bits (what a marginal link mostly produces), half with a
        // 1 % bit error rate (several bits, often far apart).
        if i % 2 == 0 {
            let mut bits = std::collections::HashSet::new();
            let wanted = 1 + rng.below(3) as usize;
            while bits.len() < wanted {
                bits.insert(rng.below(air.len() as u64 * 8) as usize);
            }
            for bit in bits {
                air[bit / 8] ^= 1 << (bit % 8);
            }
        } else {
            loop {
                for byte in air.iter_mut() {
                    for b in 0..8 {
                        if rng.chance(0.01) {
                            *byte ^= 1 << b;
                        }
                    }
                }
                if air != sent {
                    break;
                }
            }
        }
        assert_ne!(air, sent);
        if air[..4] != HEADER {
            header_rejected += 1;
            continue;
        }
        let len = usize::from(air[4]).min(air.len() - 7);
        let (body, crc) = air.split_at(air.len() - 2);
        if crc16(body) != u16::from_be_bytes([crc[0], crc[1]]) {
            chip_rejected += 1;
            continue;
        }
        match decode(&air[5..5 + len], KEY) {
            Received::Accepted(_) => {
                panic!("corrupted packet {i} accepted: sent {sent:02x?}, got {air:02x?}")
            }
            Received::Rejected(_) => link_rejected += 1,
        }
    }
    assert_eq!(header_rejected + chip_rejected + link_rejected, PACKETS);
    println!("header {header_rejected}, chip CRC {chip_rejected}, link {link_rejected}");
}

#[test]
fn link_crc_alone_catches_every_one_to_three_bit_error() {
    // With the chip CRC off, the link CRC's Hamming distance 4 still guarantees this.
    let mut rng = SplitMix64::new(7);
    let mut buf = [0u8; 64];
    for _ in 0..200_000 {
        let n = random_frame(&mut rng, &mut buf);
        let mut bad = buf;
        let mut flipped = std::collections::HashSet::new();
        for _ in 0..=rng.below(3) {
            flipped.insert(rng.below(n as u64 * 8) as usize);
        }
        for bit in &flipped {
            bad[bit / 8] ^= 1 << (bit % 8);
        }
        if flipped.is_empty() || bad[..n] == buf[..n] {
            continue;
        }
        assert!(
            matches!(decode(&bad[..n], KEY), Received::Rejected(_)),
            "{flipped:?}"
        );
    }
}
