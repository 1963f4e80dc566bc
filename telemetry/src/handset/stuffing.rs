//! The byte stuffing FrSky D link frames and S.Port frames share: frames are delimited by
//! 0x7E, and a 0x7E or 0x7D inside one is sent as 0x7D followed by the byte XOR 0x20.

/// Frame delimiter (FrSky D) / start byte (S.Port).
pub const FRAME: u8 = 0x7E;
/// Escape byte: the next byte was XORed with [`ESCAPE_XOR`].
pub const ESCAPE: u8 = 0x7D;
/// XOR applied to an escaped byte.
pub const ESCAPE_XOR: u8 = 0x20;

/// Bytes `bytes` take on the wire once stuffed.
pub(crate) fn stuffed_len(bytes: impl IntoIterator<Item = u8>) -> usize {
    bytes
        .into_iter()
        .map(|b| if matches!(b, FRAME | ESCAPE) { 2 } else { 1 })
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
        if matches!(byte, FRAME | ESCAPE) {
            self.raw(ESCAPE);
            self.raw(byte ^ ESCAPE_XOR);
        } else {
            self.raw(byte);
        }
    }
}
