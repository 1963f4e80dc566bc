//! Instructions to authenticate one air frame on the Cortex-M4 (spec §12): the SipHash-2-4
//! tag of a 16-channel F500 uplink (27 bytes before the tag, plus the 64-bit frame counter
//! epoch₃₂ ‖ wraps₂₄ ‖ slot₈) created, then checked; the tag of F500's largest downlink (28
//! bytes before the tag; also a keyed 16-channel uplink with the report); the tag of an
//! epoch-nonce frame (7 bytes); the epoch key of a follower and a master nonce (derived once
//! per handshake, by each end); and, for comparison, the keyed link CRC-16 of the same
//! uplink that the tag replaces.
//! m4count regions: 1 = uplink tag, 3 = uplink check, 5 = downlink tag, 7 = link CRC,
//! 9 = nonce-frame tag, 11 = epoch key.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use m4_bench::{exit, m4count_marker};
    use telemetry::checksum::keyed_crc16;
    use telemetry::link::LinkKey;

    let key = LinkKey::from_bytes(black_box(core::array::from_fn(|i| (i * 13) as u8)));
    let uplink: [u8; 27] = black_box(core::array::from_fn(|i| (i * 5 + 1) as u8));
    let downlink: [u8; 28] = black_box(core::array::from_fn(|i| (i * 3 + 2) as u8));
    let nonce: [u8; 7] = black_box([3, 0x44, 0x13, 0xD4, 0xC3, 0xB2, 0xA1]);
    // Epoch 0xA1B2C3D4, 0x000102 wraps, slot 0x13.
    let counter: u64 = black_box(0xA1B2_C3D4_0001_0213);

    m4count_marker();
    let tag = black_box(key.tag(counter, &uplink));
    m4count_marker();
    m4count_marker();
    let ok = black_box(key.verify(counter, &uplink, tag));
    m4count_marker();
    m4count_marker();
    let down = black_box(key.tag(counter + 3, &downlink));
    m4count_marker();
    m4count_marker();
    let crc = black_box(keyed_crc16(0x1234_5678, &uplink));
    m4count_marker();
    m4count_marker();
    let hello = black_box(key.tag(counter & !0xFF_FF00, &nonce));
    m4count_marker();
    m4count_marker();
    let epoch = black_box(key.epoch_key(black_box(0xA1B2_C3D4), black_box(0x1234_5678)));
    m4count_marker();
    black_box((ok, down, crc, hello, epoch));
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
