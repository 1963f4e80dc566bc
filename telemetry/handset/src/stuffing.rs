//! The byte stuffing FrSky D link frames and S.Port frames share: frames are delimited by
//! 0x7E, and a 0x7E or 0x7D inside one is sent as 0x7D followed by the byte XOR 0x20.
//!
//! The one definition of it: the handset codecs here and the OpenLRSng TX's handset output
//! (`openlrs-ng`'s `openlrs::frsky`) both stuff with [`escaped`].

/// Frame delimiter (FrSky D) / start byte (S.Port).
pub const FRAME: u8 = 0x7E;
/// Escape byte: the next byte was XORed with [`ESCAPE_XOR`].
pub const ESCAPE: u8 = 0x7D;
/// XOR applied to an escaped byte.
pub const ESCAPE_XOR: u8 = 0x20;

/// How a payload byte that would look like framing goes on the wire: `Some([ESCAPE, byte ^
/// ESCAPE_XOR])` for 0x7E and 0x7D, `None` for every other byte (sent as it is).
pub const fn escaped(byte: u8) -> Option<[u8; 2]> {
    match byte {
        FRAME | ESCAPE => Some([ESCAPE, byte ^ ESCAPE_XOR]),
        _ => None,
    }
}

/// Bytes `bytes` take on the wire once stuffed.
pub(crate) fn stuffed_len(bytes: impl IntoIterator<Item = u8>) -> usize {
    bytes
        .into_iter()
        .map(|b| escaped(b).map_or(1, |pair| pair.len()))
        .sum()
}

/// Writes into a buffer the caller has sized with [`stuffed_len`] (excess writes are
/// dropped, never a panic).
pub(crate) struct Writer<'a> {
    slots: core::slice::IterMut<'a, u8>,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(out: &'a mut [u8]) -> Self {
        Self {
            slots: out.iter_mut(),
        }
    }

    /// A byte as it is (delimiters, S.Port's physical ID).
    pub(crate) fn raw(&mut self, byte: u8) {
        if let Some(slot) = self.slots.next() {
            *slot = byte;
        }
    }

    /// A payload byte, escaped if it would look like framing.
    pub(crate) fn stuffed(&mut self, byte: u8) {
        match escaped(byte) {
            Some([escape, flipped]) => {
                self.raw(escape);
                self.raw(flipped);
            }
            None => self.raw(byte),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_delimiter_and_the_escape_are_escaped() {
        assert_eq!(escaped(0x7E), Some([0x7D, 0x5E]));
        assert_eq!(escaped(0x7D), Some([0x7D, 0x5D]));
        for byte in (0..=255u8).filter(|b| !matches!(b, 0x7D | 0x7E)) {
            assert_eq!(escaped(byte), None);
        }
        assert_eq!(stuffed_len([1, 0x7E, 2, 0x7D]), 6);
    }
}
