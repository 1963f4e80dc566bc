//! Appending ULog messages to a buffer the caller owns. Each method writes one whole
//! message or nothing ([`Error::Full`]): a buffer (a flash page, a link frame, a file
//! chunk) only ever holds complete messages, so a log cut between two buffers is still a
//! log whose last whole message is readable. No heap, no formatting machinery: numbers in
//! keys are written digit by digit.

use crate::record::Record;
use crate::{
    Error, FLAG_BITS_LEN, HEADER_LEN, Level, MAGIC, MESSAGE_HEADER_LEN, SYNC_MAGIC, VERSION, kind,
};

/// A cursor appending messages to `buf`.
#[derive(Debug)]
pub struct Writer<'a> {
    buf: &'a mut [u8],
    len: usize,
}

/// The decimal digits of `n` in `out`, returning how many (at most 5 for a `u16`).
fn decimal(mut n: u16, out: &mut [u8; 5]) -> usize {
    let mut tmp = [0u8; 5];
    let mut k = 0;
    loop {
        if let Some(t) = tmp.get_mut(k) {
            *t = b'0' + (n % 10) as u8;
        }
        k += 1;
        n /= 10;
        if n == 0 || k == tmp.len() {
            break;
        }
    }
    for (o, t) in out.iter_mut().zip(tmp.iter().take(k).rev()) {
        *o = *t;
    }
    k
}

impl<'a> Writer<'a> {
    /// A writer filling `buf` from its start.
    pub fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, len: 0 }
    }

    /// The bytes written so far.
    pub fn written(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or_default()
    }

    /// How many bytes are written.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Nothing written yet.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Room left, bytes.
    pub fn remaining(&self) -> usize {
        self.buf.len() - self.len
    }

    /// Forgets what was written (the caller has moved it out).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends raw `parts` as one unit, or nothing.
    fn put(&mut self, parts: &[&[u8]]) -> Result<usize, Error> {
        let total: usize = parts.iter().map(|p| p.len()).sum();
        let end = self.len.checked_add(total).ok_or(Error::Full)?;
        let out = self.buf.get_mut(self.len..end).ok_or(Error::Full)?;
        let mut at = 0;
        for p in parts {
            if let Some(o) = out.get_mut(at..at + p.len()) {
                o.copy_from_slice(p);
            }
            at += p.len();
        }
        self.len = end;
        Ok(total)
    }

    /// One message of type `msg_type` whose body is `parts` in order.
    fn message(&mut self, msg_type: u8, parts: &[&[u8]]) -> Result<usize, Error> {
        let body: usize = parts.iter().map(|p| p.len()).sum();
        let size = u16::try_from(body).map_err(|_| Error::TooLong)?;
        let [lo, hi] = size.to_le_bytes();
        if self.remaining() < MESSAGE_HEADER_LEN + body {
            return Err(Error::Full);
        }
        self.put(&[&[lo, hi, msg_type]])?;
        self.put(parts)?;
        Ok(MESSAGE_HEADER_LEN + body)
    }

    /// The file header: magic, version 1, the logging start time (µs).
    ///
    /// # Errors
    /// [`Error::Full`].
    pub fn header(&mut self, start_us: u64) -> Result<usize, Error> {
        if self.remaining() < HEADER_LEN {
            return Err(Error::Full);
        }
        self.put(&[&MAGIC, &[VERSION], &start_us.to_le_bytes()])
    }

    /// The flag-bits message, no flag set and nothing appended (it must come right after
    /// the header).
    ///
    /// # Errors
    /// [`Error::Full`].
    pub fn flag_bits(&mut self) -> Result<usize, Error> {
        self.message(kind::FLAG_BITS, &[&[0u8; FLAG_BITS_LEN]])
    }

    /// A format message: `format` is the whole text, `name:type field;…` (a record's is
    /// [`Record::FORMAT`]).
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn format(&mut self, format: &str) -> Result<usize, Error> {
        self.message(kind::FORMAT, &[format.as_bytes()])
    }

    /// A key/value message (information or parameter) with key `type name`.
    fn keyed(
        &mut self,
        msg_type: u8,
        type_parts: &[&[u8]],
        name: &str,
        value: &[u8],
    ) -> Result<usize, Error> {
        let key_len: usize = type_parts.iter().map(|p| p.len()).sum::<usize>() + 1 + name.len();
        let key_len = u8::try_from(key_len).map_err(|_| Error::TooLong)?;
        match type_parts {
            [a] => self.message(msg_type, &[&[key_len], a, b" ", name.as_bytes(), value]),
            [a, b, c] => self.message(
                msg_type,
                &[&[key_len], a, b, c, b" ", name.as_bytes(), value],
            ),
            _ => Err(Error::InvalidText),
        }
    }

    /// An information message with a text value (`char[len] name`).
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`] (a key over 255 bytes, a value over 65 535).
    pub fn info_str(&mut self, name: &str, value: &str) -> Result<usize, Error> {
        let n = u16::try_from(value.len()).map_err(|_| Error::TooLong)?;
        let mut digits = [0u8; 5];
        let k = decimal(n, &mut digits);
        let digits = digits.get(..k).unwrap_or_default();
        self.keyed(
            kind::INFO,
            &[b"char[", digits, b"]"],
            name,
            value.as_bytes(),
        )
    }

    /// An information message with a `uint32_t` value.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn info_u32(&mut self, name: &str, value: u32) -> Result<usize, Error> {
        self.keyed(kind::INFO, &[b"uint32_t"], name, &value.to_le_bytes())
    }

    /// A parameter message with an `int32_t` value.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn param_i32(&mut self, name: &str, value: i32) -> Result<usize, Error> {
        self.keyed(kind::PARAMETER, &[b"int32_t"], name, &value.to_le_bytes())
    }

    /// A parameter message with a `float` value.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn param_f32(&mut self, name: &str, value: f32) -> Result<usize, Error> {
        self.keyed(kind::PARAMETER, &[b"float"], name, &value.to_le_bytes())
    }

    /// A subscription: `msg_id` stands for the format `name` from here on.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn subscribe(&mut self, multi_id: u8, msg_id: u16, name: &str) -> Result<usize, Error> {
        self.message(
            kind::SUBSCRIPTION,
            &[&[multi_id], &msg_id.to_le_bytes(), name.as_bytes()],
        )
    }

    /// A logged-data message carrying `record` under `msg_id`.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn data<R: Record>(&mut self, msg_id: u16, record: &R) -> Result<usize, Error> {
        let body = 2 + R::SIZE;
        let size = u16::try_from(body).map_err(|_| Error::TooLong)?;
        if self.remaining() < MESSAGE_HEADER_LEN + body {
            return Err(Error::Full);
        }
        let [lo, hi] = size.to_le_bytes();
        let [id_lo, id_hi] = msg_id.to_le_bytes();
        let start = self.len;
        self.put(&[&[lo, hi, kind::DATA, id_lo, id_hi]])?;
        let out = self.buf.get_mut(self.len..).ok_or(Error::Full)?;
        if let Err(e) = record.encode(out) {
            self.len = start;
            return Err(e);
        }
        self.len += R::SIZE;
        Ok(MESSAGE_HEADER_LEN + body)
    }

    /// A logged-data message with an already encoded body.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn data_bytes(&mut self, msg_id: u16, payload: &[u8]) -> Result<usize, Error> {
        self.message(kind::DATA, &[&msg_id.to_le_bytes(), payload])
    }

    /// A logged string at `timestamp_us`.
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn logging(&mut self, level: Level, timestamp_us: u64, text: &str) -> Result<usize, Error> {
        self.message(
            kind::LOGGING,
            &[&[level as u8], &timestamp_us.to_le_bytes(), text.as_bytes()],
        )
    }

    /// A logged string made of `parts` in order (a fixed prefix and a name, without a
    /// formatting machinery).
    ///
    /// # Errors
    /// [`Error::Full`], [`Error::TooLong`].
    pub fn logging_parts(
        &mut self,
        level: Level,
        timestamp_us: u64,
        parts: &[&str],
    ) -> Result<usize, Error> {
        let text: usize = parts.iter().map(|p| p.len()).sum();
        let body = 9 + text;
        let size = u16::try_from(body).map_err(|_| Error::TooLong)?;
        if self.remaining() < MESSAGE_HEADER_LEN + body {
            return Err(Error::Full);
        }
        let [lo, hi] = size.to_le_bytes();
        self.put(&[
            &[lo, hi, kind::LOGGING, level as u8],
            &timestamp_us.to_le_bytes(),
        ])?;
        for p in parts {
            self.put(&[p.as_bytes()])?;
        }
        Ok(MESSAGE_HEADER_LEN + body)
    }

    /// A synchronisation message (a reader recovers from corruption at the next one).
    ///
    /// # Errors
    /// [`Error::Full`].
    pub fn sync(&mut self) -> Result<usize, Error> {
        self.message(kind::SYNC, &[&SYNC_MAGIC])
    }

    /// A dropout: messages of `duration_ms` were lost here.
    ///
    /// # Errors
    /// [`Error::Full`].
    pub fn dropout(&mut self, duration_ms: u16) -> Result<usize, Error> {
        self.message(kind::DROPOUT, &[&duration_ms.to_le_bytes()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_digits() {
        for (n, text) in [(0, "0"), (7, "7"), (1234, "1234"), (65535, "65535")] {
            let mut d = [0u8; 5];
            let k = decimal(n, &mut d);
            assert_eq!(&d[..k], text.as_bytes());
        }
    }

    #[test]
    fn messages_have_their_published_bytes() {
        let mut buf = [0u8; 256];
        let mut w = Writer::new(&mut buf);
        assert_eq!(w.header(0x0102), Ok(16));
        assert_eq!(w.flag_bits(), Ok(43));
        assert_eq!(w.info_str("sys_name", "TauLink"), Ok(3 + 1 + 16 + 7));
        assert_eq!(w.param_i32("a", -1), Ok(3 + 1 + 9 + 4));
        assert_eq!(w.dropout(300), Ok(5));
        let b = w.written();
        assert_eq!(b[..8], [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01]);
        assert_eq!(b[8..16], 0x0102u64.to_le_bytes());
        assert_eq!(b[16..19], [40, 0, b'B']);
        assert_eq!(b[59..63], [24, 0, b'I', 16]);
        assert_eq!(&b[63..86], b"char[7] sys_nameTauLink");
        assert_eq!(b[86..90], [14, 0, b'P', 9]);
        assert_eq!(&b[90..99], b"int32_t a");
        assert_eq!(b[99..103], [0xFF; 4]);
        assert_eq!(b[103..], [2, 0, b'O', 44, 1]);
    }

    #[test]
    fn a_string_in_parts_is_one_message() {
        let mut a = [0u8; 64];
        let mut b = [0u8; 64];
        let mut wa = Writer::new(&mut a);
        let mut wb = Writer::new(&mut b);
        assert_eq!(wa.logging(Level::Notice, 7, "mode attitude"), Ok(25));
        assert_eq!(
            wb.logging_parts(Level::Notice, 7, &["mode ", "attitude"]),
            Ok(25)
        );
        assert_eq!(wa.written(), wb.written());
    }

    #[test]
    fn a_message_that_does_not_fit_is_not_written_at_all() {
        let mut buf = [0u8; 20];
        let mut w = Writer::new(&mut buf);
        w.header(0).unwrap();
        assert_eq!(w.sync(), Err(Error::Full));
        assert_eq!(w.len(), 16);
        assert_eq!(w.dropout(1), Err(Error::Full));
        assert_eq!(w.len(), 16);
        let mut buf = [0u8; 21];
        let mut w = Writer::new(&mut buf);
        w.header(0).unwrap();
        assert_eq!(w.dropout(1), Ok(5));
        assert_eq!(w.remaining(), 0);
    }
}
