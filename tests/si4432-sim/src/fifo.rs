//! The 64-byte TX and RX FIFOs and their threshold crossings (datasheet §6.1, 0x7C–0x7E).
//!
//! The thresholds are edge events: "almost full" latches when a push makes the count reach
//! the threshold from below, "almost empty" when a pop makes it fall to the threshold from
//! above. The chip turns these into interrupt status bits.

use std::collections::VecDeque;

/// Capacity of each FIFO in bytes.
pub const FIFO_CAPACITY: usize = 64;

/// What a push or pop did besides moving a byte.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FifoEvents {
    /// The byte did not fit (push) or there was none (pop).
    pub error: bool,
    /// The count rose to the almost-full threshold.
    pub almost_full: bool,
    /// The count fell to the almost-empty threshold.
    pub almost_empty: bool,
}

/// One 64-byte hardware FIFO.
#[derive(Clone, Debug, Default)]
pub struct Fifo {
    bytes: VecDeque<u8>,
}

impl Fifo {
    /// An empty FIFO.
    pub fn new() -> Self {
        Self {
            bytes: VecDeque::with_capacity(FIFO_CAPACITY),
        }
    }

    /// Bytes held.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// True when no byte is held.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Drop everything (0x08 ffclrrx / ffclrtx).
    pub fn clear(&mut self) {
        self.bytes.clear();
    }

    /// Append a byte; reports overflow and an almost-full crossing at `full_threshold`.
    pub fn push(&mut self, byte: u8, full_threshold: u8) -> FifoEvents {
        if self.bytes.len() >= FIFO_CAPACITY {
            return FifoEvents {
                error: true,
                ..FifoEvents::default()
            };
        }
        self.bytes.push_back(byte);
        FifoEvents {
            almost_full: self.bytes.len() == usize::from(full_threshold),
            ..FifoEvents::default()
        }
    }

    /// Take the oldest byte; reports underflow and an almost-empty crossing at `empty_threshold`.
    pub fn pop(&mut self, empty_threshold: u8) -> (Option<u8>, FifoEvents) {
        match self.bytes.pop_front() {
            None => (
                None,
                FifoEvents {
                    error: true,
                    ..FifoEvents::default()
                },
            ),
            Some(byte) => {
                let events = FifoEvents {
                    almost_empty: self.bytes.len() == usize::from(empty_threshold),
                    ..FifoEvents::default()
                };
                (Some(byte), events)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn almost_full_fires_once_when_the_count_reaches_the_threshold() {
        let mut fifo = Fifo::new();
        let fired: Vec<usize> = (0..40)
            .filter(|&i| fifo.push(i as u8, 32).almost_full)
            .map(|i| i + 1)
            .collect();
        assert_eq!(fired, vec![32]);
        assert_eq!(fifo.len(), 40);
    }

    #[test]
    fn overflow_after_64_and_underflow_when_empty() {
        let mut fifo = Fifo::new();
        for i in 0..64 {
            assert!(!fifo.push(i, 62).error);
        }
        assert!(fifo.push(0xAA, 62).error);
        assert_eq!(fifo.len(), 64);
        let mut popped = Vec::new();
        let mut empty_at = Vec::new();
        while let (Some(b), ev) = fifo.pop(4) {
            popped.push(b);
            if ev.almost_empty {
                empty_at.push(fifo.len());
            }
        }
        assert_eq!(popped, (0..64).collect::<Vec<u8>>());
        assert_eq!(empty_at, vec![4]);
        assert!(fifo.pop(4).1.error);
    }
}
