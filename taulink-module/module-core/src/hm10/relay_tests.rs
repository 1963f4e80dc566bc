use super::*;
use proptest::prelude::*;

/// What the phone app does: split the notification stream at 0x00 and COBS-decode.
fn phone_decode(stream: &[u8]) -> Vec<Vec<u8>> {
    stream
        .split(|b| *b == 0)
        .filter(|f| !f.is_empty())
        .map(|f| {
            let mut frame = f.to_vec();
            let n = cobs::decode_in_place(&mut frame).unwrap();
            frame.truncate(n);
            frame
        })
        .collect()
}

fn phone_encode(records: &[Vec<u8>]) -> Vec<u8> {
    let mut stream = Vec::new();
    for record in records {
        let mut buf = vec![0u8; cobs::max_encoded_len(record.len())];
        let n = cobs::encode(record, &mut buf).unwrap();
        stream.extend_from_slice(&buf[..n]);
        stream.push(0);
    }
    stream
}

fn drain_to_phone(relay: &mut Relay) -> Vec<u8> {
    let mut stream = Vec::new();
    let mut frame = [0u8; MAX_FRAME_LEN];
    while let Some(n) = relay.next_frame_to_phone(&mut frame) {
        stream.extend_from_slice(&frame[..n]);
    }
    stream
}

fn drain_to_flight(relay: &mut Relay) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut record = [0u8; MAX_RECORD_LEN];
    while let Some(n) = relay.next_record_to_flight(&mut record) {
        out.push(record[..n].to_vec());
    }
    out
}

#[test]
fn records_reach_the_phone_framed_and_intact() {
    let mut relay = Relay::new(true);
    let records = [vec![0x14, 0x00, 0x64, 0x00], vec![0x08], vec![0u8; 64]];
    for record in &records {
        relay.on_link_record(record);
    }
    let stream = drain_to_phone(&mut relay);
    assert_eq!(stream.iter().filter(|b| **b == 0).count(), 3);
    assert_eq!(phone_decode(&stream), records);
    // The first frame byte for byte: code 2, 0x14, code 3, 0x64 0x00 → 0x64 then end.
    assert_eq!(&stream[..5], &[0x02, 0x14, 0x02, 0x64, 0x01]);
}

#[test]
fn a_short_output_buffer_takes_nothing() {
    let mut relay = Relay::new(true);
    relay.on_link_record(&[1, 2, 3]);
    assert_eq!(
        relay.next_frame_to_phone(&mut [0u8; MAX_FRAME_LEN - 1]),
        None
    );
    assert_eq!(
        phone_decode(&drain_to_phone(&mut relay)),
        vec![vec![1, 2, 3]]
    );
}

#[test]
fn nothing_is_sent_without_a_phone_and_notifications_switch() {
    let mut relay = Relay::new(false);
    relay.on_link_record(&[1, 2, 3]);
    assert!(drain_to_phone(&mut relay).is_empty());
    relay.on_phone_bytes(b"OK+CONN");
    assert!(relay.is_connected());
    relay.on_link_record(&[4, 5]);
    relay.on_link_record(&[6]);
    relay.on_phone_bytes(b"OK+LOST");
    assert!(!relay.is_connected());
    assert!(drain_to_phone(&mut relay).is_empty());
    assert_eq!(
        relay.stats().to_phone.records,
        2,
        "cleared on disconnect, counted"
    );
}

#[test]
fn phone_records_in_20_byte_notifications_reach_the_flight_side() {
    let mut relay = Relay::new(false);
    let records: Vec<Vec<u8>> = (0..10u8).map(|i| vec![i; usize::from(i) * 5 + 1]).collect();
    let mut stream = b"OK+CONN".to_vec();
    stream.extend(phone_encode(&records));
    // The link takes records as they come; 10 at once would overflow the 8-record queue.
    let mut received = Vec::new();
    for chunk in stream.chunks(20) {
        relay.on_phone_bytes(chunk);
        received.extend(drain_to_flight(&mut relay));
    }
    assert_eq!(received, records);
    assert_eq!(relay.stats().to_flight.records, 0);
}

#[test]
fn a_slow_phone_loses_whole_oldest_records_only() {
    let mut relay = Relay::new(true);
    for i in 0..100u8 {
        relay.on_link_record(&[i; 40]);
    }
    // 1024 bytes hold 25 records of 40 bytes: the newest 25 survive.
    let received = phone_decode(&drain_to_phone(&mut relay));
    assert_eq!(received.len(), 25);
    assert_eq!(received[0], vec![75u8; 40]);
    assert_eq!(received[24], vec![99u8; 40]);
    assert_eq!(relay.stats().to_phone.records, 75);
    assert_eq!(relay.stats().to_phone.bytes, 75 * 40);
}

#[test]
fn bad_phone_frames_are_counted_and_resynchronised() {
    let mut relay = Relay::new(true);
    let mut stream = vec![0x05, 0x01, 0x00]; // code points past the frame end
    stream.extend(vec![0x33; 200]); // longer than any frame
    stream.push(0);
    stream.extend(phone_encode(&[vec![9, 8, 7]]));
    relay.on_phone_bytes(&stream);
    assert_eq!(relay.stats().bad_frames_from_phone, 2);
    assert_eq!(drain_to_flight(&mut relay), vec![vec![9, 8, 7]]);
}

#[test]
fn module_records_stop_at_the_module_and_the_rest_goes_on() {
    use telemetry::module_record::MARKER;
    let mut relay = Relay::new(true);
    let records = vec![vec![0x01, 0x02, 0x03], vec![MARKER, 1, 0, 7], vec![0x04]];
    relay.on_phone_bytes(&phone_encode(&records));
    assert_eq!(drain_to_flight(&mut relay), vec![vec![1, 2, 3], vec![4]]);
    let mut out = [0u8; MAX_RECORD_LEN];
    let n = relay.next_record_to_module(&mut out).unwrap();
    assert_eq!(&out[..n], &[MARKER, 1, 0, 7]);
    assert_eq!(relay.next_record_to_module(&mut out), None);
}

#[test]
fn a_phone_never_speaks_for_the_radios_device_tool() {
    // A CRSF record (a PARAMETER_WRITE for the flight controller) from the phone.
    let write = vec![telemetry::crsf_record::MARKER, 35, 0x2D, 0xC8, 0xEF, 20, 3];
    let mut relay = Relay::new(true);
    relay.on_phone_bytes(&phone_encode(&[write, vec![0x04]]));
    assert_eq!(drain_to_flight(&mut relay), vec![vec![4]]);
    assert_eq!(relay.stats().bad_frames_from_phone, 1);
}

proptest! {
    #[test]
    fn random_phone_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let mut relay = Relay::new(false);
        relay.on_phone_bytes(&bytes);
        let mut out = [0u8; MAX_RECORD_LEN];
        while let Some(n) = relay.next_record_to_flight(&mut out) {
            prop_assert!(n <= MAX_RECORD_LEN);
        }
    }

    /// Records framed after any garbage (ended by a delimiter) all arrive, whole and in
    /// order, however the HM-10 chops the stream.
    #[test]
    fn records_after_garbage_arrive_whole(
        garbage in proptest::collection::vec(any::<u8>(), 0..300),
        records in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..=MAX_RECORD_LEN), 0..8),
        chunk in 1usize..=20,
    ) {
        let mut relay = Relay::new(true);
        let mut stream = garbage;
        stream.push(0);
        // Garbage may have happened to spell a notification; say where we stand.
        stream.extend_from_slice(b"OK+CONN");
        stream.extend(phone_encode(&records));
        let mut received = Vec::new();
        for piece in stream.chunks(chunk) {
            relay.on_phone_bytes(piece);
            received.extend(drain_to_flight(&mut relay));
        }
        // Module-addressed records (the marker first) stop at the module; CRSF records
        // (the radio's device tool speaks on the JR line only) are dropped.
        let for_flight: Vec<Vec<u8>> = records
            .iter()
            .filter(|r| !telemetry::module_record::is_module_payload(r))
            .filter(|r| !telemetry::crsf_record::is_crsf_payload(r))
            .cloned()
            .collect();
        let tail = received.len().saturating_sub(for_flight.len());
        prop_assert_eq!(&received[tail..], &for_flight[..]);
    }

    /// Every link record is either delivered to the phone, in order, or counted as dropped.
    #[test]
    fn link_records_delivered_or_counted(
        records in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 1..=80), 0..120),
        drain_every in 1usize..40,
    ) {
        let mut relay = Relay::new(true);
        let mut stream = Vec::new();
        for (i, record) in records.iter().enumerate() {
            relay.on_link_record(record);
            if i % drain_every == 0 {
                stream.extend(drain_to_phone(&mut relay));
            }
        }
        stream.extend(drain_to_phone(&mut relay));
        let delivered = phone_decode(&stream);
        let mut cursor = records.iter();
        for record in &delivered {
            prop_assert!(cursor.any(|r| r == record));
        }
        prop_assert_eq!(delivered.len() + relay.stats().to_phone.records as usize, records.len());
    }
}
