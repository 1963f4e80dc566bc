//! A bounded queue of whole records that makes room by dropping the oldest records, never
//! part of one, and counts what it dropped. Pushing never waits, so a slow phone (or a full
//! uplink) can never stall the radio side.

use heapless::Deque;

/// What [`RecordQueue::push`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pushed {
    /// Stored; `dropped` older records were removed to make room.
    Stored {
        /// Records dropped for this one.
        dropped: u16,
    },
    /// Longer than the queue's record limit: dropped (and counted).
    TooLarge,
}

/// The caller's buffer cannot hold the next record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BufferTooSmall {
    /// Bytes the next record needs.
    pub needed: usize,
}

/// Drop counters of a queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DropStats {
    /// Records dropped (oldest-first eviction and oversize records).
    pub records: u32,
    /// Bytes in those records.
    pub bytes: u32,
}

/// Up to `RECORDS` records in `BYTES` bytes, each at most `max_record_len` long.
///
/// ```
/// use module_core::hm10::{Pushed, RecordQueue};
///
/// let mut queue = RecordQueue::<8, 4>::new(8);
/// queue.push(&[1, 2, 3]);
/// queue.push(&[4, 5, 6]);
/// // 6 of 8 bytes used: the oldest record goes, whole.
/// assert_eq!(queue.push(&[7, 8, 9]), Pushed::Stored { dropped: 1 });
/// let mut out = [0; 8];
/// assert_eq!(queue.pop_into(&mut out), Ok(Some(3)));
/// assert_eq!(&out[..3], &[4, 5, 6]);
/// ```
#[derive(Debug)]
pub struct RecordQueue<const BYTES: usize, const RECORDS: usize> {
    bytes: Deque<u8, BYTES>,
    lengths: Deque<u16, RECORDS>,
    max_record_len: usize,
    dropped: DropStats,
}

impl<const BYTES: usize, const RECORDS: usize> RecordQueue<BYTES, RECORDS> {
    /// An empty queue; records longer than `max_record_len` (or `BYTES`) are refused.
    pub const fn new(max_record_len: usize) -> Self {
        Self {
            bytes: Deque::new(),
            lengths: Deque::new(),
            max_record_len,
            dropped: DropStats {
                records: 0,
                bytes: 0,
            },
        }
    }

    /// Longest record accepted; a `pop_into` buffer this long always suffices.
    pub fn max_record_len(&self) -> usize {
        self.max_record_len.min(BYTES).min(usize::from(u16::MAX))
    }

    /// Records waiting.
    pub fn len(&self) -> usize {
        self.lengths.len()
    }

    /// No record waiting.
    pub fn is_empty(&self) -> bool {
        self.lengths.is_empty()
    }

    /// What was dropped so far.
    pub fn dropped(&self) -> DropStats {
        self.dropped
    }

    /// Stores a record, dropping the oldest whole records while it does not fit.
    pub fn push(&mut self, record: &[u8]) -> Pushed {
        let Some(length) = u16::try_from(record.len())
            .ok()
            .filter(|_| record.len() <= self.max_record_len())
        else {
            self.count_drop(record.len());
            return Pushed::TooLarge;
        };
        let mut dropped = 0u16;
        while BYTES - self.bytes.len() < record.len() || self.lengths.is_full() {
            if !self.drop_oldest() {
                // Cannot happen (the record fits an empty queue); refuse rather than loop.
                self.count_drop(record.len());
                return Pushed::TooLarge;
            }
            dropped = dropped.saturating_add(1);
        }
        for &byte in record {
            // Room was made above, so these pushes succeed.
            let _ = self.bytes.push_back(byte);
        }
        let _ = self.lengths.push_back(length);
        Pushed::Stored { dropped }
    }

    /// Moves the oldest record into `out`; `Ok(None)` when empty. On `Err` the record stays.
    pub fn pop_into(&mut self, out: &mut [u8]) -> Result<Option<usize>, BufferTooSmall> {
        let Some(&length) = self.lengths.front() else {
            return Ok(None);
        };
        let length = usize::from(length);
        let Some(target) = out.get_mut(..length) else {
            return Err(BufferTooSmall { needed: length });
        };
        for slot in target.iter_mut() {
            *slot = self.bytes.pop_front().unwrap_or(0);
        }
        self.lengths.pop_front();
        Ok(Some(length))
    }

    /// Drops everything waiting (counted).
    pub fn clear(&mut self) {
        while self.drop_oldest() {}
    }

    fn drop_oldest(&mut self) -> bool {
        let Some(length) = self.lengths.pop_front() else {
            return false;
        };
        for _ in 0..length {
            self.bytes.pop_front();
        }
        self.count_drop(usize::from(length));
        true
    }

    fn count_drop(&mut self, length: usize) {
        self.dropped.records = self.dropped.records.saturating_add(1);
        self.dropped.bytes = self
            .dropped
            .bytes
            .saturating_add(u32::try_from(length).unwrap_or(u32::MAX));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_order_and_whole_record_eviction() {
        let mut queue = RecordQueue::<10, 4>::new(8);
        assert_eq!(queue.push(&[1, 2, 3]), Pushed::Stored { dropped: 0 });
        assert_eq!(queue.push(&[4, 5, 6]), Pushed::Stored { dropped: 0 });
        assert_eq!(queue.push(&[7, 8, 9]), Pushed::Stored { dropped: 0 });
        // 9 of 10 bytes used: a 2-byte record evicts the whole oldest record.
        assert_eq!(queue.push(&[10, 11]), Pushed::Stored { dropped: 1 });
        assert_eq!(
            queue.dropped(),
            DropStats {
                records: 1,
                bytes: 3
            }
        );
        let mut out = [0u8; 8];
        assert_eq!(queue.pop_into(&mut out), Ok(Some(3)));
        assert_eq!(&out[..3], &[4, 5, 6]);
        assert_eq!(queue.pop_into(&mut out), Ok(Some(3)));
        assert_eq!(queue.pop_into(&mut out), Ok(Some(2)));
        assert_eq!(&out[..2], &[10, 11]);
        assert_eq!(queue.pop_into(&mut out), Ok(None));
    }

    #[test]
    fn record_count_limit_and_oversize() {
        let mut queue = RecordQueue::<64, 2>::new(16);
        queue.push(&[1]);
        queue.push(&[2]);
        assert_eq!(queue.push(&[3]), Pushed::Stored { dropped: 1 });
        assert_eq!(queue.push(&[0; 17]), Pushed::TooLarge);
        assert_eq!(
            queue.dropped(),
            DropStats {
                records: 2,
                bytes: 18
            }
        );
        assert_eq!(queue.len(), 2);
        let mut tiny = [0u8; 0];
        assert_eq!(queue.pop_into(&mut tiny), Err(BufferTooSmall { needed: 1 }));
        assert_eq!(queue.len(), 2, "a failed pop keeps the record");
        queue.clear();
        assert!(queue.is_empty());
        assert_eq!(queue.dropped().records, 4);
    }

    proptest::proptest! {
        /// Whatever comes out is a suffix of what went in, in order and whole; every record
        /// is either delivered or counted as dropped.
        #[test]
        fn delivered_plus_dropped_is_everything(
            ops in proptest::collection::vec((0usize..40, proptest::prelude::any::<bool>()), 0..300),
        ) {
            let mut queue = RecordQueue::<96, 8>::new(32);
            let mut pushed = Vec::new();
            let mut popped = Vec::new();
            let mut out = [0u8; 32];
            for (i, (len, pop)) in ops.into_iter().enumerate() {
                if pop {
                    if let Some(n) = queue.pop_into(&mut out).unwrap() {
                        popped.push(out[..n].to_vec());
                    }
                } else {
                    let record: Vec<u8> = (0..len).map(|k| (i + k) as u8).collect();
                    queue.push(&record);
                    pushed.push(record);
                }
            }
            while let Some(n) = queue.pop_into(&mut out).unwrap() {
                popped.push(out[..n].to_vec());
            }
            // Delivered records appear in push order.
            let mut cursor = pushed.iter();
            for record in &popped {
                proptest::prop_assert!(cursor.any(|r| r == record));
            }
            let dropped = queue.dropped();
            proptest::prop_assert_eq!(popped.len() + dropped.records as usize, pushed.len());
            let total: usize = pushed.iter().map(Vec::len).sum();
            let delivered: usize = popped.iter().map(Vec::len).sum();
            proptest::prop_assert_eq!(delivered + dropped.bytes as usize, total);
        }
    }
}
