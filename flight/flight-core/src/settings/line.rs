//! Console line assembly: bytes in, whole lines out. A line longer than the buffer is
//! refused as a whole ([`LineError::TooLong`]) instead of being cut — a cut line can still
//! parse and mean something else (101 characters of `set failsafe.descent_mps 0.2…` cut
//! after the `2` stored 2). The firmware's USB console and the simulator both feed bytes
//! through this, so what the simulator tests is what the board runs.

/// Why no line came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineError {
    /// More bytes than the buffer holds before the line ended; the whole line is dropped.
    TooLong,
    /// The line is not UTF-8 text.
    NotText,
}

impl core::fmt::Display for LineError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            LineError::TooLong => "line too long, ignored",
            LineError::NotText => "line is not text, ignored",
        })
    }
}

impl core::error::Error for LineError {}

/// Collects bytes into lines of at most `N` bytes; `\r`, `\n` and `\r\n` end a line.
#[derive(Debug, Clone, Default)]
pub struct LineAssembler<const N: usize> {
    buf: heapless::Vec<u8, N>,
    overflow: bool,
    after_cr: bool,
}

impl<const N: usize> LineAssembler<N> {
    /// Empty.
    pub const fn new() -> Self {
        Self {
            buf: heapless::Vec::new(),
            overflow: false,
            after_cr: false,
        }
    }

    /// Feeds one byte; returns a finished line (without its ending) or why it was dropped.
    pub fn push(&mut self, byte: u8) -> Option<Result<heapless::String<N>, LineError>> {
        let after_cr = core::mem::replace(&mut self.after_cr, byte == b'\r');
        match byte {
            // The `\n` of a `\r\n` pair: the line already ended.
            b'\n' if after_cr => None,
            b'\r' | b'\n' => {
                let overflow = core::mem::replace(&mut self.overflow, false);
                let bytes = core::mem::take(&mut self.buf);
                if overflow {
                    return Some(Err(LineError::TooLong));
                }
                Some(heapless::String::from_utf8(bytes).map_err(|_| LineError::NotText))
            }
            _ => {
                if !self.overflow && self.buf.push(byte).is_err() {
                    self.overflow = true;
                    self.buf.clear();
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed<const N: usize>(
        a: &mut LineAssembler<N>,
        bytes: &[u8],
    ) -> Vec<Result<String, LineError>> {
        bytes
            .iter()
            .filter_map(|&b| a.push(b))
            .map(|r| r.map(|s| s.as_str().to_string()))
            .collect()
    }

    #[test]
    fn lines_end_on_cr_lf_or_both() {
        let mut a = LineAssembler::<16>::new();
        assert_eq!(
            feed(&mut a, b"get a\r\nlist\nhelp\r\rx"),
            [
                Ok("get a".to_string()),
                Ok("list".to_string()),
                Ok("help".to_string()),
                Ok(String::new())
            ]
        );
        assert_eq!(feed(&mut a, b"\n"), [Ok("x".to_string())]);
    }

    #[test]
    fn an_overlong_line_is_refused_whole_not_cut() {
        // 101 characters meaning 0.2 with a 100-byte buffer: the old console kept the first
        // 96 and stored 2.
        let mut line = String::from("set failsafe.descent_mps ");
        while line.len() < 99 {
            line.push(' ');
        }
        line.push_str("0.2");
        assert_eq!(line.len(), 102);
        let mut a = LineAssembler::<100>::new();
        let mut bytes = line.into_bytes();
        bytes.extend_from_slice(b"\r\nstatus\r\n");
        assert_eq!(
            feed(&mut a, &bytes),
            [Err(LineError::TooLong), Ok("status".to_string())]
        );
        // Exactly N bytes fit.
        let full = [b'a'; 100];
        let mut a = LineAssembler::<100>::new();
        let mut bytes = full.to_vec();
        bytes.push(b'\n');
        assert_eq!(feed(&mut a, &bytes), [Ok("a".repeat(100))]);
    }

    #[test]
    fn non_text_is_refused() {
        let mut a = LineAssembler::<8>::new();
        assert_eq!(feed(&mut a, b"\xff\xfe\n"), [Err(LineError::NotText)]);
    }
}
