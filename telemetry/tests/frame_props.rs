//! Property tests of the air-frame decoder: it never panics on arbitrary bytes, and every
//! frame the encoder can produce decodes back to itself; the message-stream reader never
//! panics either.

use proptest::prelude::*;
use telemetry::channels::{ChannelFormat, pack};
use telemetry::frame::{
    Downlink, Frame, LinkReport, Received, StreamHeader, Uplink, decode, encode,
};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn decoder_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..80), key in any::<u32>()) {
        let _ = decode(&bytes, key);
    }

    #[test]
    fn decoder_never_panics_on_versioned_prefixes(
        kind in any::<u8>(),
        rest in proptest::collection::vec(any::<u8>(), 0..70),
        key in any::<u32>(),
    ) {
        // Past the version byte and with a valid CRC, so the field parsers are reached.
        let mut bytes = vec![telemetry::frame::PROTOCOL_VERSION, kind];
        bytes.extend_from_slice(&rest);
        let crc = telemetry::checksum::keyed_crc16(key, &bytes);
        bytes.extend_from_slice(&crc.to_be_bytes());
        let _ = decode(&bytes, key);
    }

    #[test]
    fn opener_never_panics_on_sealed_prefixes(
        kind in any::<u8>(),
        rest in proptest::collection::vec(any::<u8>(), 0..70),
        key in any::<[u8; 16]>(),
        counter in any::<u64>(),
    ) {
        // The sealed version with a valid tag, so the field parsers are reached; bind kinds are
        // never accepted sealed.
        let key = telemetry::link::LinkKey::from_bytes(key);
        let mut bytes = vec![telemetry::frame::SEALED_VERSION, kind];
        bytes.extend_from_slice(&rest);
        let tag = key.tag(counter, &bytes);
        bytes.extend_from_slice(&tag.to_le_bytes());
        let context = telemetry::link::auth::TagContext::Counter(counter);
        let opened = telemetry::frame::open(&bytes, &key, &context);
        let bind = matches!(
            opened,
            Received::Accepted(Frame::BindOffer(_) | Frame::BindAccept { .. })
        );
        prop_assert!(!bind);
        let other = telemetry::link::auth::TagContext::Counter(counter.wrapping_add(1));
        let _ = telemetry::frame::open(&bytes, &key, &other);
    }

    #[test]
    fn message_reader_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let mut reader = telemetry::messages::MessageReader::new();
        for b in bytes {
            let _ = reader.push(b);
        }
    }

    #[test]
    fn uplinks_round_trip(
        channels in proptest::array::uniform16(0u16..2048),
        compact in any::<bool>(),
        slot in any::<u8>(), seq in any::<u8>(), ack in any::<u8>(),
        report in proptest::option::of((any::<i8>(), 0u8..=100)),
        save in any::<bool>(),
        input_lost in any::<bool>(),
        data in proptest::collection::vec(any::<u8>(), 0..20),
        key in any::<u32>(),
    ) {
        let format = if compact { ChannelFormat::Compact8 } else { ChannelFormat::Full16 };
        let mut packed = vec![0u8; format.packed_bytes()];
        pack(&channels, format, &mut packed);
        let up = Uplink {
            slot,
            stream: StreamHeader { seq, ack },
            report: report.map(|(rssi_dbm, lq_percent)| LinkReport { rssi_dbm, lq_percent }),
            save_failsafe: save,
            input_lost,
            format,
            packed_channels: &packed,
            data: &data,
        };
        let mut buf = [0u8; 64];
        let n = encode(&Frame::Uplink(up), key, &mut buf).unwrap();
        prop_assert_eq!(decode(&buf[..n], key), Received::Accepted(Frame::Uplink(up)));
        let mut out = [0u16; 16];
        if let Received::Accepted(Frame::Uplink(u)) = decode(&buf[..n], key) {
            prop_assert!(u.channels_into(&mut out));
        }
        prop_assert_eq!(&out[..format.count()], &channels[..format.count()]);
    }

    #[test]
    fn downlinks_round_trip(
        slot in any::<u8>(), seq in any::<u8>(), ack in any::<u8>(),
        report in proptest::option::of((any::<i8>(), 0u8..=100)),
        data in proptest::collection::vec(any::<u8>(), 0..50),
        key in any::<u32>(),
    ) {
        let down = Downlink {
            slot,
            stream: StreamHeader { seq, ack },
            report: report.map(|(rssi_dbm, lq_percent)| LinkReport { rssi_dbm, lq_percent }),
            data: &data,
        };
        let mut buf = [0u8; 64];
        let n = encode(&Frame::Downlink(down), key, &mut buf).unwrap();
        prop_assert_eq!(decode(&buf[..n], key), Received::Accepted(Frame::Downlink(down)));
    }
}
