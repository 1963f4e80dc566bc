//! The README's table of worked CRSF frames is real: every row decodes as exactly one frame
//! of the type it names, parses as a message, and re-encodes to the same bytes. (What each
//! frame means is checked field by field in `crsf_frames.rs`; this keeps the table a reader
//! copies from honest.)

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use taulink_handset::crsf::{Decoded, Decoder, Message};

const README: &str = include_str!("../README.md");

/// `(letter, bytes, type)` of each row between the worked-frames markers.
fn worked_frames() -> Vec<(String, Vec<u8>, u8)> {
    let start = README.find("<!-- worked-frames").expect("start marker");
    let end = README.find("<!-- end worked-frames").expect("end marker");
    README[start..end]
        .lines()
        .filter(|line| line.starts_with("| ") && line.contains('`'))
        .map(|line| {
            let cells: Vec<&str> = line.split(" | ").collect();
            let letter = cells[0].trim_start_matches("| ").to_owned();
            let bytes = cells[1]
                .trim_matches('`')
                .split_whitespace()
                .map(|b| u8::from_str_radix(b, 16).unwrap())
                .collect();
            let frame_type = u8::from_str_radix(cells[2].trim_start_matches("0x"), 16).unwrap();
            (letter, bytes, frame_type)
        })
        .collect()
}

#[test]
fn every_worked_frame_in_the_readme_decodes_and_re_encodes() {
    let frames = worked_frames();
    assert_eq!(frames.len(), 13, "rows of the worked-frames table");
    for (letter, bytes, frame_type) in frames {
        let decoded: Vec<Decoded> = Decoder::new().feed(&bytes).collect();
        let [Decoded::Frame(frame)] = decoded.as_slice() else {
            panic!("frame {letter}: {decoded:?}");
        };
        assert_eq!(frame.frame_type, frame_type, "frame {letter}: type");
        let message =
            Message::from_frame(frame).unwrap_or_else(|e| panic!("frame {letter}: {e:?}"));
        let mut out = [0u8; 64];
        let written = message.encode(frame.address, &mut out).unwrap();
        assert_eq!(written, bytes.as_slice(), "frame {letter}: re-encoded");
    }
}
