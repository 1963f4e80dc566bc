//! Reading a ULog file from untrusted bytes, as the specification's "requirements for
//! parsers" ask: unknown message types are passed on, unknown incompatible flags refuse the
//! file, a file cut inside a message ends at its last whole message, appended data (the
//! flag-bits offsets) is read in its place. Each malformed message is an error naming its
//! offset; the walk goes on at the next message.

use crate::format::{Format, Key};
use crate::{Error, FLAG_BITS_LEN, HEADER_LEN, MAGIC, MESSAGE_HEADER_LEN, SYNC_MAGIC, kind};

/// The file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// File format version (1; later ones are read too).
    pub version: u8,
    /// When logging started, µs.
    pub start_us: u64,
}

/// One message, borrowing from the file's bytes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message<'a> {
    /// Flag bits (the first message).
    FlagBits {
        /// Compatible flags.
        compat: [u8; 8],
        /// Incompatible flags (only DATA_APPENDED is known).
        incompat: [u8; 8],
        /// File offsets of appended data (0: none).
        appended: [u64; 3],
    },
    /// A format definition.
    Format(Format<'a>),
    /// Information.
    Info {
        /// Its key.
        key: Key<'a>,
        /// Its value's bytes.
        value: &'a [u8],
    },
    /// Multi information.
    InfoMultiple {
        /// Continues the previous message of the same key.
        continued: bool,
        /// Its key.
        key: Key<'a>,
        /// Its value's bytes.
        value: &'a [u8],
    },
    /// A parameter value (initial in the definitions, a change in the data).
    Parameter {
        /// Its key.
        key: Key<'a>,
        /// Its value's bytes.
        value: &'a [u8],
    },
    /// A default parameter value.
    ParameterDefault {
        /// Which defaults (bit 0 system, bit 1 configuration).
        types: u8,
        /// Its key.
        key: Key<'a>,
        /// Its value's bytes.
        value: &'a [u8],
    },
    /// A subscription.
    Subscription {
        /// Instance.
        multi_id: u8,
        /// The id logged data carries.
        msg_id: u16,
        /// The format's name.
        name: &'a str,
    },
    /// An unsubscription.
    Unsubscription {
        /// The id no longer logged.
        msg_id: u16,
    },
    /// Logged data.
    Data {
        /// Its subscription's id.
        msg_id: u16,
        /// The encoded message.
        data: &'a [u8],
    },
    /// A logged string.
    Logging {
        /// Level (`b'0'`…`b'7'`).
        level: u8,
        /// Time, µs.
        timestamp_us: u64,
        /// The text (bytes as logged).
        text: &'a [u8],
    },
    /// A tagged logged string.
    LoggingTagged {
        /// Level.
        level: u8,
        /// Source tag.
        tag: u16,
        /// Time, µs.
        timestamp_us: u64,
        /// The text.
        text: &'a [u8],
    },
    /// A synchronisation message.
    Sync,
    /// Lost messages.
    Dropout {
        /// How long, ms.
        duration_ms: u16,
    },
    /// A message type this reader does not know (to be ignored).
    Unknown {
        /// Its type byte.
        msg_type: u8,
        /// Its body.
        body: &'a [u8],
    },
}

/// Walks a log's messages.
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    header: Header,
    truncated: bool,
    refused: bool,
    /// Offsets where appended data starts, ascending (0: unused).
    appended: [u64; 3],
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    let s = b.get(at..at + 2)?;
    Some(u16::from_le_bytes([*s.first()?, *s.get(1)?]))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    let mut a = [0u8; 8];
    a.copy_from_slice(b.get(at..at + 8)?);
    Some(u64::from_le_bytes(a))
}

/// A key (`key_len` then the key) followed by its value.
fn keyed(body: &[u8]) -> Option<(Key<'_>, &[u8])> {
    let (&len, rest) = body.split_first()?;
    let key = rest.get(..usize::from(len))?;
    let value = rest.get(usize::from(len)..)?;
    let key = Key::parse(core::str::from_utf8(key).ok()?).ok()?;
    Some((key, value))
}

fn parse(msg_type: u8, body: &[u8]) -> Option<Message<'_>> {
    Some(match msg_type {
        kind::FLAG_BITS => {
            // Longer bodies are a later version's: the extra bytes are ignored.
            if body.len() < FLAG_BITS_LEN {
                return None;
            }
            let mut compat = [0u8; 8];
            let mut incompat = [0u8; 8];
            compat.copy_from_slice(body.get(..8)?);
            incompat.copy_from_slice(body.get(8..16)?);
            let appended = [u64_at(body, 16)?, u64_at(body, 24)?, u64_at(body, 32)?];
            Message::FlagBits {
                compat,
                incompat,
                appended,
            }
        }
        kind::FORMAT => Message::Format(Format::parse(core::str::from_utf8(body).ok()?).ok()?),
        kind::INFO => {
            let (key, value) = keyed(body)?;
            Message::Info { key, value }
        }
        kind::INFO_MULTIPLE => {
            let (&continued, rest) = body.split_first()?;
            let (key, value) = keyed(rest)?;
            Message::InfoMultiple {
                continued: continued != 0,
                key,
                value,
            }
        }
        kind::PARAMETER => {
            let (key, value) = keyed(body)?;
            Message::Parameter { key, value }
        }
        kind::PARAMETER_DEFAULT => {
            let (&types, rest) = body.split_first()?;
            let (key, value) = keyed(rest)?;
            Message::ParameterDefault { types, key, value }
        }
        kind::SUBSCRIPTION => {
            let name = core::str::from_utf8(body.get(3..)?).ok()?;
            if !crate::format::is_message_name(name) {
                return None;
            }
            Message::Subscription {
                multi_id: *body.first()?,
                msg_id: u16_at(body, 1)?,
                name,
            }
        }
        // The fixed-size messages are refused at any other size: a reader that took the
        // first bytes of a longer one would lose the rest without a word.
        kind::UNSUBSCRIPTION if body.len() == 2 => Message::Unsubscription {
            msg_id: u16_at(body, 0)?,
        },
        kind::DATA => Message::Data {
            msg_id: u16_at(body, 0)?,
            data: body.get(2..)?,
        },
        kind::LOGGING => Message::Logging {
            level: *body.first()?,
            timestamp_us: u64_at(body, 1)?,
            text: body.get(9..)?,
        },
        kind::LOGGING_TAGGED => Message::LoggingTagged {
            level: *body.first()?,
            tag: u16_at(body, 1)?,
            timestamp_us: u64_at(body, 3)?,
            text: body.get(11..)?,
        },
        kind::SYNC => {
            if body != SYNC_MAGIC {
                return None;
            }
            Message::Sync
        }
        kind::DROPOUT if body.len() == 2 => Message::Dropout {
            duration_ms: u16_at(body, 0)?,
        },
        kind::UNSUBSCRIPTION | kind::DROPOUT => return None,
        _ => Message::Unknown { msg_type, body },
    })
}

impl<'a> Reader<'a> {
    /// A reader of `bytes`, a whole file or its beginning.
    ///
    /// # Errors
    /// [`Error::NotULog`] if the header is short or its magic wrong.
    pub fn new(bytes: &'a [u8]) -> Result<Self, Error> {
        let head = bytes.get(..HEADER_LEN).ok_or(Error::NotULog)?;
        if head.get(..MAGIC.len()) != Some(&MAGIC[..]) {
            return Err(Error::NotULog);
        }
        let header = Header {
            version: *head.get(7).ok_or(Error::NotULog)?,
            start_us: u64_at(head, 8).ok_or(Error::NotULog)?,
        };
        Ok(Self {
            bytes,
            at: HEADER_LEN,
            header,
            truncated: false,
            refused: false,
            appended: [0; 3],
        })
    }

    /// The file header.
    pub fn header(&self) -> Header {
        self.header
    }

    /// Offset of the next message.
    pub fn offset(&self) -> usize {
        self.at
    }

    /// The file ended inside a message (the cut message was discarded).
    pub fn truncated(&self) -> bool {
        self.truncated
    }

    /// The next appended-data offset after `from`, if a message would run over it.
    fn appended_within(&self, from: usize, end: usize) -> Option<usize> {
        self.appended
            .iter()
            .filter_map(|&o| usize::try_from(o).ok())
            .find(|&o| o > from && o < end)
    }

    fn step(&mut self) -> Option<Result<(usize, Message<'a>), Error>> {
        let offset = self.at;
        let head = self.bytes.get(offset..offset + MESSAGE_HEADER_LEN);
        let Some(&[lo, hi, msg_type]) = head else {
            self.truncated = self.bytes.len() > offset;
            return None;
        };
        let size = usize::from(u16::from_le_bytes([lo, hi]));
        let end = offset + MESSAGE_HEADER_LEN + size;
        // Appended data starts inside this message: the message was cut there.
        if let Some(o) = self.appended_within(offset, end) {
            self.at = o;
            return self.step();
        }
        let Some(body) = self.bytes.get(offset + MESSAGE_HEADER_LEN..end) else {
            self.truncated = true;
            return None;
        };
        self.at = end;
        let Some(message) = parse(msg_type, body) else {
            return Some(Err(Error::Malformed { offset }));
        };
        if let Message::FlagBits {
            incompat, appended, ..
        } = message
        {
            let known_only = incompat.iter().enumerate().all(|(i, &b)| match i {
                0 => b & !1 == 0,
                _ => b == 0,
            });
            if !known_only {
                self.refused = true;
                return Some(Err(Error::IncompatibleFlags));
            }
            self.appended = appended;
        }
        Some(Ok((offset, message)))
    }
}

impl<'a> Iterator for Reader<'a> {
    /// Each message with its file offset, or why the message there is unreadable.
    type Item = Result<(usize, Message<'a>), Error>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.refused {
            return None;
        }
        self.step()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Level, Writer};

    crate::record! {
        struct Sample = "sample" { value: f32 }
    }

    fn log(buf: &mut [u8]) -> usize {
        let mut w = Writer::new(buf);
        w.header(42).unwrap();
        w.flag_bits().unwrap();
        w.format(<Sample as crate::Record>::FORMAT).unwrap();
        w.info_str("sys_name", "TauLink").unwrap();
        w.param_f32("pid/roll/kp", 0.003).unwrap();
        w.subscribe(0, 0, "sample").unwrap();
        w.data(
            0,
            &Sample {
                timestamp: 1000,
                value: 2.5,
            },
        )
        .unwrap();
        w.logging(Level::Warning, 1500, "low battery").unwrap();
        w.sync().unwrap();
        w.dropout(20).unwrap();
        w.len()
    }

    #[test]
    fn what_the_writer_writes_reads_back() {
        let mut buf = [0u8; 512];
        let n = log(&mut buf);
        let mut r = Reader::new(&buf[..n]).unwrap();
        assert_eq!(
            r.header(),
            Header {
                version: 1,
                start_us: 42
            }
        );
        let messages: Vec<Message> = r.by_ref().map(|m| m.unwrap().1).collect();
        assert!(!r.truncated());
        assert_eq!(messages.len(), 9);
        assert!(matches!(messages[0], Message::FlagBits { incompat, .. } if incompat == [0; 8]));
        assert!(matches!(messages[1], Message::Format(f) if f.name == "sample"));
        match messages[2] {
            Message::Info { key, value } => {
                assert_eq!(
                    (key.name, key.ty.array, value),
                    ("sys_name", Some(7), &b"TauLink"[..])
                );
            }
            ref m => panic!("{m:?}"),
        }
        match messages[3] {
            Message::Parameter { key, value } => {
                assert_eq!(key.name, "pid/roll/kp");
                assert_eq!(key.scalar(value), Ok(crate::Scalar::F32(0.003)));
            }
            ref m => panic!("{m:?}"),
        }
        assert_eq!(
            messages[4],
            Message::Subscription {
                multi_id: 0,
                msg_id: 0,
                name: "sample"
            }
        );
        match messages[5] {
            Message::Data { msg_id: 0, data } => assert_eq!(
                <Sample as crate::Record>::decode(data),
                Ok(Sample {
                    timestamp: 1000,
                    value: 2.5
                })
            ),
            ref m => panic!("{m:?}"),
        }
        assert_eq!(
            messages[6],
            Message::Logging {
                level: b'4',
                timestamp_us: 1500,
                text: b"low battery"
            }
        );
        assert_eq!(messages[7], Message::Sync);
        assert_eq!(messages[8], Message::Dropout { duration_ms: 20 });
    }

    #[test]
    fn a_cut_file_ends_at_its_last_whole_message() {
        let mut buf = [0u8; 512];
        let n = log(&mut buf);
        let full: Vec<(usize, Message)> = Reader::new(&buf[..n])
            .unwrap()
            .map(Result::unwrap)
            .collect();
        // Where each message ends: the next one's offset, the file's end for the last.
        let ends: Vec<usize> = full.iter().skip(1).map(|(o, _)| *o).chain([n]).collect();
        for cut in 16..=n {
            let mut r = Reader::new(&buf[..cut]).unwrap();
            let read: Vec<(usize, Message)> = r.by_ref().map(Result::unwrap).collect();
            let whole = ends.iter().filter(|&&e| e <= cut).count();
            assert_eq!(read[..], full[..whole], "cut at {cut}");
            assert_eq!(
                r.truncated(),
                !ends.contains(&cut) && cut != 16,
                "cut at {cut}"
            );
        }
    }

    #[test]
    fn unknown_incompatible_flags_refuse_the_file() {
        let mut buf = [0u8; 512];
        let n = log(&mut buf);
        buf[16 + 3 + 8] = 0b10; // incompat_flags[0] bit 1
        let mut r = Reader::new(&buf[..n]).unwrap();
        assert_eq!(r.next(), Some(Err(Error::IncompatibleFlags)));
        assert_eq!(r.next(), None);
    }

    #[test]
    fn unknown_types_pass_and_malformed_ones_are_errors() {
        let mut buf = [0u8; 64];
        buf[..16].copy_from_slice(&[
            0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 1, 0, 0, 0, 0, 0, 0, 0, 0,
        ]);
        buf[16..21].copy_from_slice(&[2, 0, b'Z', 9, 9]);
        buf[21..25].copy_from_slice(&[1, 0, b'D', 0]); // data without a whole msg_id
        buf[25..31].copy_from_slice(&[3, 0, b'A', 0, 1, 0]); // subscription without a name
        let r = Reader::new(&buf[..31]).unwrap();
        let all: Vec<_> = r.collect();
        assert_eq!(
            all,
            [
                Ok((
                    16,
                    Message::Unknown {
                        msg_type: b'Z',
                        body: &[9, 9]
                    }
                )),
                Err(Error::Malformed { offset: 21 }),
                Err(Error::Malformed { offset: 25 }),
            ]
        );
        assert_eq!(Reader::new(&buf[..15]).err(), Some(Error::NotULog));
        buf[0] = b'X';
        assert_eq!(Reader::new(&buf).err(), Some(Error::NotULog));
    }

    /// Fuzzing (ulog_reader) found a dropout of nine bytes read as its first two: the
    /// fixed-size messages are malformed at any other size, never cut short.
    #[test]
    fn fixed_size_messages_of_another_size_are_errors() {
        let mut file = vec![
            0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 1, 0, 0, 0, 0, 0, 0, 0, 0,
        ];
        file.extend_from_slice(&[
            9, 0, b'O', 0xf7, 0x28, 0x50, 0x50, 0xf7, 0x10, 0x09, 0x00, 0xf7,
        ]);
        file.extend_from_slice(&[3, 0, b'R', 1, 0, 0]); // an unsubscription of three bytes
        file.extend_from_slice(&[
            9, 0, b'S', 0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12, 0,
        ]);
        file.extend_from_slice(&[2, 0, b'O', 20, 0]); // a whole dropout still reads
        let all: Vec<_> = Reader::new(&file).unwrap().collect();
        assert_eq!(
            all,
            [
                Err(Error::Malformed { offset: 16 }),
                Err(Error::Malformed { offset: 28 }),
                Err(Error::Malformed { offset: 34 }),
                Ok((46, Message::Dropout { duration_ms: 20 })),
            ]
        );
    }

    #[test]
    fn appended_data_is_read_where_the_flag_bits_point() {
        let mut buf = [0u8; 512];
        let n = log(&mut buf);
        // Cut the last message (the dropout) in half and append a logged string after it.
        let cut = n - 2;
        let mut tail = [0u8; 64];
        let mut w = Writer::new(&mut tail);
        w.logging(Level::Info, 9, "after").unwrap();
        let t = w.len();
        let mut file = buf[..cut].to_vec();
        file.extend_from_slice(&tail[..t]);
        file[16 + 3 + 8] = 1; // DATA_APPENDED
        file[16 + 3 + 16..16 + 3 + 24].copy_from_slice(&(cut as u64).to_le_bytes());
        let last = Reader::new(&file).unwrap().last().unwrap().unwrap().1;
        assert_eq!(
            last,
            Message::Logging {
                level: b'6',
                timestamp_us: 9,
                text: b"after"
            }
        );
    }
}
