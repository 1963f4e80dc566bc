//! The ULog reader (`taulink_ulog::Reader`, `format::{Format, Key}`) on fuzzed files: the
//! header made valid (the fuzzer would rarely find the magic), the rest as it comes.
//!
//! Invariants: never a panic; offsets strictly increase and stay inside the file; a
//! message the writer can write re-encodes, through `taulink_ulog::Writer`, to exactly the
//! bytes it was read from; a format's field offsets are inside its size; after the
//! incompatible-flags refusal nothing more is read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_ulog::{Error, Level, MAGIC, Message, Reader, Writer};

/// The bytes `message` is written as, for the kinds the writer writes the same way.
fn rewrite(message: &Message, out: &mut [u8]) -> Option<usize> {
    let mut w = Writer::new(out);
    let level = |l: u8| match l {
        b'0' => Some(Level::Emergency),
        b'1' => Some(Level::Alert),
        b'2' => Some(Level::Critical),
        b'3' => Some(Level::Error),
        b'4' => Some(Level::Warning),
        b'5' => Some(Level::Notice),
        b'6' => Some(Level::Info),
        b'7' => Some(Level::Debug),
        _ => None,
    };
    match *message {
        Message::Subscription {
            multi_id,
            msg_id,
            name,
        } => w.subscribe(multi_id, msg_id, name).ok(),
        Message::Data { msg_id, data } => w.data_bytes(msg_id, data).ok(),
        Message::Sync => w.sync().ok(),
        Message::Dropout { duration_ms } => w.dropout(duration_ms).ok(),
        Message::Logging {
            level: l,
            timestamp_us,
            text,
        } => {
            let text = std::str::from_utf8(text).ok()?;
            w.logging(level(l)?, timestamp_us, text).ok()
        }
        Message::Parameter { key, value } if key.ty.array.is_none() && value.len() == 4 => {
            let bits = [value[0], value[1], value[2], value[3]];
            match key.ty.name {
                "int32_t" => w.param_i32(key.name, i32::from_le_bytes(bits)).ok(),
                "float" => w.param_f32(key.name, f32::from_le_bytes(bits)).ok(),
                _ => None,
            }
        }
        _ => None,
    }
}

fuzz_target!(|data: &[u8]| {
    let mut file = Vec::with_capacity(16 + data.len());
    file.extend_from_slice(&MAGIC);
    file.push(1);
    file.extend_from_slice(&[0; 8]);
    file.extend_from_slice(data);
    let mut reader = Reader::new(&file).expect("a valid header");
    let mut last = None;
    let mut out = vec![0u8; 70_000];
    while let Some(item) = reader.next() {
        match item {
            Ok((offset, message)) => {
                assert!(offset >= 16 && offset < file.len());
                assert!(last.is_none_or(|l| offset > l), "offsets increase");
                last = Some(offset);
                let end = reader.offset();
                assert!(end > offset && end <= file.len());
                if let Some(n) = rewrite(&message, &mut out) {
                    assert_eq!(out[..n], file[offset..end], "{message:?}");
                }
                if let Message::Format(f) = message
                    && let Ok(size) = f.size()
                {
                    for field in f.fields() {
                        let (at, ty) = f.field(field.name).expect("its own field");
                        assert!(at + ty.size().expect("basic") <= size);
                    }
                }
            }
            Err(Error::IncompatibleFlags) => {
                assert!(reader.next().is_none(), "nothing after a refusal");
                break;
            }
            Err(Error::Malformed { offset }) => assert!(offset < file.len()),
            Err(e) => panic!("unexpected error {e:?}"),
        }
    }
});
