//! Unit tests of the air frame codec.

use super::*;
use crate::channels::pack;

const KEY: u32 = 0xA1B2_C3D4;

fn uplink_bytes(data: &[u8]) -> ([u8; 64], usize) {
    let mut ch = [0u16; 16];
    for (i, c) in ch.iter_mut().enumerate() {
        *c = 172 + i as u16 * 100;
    }
    let mut packed = [0u8; 22];
    pack(&ch, ChannelFormat::Full16, &mut packed);
    let up = Uplink {
        slot: 77,
        stream: StreamHeader { seq: 3, ack: 250 },
        report: Some(LinkReport {
            rssi_dbm: -87,
            lq_percent: 96,
        }),
        save_failsafe: true,
        input_lost: false,
        format: ChannelFormat::Full16,
        packed_channels: &packed,
        data,
    };
    let mut out = [0u8; 64];
    let n = encode(&Frame::Uplink(up), KEY, &mut out).unwrap();
    (out, n)
}

#[test]
fn uplink_round_trip_and_size() {
    let (out, n) = uplink_bytes(b"hello");
    assert_eq!(n, uplink_overhead(ChannelFormat::Full16, true) + 5);
    assert_eq!(n, 36);
    assert_eq!(out[0], PROTOCOL_VERSION);
    assert_eq!(out[1], KIND_RC16 | FLAG_REPORT | FLAG_SAVE_FAILSAFE);
    let Received::Accepted(Frame::Uplink(up)) = decode(&out[..n], KEY) else {
        panic!("not accepted");
    };
    assert_eq!(up.slot, 77);
    assert_eq!(up.stream, StreamHeader { seq: 3, ack: 250 });
    assert_eq!(
        up.report,
        Some(LinkReport {
            rssi_dbm: -87,
            lq_percent: 96
        })
    );
    assert!(up.save_failsafe);
    assert_eq!(up.data, b"hello");
    let mut ch = [0u16; 16];
    assert!(up.channels_into(&mut ch));
    assert_eq!(ch[15], 172 + 1500);
}

#[test]
fn downlink_and_bind_round_trip() {
    let down = Downlink {
        slot: 9,
        stream: StreamHeader { seq: 1, ack: 2 },
        report: None,
        data: &[0, 255, 7],
    };
    let mut out = [0u8; 64];
    let n = encode(&Frame::Downlink(down), KEY, &mut out).unwrap();
    assert_eq!(n, downlink_overhead(false) + 3);
    assert_eq!(
        decode(&out[..n], KEY),
        Received::Accepted(Frame::Downlink(down))
    );

    let plain = BindOffer {
        bind_id: 0xDEAD_BEEF,
        band: Band::Mhz868,
        rate: RateMode::F250,
        format: ChannelFormat::Compact8,
        telemetry_ratio: 4,
        exchange: None,
    };
    let exchange = OfferExchange {
        salt: Some([1; 8]),
        session: [2; 8],
        share: [3; 32],
    };
    let anonymous = OfferExchange {
        salt: None,
        ..exchange
    };
    for (offer, len) in [
        (plain, 13),
        (
            BindOffer {
                exchange: Some(exchange),
                ..plain
            },
            61,
        ),
        (
            BindOffer {
                exchange: Some(anonymous),
                ..plain
            },
            53,
        ),
    ] {
        let n = encode(&Frame::BindOffer(offer), KEY, &mut out).unwrap();
        assert_eq!(n, len);
        assert_eq!(out[0], BIND_VERSION);
        assert_eq!(
            decode(&out[..n], KEY),
            Received::Accepted(Frame::BindOffer(offer))
        );
        // One byte less or more: malformed, never a shorter offer.
        let cut = &mut out[..n - 1].to_vec()[..n - 3];
        let mut short = cut.to_vec();
        short.extend(crate::checksum::keyed_crc16(KEY, &short).to_be_bytes());
        assert_eq!(
            decode(&short, KEY),
            Received::Rejected(Rejection::Malformed)
        );
    }
    let accept = Frame::BindAccept {
        bind_id: 5,
        exchange: None,
    };
    let n = encode(&accept, KEY, &mut out).unwrap();
    assert_eq!(&out[..6], &[BIND_VERSION, KIND_BIND_ACCEPT, 5, 0, 0, 0]);
    assert_eq!(decode(&out[..n], KEY), Received::Accepted(accept));
    let accept = Frame::BindAccept {
        bind_id: 5,
        exchange: Some(AcceptExchange {
            share: [4; 32],
            tag: [5; 16],
        }),
    };
    let n = encode(&accept, KEY, &mut out).unwrap();
    assert_eq!(n, 56);
    assert_eq!(decode(&out[..n], KEY), Received::Accepted(accept));
    let confirm = Frame::BindConfirm {
        bind_id: 5,
        tag: [6; 16],
        sealed: [7; 16],
    };
    let n = encode(&confirm, KEY, &mut out).unwrap();
    assert_eq!(n, 40);
    assert_eq!(decode(&out[..n], KEY), Received::Accepted(confirm));
    // Bind kinds under the link version, link kinds under the bind version: refused.
    let mut link = out[..n - CRC_BYTES].to_vec();
    link[0] = PROTOCOL_VERSION;
    link.extend(crate::checksum::keyed_crc16(KEY, &link).to_be_bytes());
    assert!(matches!(
        decode(&link, KEY),
        Received::Rejected(Rejection::UnknownKind(_))
    ));
}

#[test]
fn foreign_key_is_rejected() {
    let (out, n) = uplink_bytes(b"x");
    assert_eq!(
        decode(&out[..n], KEY ^ 1),
        Received::Rejected(Rejection::Crc)
    );
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let (out, n) = uplink_bytes(b"abcdef");
    for bit in 0..n * 8 {
        let mut bad = out;
        bad[bit / 8] ^= 1 << (bit % 8);
        assert!(
            matches!(decode(&bad[..n], KEY), Received::Rejected(_)),
            "bit {bit}"
        );
    }
}

#[test]
fn other_version_is_rejected_first() {
    let (mut out, n) = uplink_bytes(b"");
    out[0] = 9;
    assert_eq!(
        decode(&out[..n], KEY),
        Received::Rejected(Rejection::Version(9))
    );
}

#[test]
fn short_and_inconsistent_packets_are_rejected() {
    assert_eq!(decode(&[], KEY), Received::Rejected(Rejection::TooShort));
    assert_eq!(
        decode(&[1, 2, 3], KEY),
        Received::Rejected(Rejection::TooShort)
    );
    // A correctly keyed RC16 frame whose channel block is cut short.
    let mut body = [0u8; 12];
    body[..5].copy_from_slice(&[PROTOCOL_VERSION, KIND_RC16, 0, 0, 0]);
    let crc = keyed_crc16(KEY, &body[..10]);
    body[10..].copy_from_slice(&crc.to_be_bytes());
    assert_eq!(decode(&body, KEY), Received::Rejected(Rejection::Malformed));
    // Unknown kind 7 with a valid CRC.
    let mut unknown = [PROTOCOL_VERSION, 7, 0, 0];
    let crc = keyed_crc16(KEY, &unknown[..2]);
    unknown[2..].copy_from_slice(&crc.to_be_bytes());
    assert_eq!(
        decode(&unknown, KEY),
        Received::Rejected(Rejection::UnknownKind(7))
    );
}

#[test]
fn input_lost_is_bit_5_of_uplinks_only() {
    let mut packed = [0u8; 11];
    pack(&[992; 16], ChannelFormat::Compact8, &mut packed);
    let up = Uplink {
        slot: 1,
        stream: StreamHeader::default(),
        report: None,
        save_failsafe: false,
        input_lost: true,
        format: ChannelFormat::Compact8,
        packed_channels: &packed,
        data: &[],
    };
    let mut out = [0u8; 64];
    let n = encode(&Frame::Uplink(up), KEY, &mut out).unwrap();
    assert_eq!(out[1], KIND_RC8 | FLAG_INPUT_LOST);
    assert_eq!(
        decode(&out[..n], KEY),
        Received::Accepted(Frame::Uplink(up))
    );
    // The same bit on a downlink is malformed; bits 7..6 stay reserved.
    let mut down = [
        PROTOCOL_VERSION,
        KIND_DOWNLINK | FLAG_INPUT_LOST,
        0,
        0,
        0,
        0,
        0,
    ];
    let crc = keyed_crc16(KEY, &down[..5]);
    down[5..].copy_from_slice(&crc.to_be_bytes());
    assert_eq!(decode(&down, KEY), Received::Rejected(Rejection::Malformed));
    let mut reserved = [PROTOCOL_VERSION, KIND_RC8 | 0x40, 0, 0];
    let crc = keyed_crc16(KEY, &reserved[..2]);
    reserved[2..].copy_from_slice(&crc.to_be_bytes());
    assert_eq!(
        decode(&reserved, KEY),
        Received::Rejected(Rejection::UnknownKind(KIND_RC8 | 0x40))
    );
}

#[test]
fn encode_reports_needed_size() {
    let mut small = [0u8; 10];
    let down = Downlink {
        slot: 0,
        stream: StreamHeader::default(),
        report: None,
        data: &[1; 8],
    };
    assert_eq!(
        encode(&Frame::Downlink(down), KEY, &mut small),
        Err(EncodeError::BufferTooSmall { needed: 13 })
    );
    let bad_ratio = BindOffer {
        bind_id: 1,
        band: Band::Mhz433,
        rate: RateMode::L50,
        format: ChannelFormat::Full16,
        telemetry_ratio: 3,
        exchange: None,
    };
    assert_eq!(
        encode(&Frame::BindOffer(bad_ratio), KEY, &mut [0; 64]),
        Err(EncodeError::InvalidField)
    );
}

fn sealed_key() -> LinkKey {
    LinkKey::from_bytes(core::array::from_fn(|i| 0x40 + i as u8))
}

#[test]
fn sealed_frames_round_trip_and_carry_a_four_byte_tag() {
    let (plain, n) = uplink_bytes(b"abc");
    let Received::Accepted(frame) = decode(&plain[..n], KEY) else {
        panic!()
    };
    let mut out = [0u8; 64];
    let m = seal(&frame, &sealed_key(), &TagContext::Counter(77), &mut out).unwrap();
    assert_eq!(m, n + TAG_BYTES - CRC_BYTES);
    assert_eq!(out[0], SEALED_VERSION);
    assert_eq!(
        open(&out[..m], &sealed_key(), &TagContext::Counter(77)),
        Received::Accepted(frame)
    );
}

#[test]
fn sealed_frames_fail_under_another_counter_key_or_any_flipped_bit() {
    let (plain, n) = uplink_bytes(b"");
    let Received::Accepted(frame) = decode(&plain[..n], KEY) else {
        panic!()
    };
    let mut out = [0u8; 64];
    let m = seal(&frame, &sealed_key(), &TagContext::Counter(5), &mut out).unwrap();
    let sealed = &out[..m];
    assert_eq!(
        open(sealed, &sealed_key(), &TagContext::Counter(5 + 256)),
        Received::Rejected(Rejection::Tag),
        "a replay under a later counter"
    );
    let other = LinkKey::from_bytes([0x40; 16]);
    assert_eq!(
        open(sealed, &other, &TagContext::Counter(5)),
        Received::Rejected(Rejection::Tag)
    );
    for bit in 8..m * 8 {
        let mut f = sealed.to_vec();
        f[bit / 8] ^= 1 << (bit % 8);
        assert_eq!(
            open(&f, &sealed_key(), &TagContext::Counter(5)),
            Received::Rejected(Rejection::Tag),
            "bit {bit}"
        );
    }
    // A version 1 frame (CRC keyed with the public bind ID) is no sealed frame.
    assert_eq!(
        open(&plain[..n], &sealed_key(), &TagContext::Counter(77)),
        Received::Rejected(Rejection::Version(PROTOCOL_VERSION))
    );
}

#[test]
fn bind_frames_are_never_sealed() {
    let offer = Frame::BindAccept {
        bind_id: 9,
        exchange: None,
    };
    let mut out = [0u8; 64];
    assert_eq!(
        seal(&offer, &sealed_key(), &TagContext::Counter(0), &mut out),
        Err(EncodeError::InvalidField)
    );
}

#[test]
fn the_epoch_nonce_travels_only_in_sealed_downlinks_with_64_bits_and_an_optional_proof() {
    let nonce = Frame::Nonce {
        slot: 7,
        nonce: 0x0102_0304_DEAD_BEEF,
        proof: None,
    };
    let ctx = TagContext::FollowerNonce;
    let mut out = [0u8; 64];
    let n = seal(&nonce, &sealed_key(), &ctx, &mut out).unwrap();
    assert_eq!(n, NONCE_FRAME_BYTES);
    assert_eq!(
        out[..11],
        [SEALED_VERSION, 0x44, 7, 0xEF, 0xBE, 0xAD, 0xDE, 4, 3, 2, 1]
    );
    assert_eq!(
        open(&out[..n], &sealed_key(), &ctx),
        Received::Accepted(nonce)
    );
    assert_eq!(peek_sealed(&out[..n]), Some(nonce));
    assert_eq!(
        open(&out[..n], &sealed_key(), &TagContext::Counter(9)),
        Received::Rejected(Rejection::Tag)
    );
    // With the proof of the previous epoch: kind bit 3, four more bytes.
    let proven = Frame::Nonce {
        slot: 7,
        nonce: 5,
        proof: Some(0xA1B2_C3D4),
    };
    let p = seal(&proven, &sealed_key(), &ctx, &mut out).unwrap();
    assert_eq!(p, PROVEN_NONCE_FRAME_BYTES);
    assert_eq!(out[1], 0x4C);
    assert_eq!(out[11..15], [0xD4, 0xC3, 0xB2, 0xA1]);
    assert_eq!(
        open(&out[..p], &sealed_key(), &ctx),
        Received::Accepted(proven)
    );
    // The proof bit on a nonce frame without a proof, or the proof without the bit:
    // malformed.
    for (kind, len) in [(0x4C, 11), (0x44, 15), (0x4E, 11)] {
        let mut body = out[..len].to_vec();
        body[1] = kind;
        let tag = sealed_key().tag_in(&ctx, &body);
        body.extend_from_slice(&tag.to_le_bytes());
        assert_eq!(
            open(&body, &sealed_key(), &ctx),
            Received::Rejected(Rejection::Malformed),
            "{kind:#x} {len}"
        );
    }
    // Never in a version 1 frame, never 0.
    assert_eq!(
        encode(&nonce, KEY, &mut out),
        Err(EncodeError::InvalidField)
    );
    let zero = Frame::Nonce {
        slot: 7,
        nonce: 0,
        proof: None,
    };
    assert_eq!(
        seal(&zero, &sealed_key(), &ctx, &mut out),
        Err(EncodeError::InvalidField)
    );
    // Bit 6 stays reserved in version 1 frames; in sealed frames it makes any other kind
    // byte malformed.
    let (plain, m) = uplink_bytes(b"");
    let mut flagged = plain[..m - CRC_BYTES].to_vec();
    flagged[1] |= 0x40;
    let crc = crate::checksum::keyed_crc16(KEY, &flagged);
    flagged.extend_from_slice(&crc.to_be_bytes());
    assert!(matches!(
        decode(&flagged, KEY),
        Received::Rejected(Rejection::UnknownKind(_))
    ));
    let mut body = flagged[..m - CRC_BYTES].to_vec();
    body[0] = SEALED_VERSION;
    let tag = sealed_key().tag(3, &body);
    body.extend_from_slice(&tag.to_le_bytes());
    assert_eq!(
        open(&body, &sealed_key(), &TagContext::Counter(3)),
        Received::Rejected(Rejection::Malformed)
    );
}

#[test]
fn stick_uplinks_are_kind_5_and_fit_f700_with_a_report() {
    let mut ch = [0u16; 16];
    for (i, c) in ch.iter_mut().enumerate() {
        *c = 100 + i as u16 * 97;
    }
    let mut packed = [0u8; 10];
    assert!(crate::channels::pack_group(
        &ch,
        ChannelFormat::Sticks16,
        2,
        &mut packed
    ));
    let up = Uplink {
        slot: 9,
        stream: StreamHeader::default(),
        report: Some(LinkReport {
            rssi_dbm: -60,
            lq_percent: 100,
        }),
        save_failsafe: false,
        input_lost: false,
        format: ChannelFormat::Sticks16,
        packed_channels: &packed,
        data: b"ab",
    };
    let mut out = [0u8; 64];
    let n = encode(&Frame::Uplink(up), KEY, &mut out).unwrap();
    // 5 header + 2 report + 10 channels + 2 stream + 2 CRC: F700's 21-byte frame.
    assert_eq!(n, crate::link::RateMode::F700.max_frame_bytes());
    assert_eq!(out[1] & KIND_MASK, KIND_RC_STICKS);
    let Received::Accepted(Frame::Uplink(got)) = decode(&out[..n], KEY) else {
        panic!("not accepted");
    };
    let mut output = [0u16; 16];
    assert_eq!(
        got.channels_into_mask(&mut output),
        Some(0x000F | 0b111 << 10)
    );
    assert_eq!(&output[..4], &ch[..4]);
    assert_eq!(&output[10..13], &ch[10..13]);
    // The reserved bit set (CRC recomputed): malformed.
    out[5 + 2 + 9] |= 0x80;
    let body = n - CRC_BYTES;
    let crc = keyed_crc16(KEY, &out[..body]).to_be_bytes();
    out[body..n].copy_from_slice(&crc);
    assert_eq!(
        decode(&out[..n], KEY),
        Received::Rejected(Rejection::Malformed)
    );
}

/// Sealed frames without stream data carry no seq byte (kind bit 7; it reads 0): the keyed
/// 16-channel uplink with the report is 32 bytes, F500's frame (spec §4.1, §12.7). Version 1
/// frames keep it, and a sealed frame with the flag and stream bytes is malformed.
#[test]
fn sealed_frames_without_stream_data_drop_the_seq_byte() {
    let (plain, n) = uplink_bytes(b"");
    assert_eq!(n, 31, "version 1 keeps the seq byte");
    let Received::Accepted(Frame::Uplink(up)) = decode(&plain[..n], KEY) else {
        panic!()
    };
    let mut out = [0u8; 64];
    let m = seal(
        &Frame::Uplink(up),
        &sealed_key(),
        &TagContext::Counter(5),
        &mut out,
    )
    .unwrap();
    assert_eq!(m, 32);
    assert_eq!(m, sealed_uplink_bytes(ChannelFormat::Full16, true, 0));
    assert_eq!(out[1] & 0x80, 0x80);
    assert_eq!(out[3], 250, "the ack follows the slot");
    let expected = Uplink {
        stream: StreamHeader { seq: 0, ack: 250 },
        ..up
    };
    assert_eq!(
        open(&out[..m], &sealed_key(), &TagContext::Counter(5)),
        Received::Accepted(Frame::Uplink(expected))
    );
    // With stream data the seq byte is there and the flag is not.
    let data = Uplink { data: b"xy", ..up };
    let k = seal(
        &Frame::Uplink(data),
        &sealed_key(),
        &TagContext::Counter(5),
        &mut out,
    )
    .unwrap();
    assert_eq!(k, 35);
    assert_eq!(out[1] & 0x80, 0);
    assert_eq!(
        open(&out[..k], &sealed_key(), &TagContext::Counter(5)),
        Received::Accepted(Frame::Uplink(data))
    );
    // The flag with stream bytes after the channels: malformed.
    let mut body = out[..k - TAG_BYTES].to_vec();
    body[1] |= 0x80;
    body.remove(3);
    let tag = sealed_key().tag(5, &body);
    body.extend_from_slice(&tag.to_le_bytes());
    assert_eq!(
        open(&body, &sealed_key(), &TagContext::Counter(5)),
        Received::Rejected(Rejection::Malformed)
    );
}

#[test]
fn the_master_nonce_travels_only_in_sealed_frames_as_kind_0x46_bound_to_both_nonces() {
    let nonce = Frame::MasterNonce {
        slot: 8,
        nonce: 0x0A0B_0C0D_0102_0304,
    };
    let ctx = TagContext::MasterNonce { follower_nonce: 77 };
    let mut out = [0u8; 64];
    let n = seal(&nonce, &sealed_key(), &ctx, &mut out).unwrap();
    assert_eq!(n, NONCE_FRAME_BYTES);
    assert_eq!(
        out[..11],
        [SEALED_VERSION, 0x46, 8, 4, 3, 2, 1, 0x0D, 0x0C, 0x0B, 0x0A]
    );
    assert_eq!(
        open(&out[..n], &sealed_key(), &ctx),
        Received::Accepted(nonce)
    );
    assert_eq!(peek_sealed(&out[..n]), Some(nonce));
    // Under another follower nonce it fails: only the follower it answers takes it.
    assert_eq!(
        open(
            &out[..n],
            &sealed_key(),
            &TagContext::MasterNonce { follower_nonce: 78 }
        ),
        Received::Rejected(Rejection::Tag)
    );
    assert_eq!(
        encode(&nonce, KEY, &mut out),
        Err(EncodeError::InvalidField)
    );
    let zero = Frame::MasterNonce { slot: 8, nonce: 0 };
    assert_eq!(
        seal(&zero, &sealed_key(), &ctx, &mut out),
        Err(EncodeError::InvalidField)
    );
}
