//! The reliable telemetry byte stream: Go-Back-N over byte offsets modulo 256, with a
//! cumulative ack in every frame. Bytes arrive exactly once and in order; anything lost is
//! sent again until acknowledged (ExpressLRS' "stubborn" sender, generalised to a window).
//!
//! Why rewinding to the ack is exact here: the link is half duplex and slot-ordered, so an
//! ack always reflects every frame its sender could have received before sending it. When
//! an ack arrives, every byte past it was either lost or dropped as out of order.

use heapless::Deque;

/// Most stream bytes that may be unacknowledged at once: half the 8-bit offset space, so an
/// offset is never ambiguous between "old" and "new".
pub const MAX_IN_FLIGHT: usize = 127;
/// Consecutive acks outside the sent window after which the sender adopts the peer's offset:
/// the peer rebooted (or this end did), so the two offset counters no longer agree.
pub const STALE_ACKS_TO_RESYNC: u8 = 8;

/// Sending half: buffers bytes until the peer acknowledges them.
#[derive(Debug)]
pub struct StreamSender<const N: usize> {
    /// Unacknowledged bytes plus bytes not yet sent; front = offset `base`.
    buffer: Deque<u8, N>,
    /// Offset of `buffer`'s front.
    base: u8,
    /// Offset of the next byte to send (`base..=base + in_flight`).
    next: u8,
    /// Bytes ever acknowledged (statistics).
    acked_total: u64,
    /// Bytes ever (re)sent (statistics).
    sent_total: u64,
    /// Consecutive acks outside `base..=next`.
    stale_acks: u8,
}

impl<const N: usize> Default for StreamSender<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> StreamSender<N> {
    /// An empty sender at offset 0.
    pub const fn new() -> Self {
        Self {
            buffer: Deque::new(),
            base: 0,
            next: 0,
            acked_total: 0,
            sent_total: 0,
            stale_acks: 0,
        }
    }

    /// Queues as many of `bytes` as fit; returns how many were taken.
    pub fn write(&mut self, bytes: &[u8]) -> usize {
        let mut taken = 0;
        for &b in bytes {
            if self.buffer.push_back(b).is_err() {
                break;
            }
            taken += 1;
        }
        taken
    }

    /// Free buffer space.
    pub fn free(&self) -> usize {
        N - self.buffer.len()
    }

    /// Bytes queued and not yet acknowledged.
    pub fn pending(&self) -> usize {
        self.buffer.len()
    }

    fn in_flight(&self) -> usize {
        usize::from(self.next.wrapping_sub(self.base))
    }

    /// How many bytes a [`StreamSender::fill`] of `room` bytes would send now: those queued
    /// past the ones in flight, within the window and `room`.
    pub fn ready(&self, room: usize) -> usize {
        let in_flight = self.in_flight();
        let unsent = self.buffer.len().saturating_sub(in_flight);
        MAX_IN_FLIGHT
            .saturating_sub(in_flight)
            .min(room)
            .min(unsent)
    }

    /// Fills `out` with the next bytes to send; returns (offset of the first, count).
    pub fn fill(&mut self, out: &mut [u8]) -> (u8, usize) {
        let in_flight = self.in_flight();
        let count = self.ready(out.len());
        for (dst, src) in out
            .iter_mut()
            .zip(self.buffer.iter().skip(in_flight).take(count))
        {
            *dst = *src;
        }
        let seq = self.next;
        self.next = self.next.wrapping_add(count as u8);
        self.sent_total += count as u64;
        (seq, count)
    }

    /// Processes the peer's cumulative ack. An ack outside `base..=next` is stale and
    /// ignored — unless [`STALE_ACKS_TO_RESYNC`] come in a row: then the peer's counter is
    /// adopted and the unacknowledged bytes are sent again from it (the peer restarted, and
    /// lost whatever it had not handed on). Otherwise the acknowledged bytes are released
    /// and sending restarts at the ack (Go-Back-N).
    pub fn on_ack(&mut self, ack: u8) {
        let acked = usize::from(ack.wrapping_sub(self.base));
        if acked > self.in_flight() {
            self.stale_acks = self.stale_acks.saturating_add(1);
            if self.stale_acks >= STALE_ACKS_TO_RESYNC {
                self.stale_acks = 0;
                self.base = ack;
                self.next = ack;
            }
            return;
        }
        self.stale_acks = 0;
        for _ in 0..acked {
            self.buffer.pop_front();
        }
        self.acked_total += acked as u64;
        self.base = ack;
        self.next = ack;
    }

    /// Bytes acknowledged so far.
    pub fn acked_total(&self) -> u64 {
        self.acked_total
    }

    /// Bytes sent so far, retransmissions included.
    pub fn sent_total(&self) -> u64 {
        self.sent_total
    }
}

/// Receiving half: accepts the next expected bytes into a bounded buffer the application
/// drains; never accepts more than fits, so nothing acknowledged is ever dropped.
#[derive(Debug)]
pub struct StreamReceiver<const N: usize> {
    buffer: Deque<u8, N>,
    expected: u8,
    received_total: u64,
}

impl<const N: usize> Default for StreamReceiver<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> StreamReceiver<N> {
    /// An empty receiver expecting offset 0.
    pub const fn new() -> Self {
        Self {
            buffer: Deque::new(),
            expected: 0,
            received_total: 0,
        }
    }

    /// Handles the data of one frame starting at offset `seq`; returns how many new bytes
    /// were accepted. Overlaps with already received bytes are skipped; a gap (an earlier
    /// frame was lost) drops the whole chunk, which the sender will repeat.
    pub fn on_data(&mut self, seq: u8, data: &[u8]) -> usize {
        let already = usize::from(self.expected.wrapping_sub(seq));
        if already > MAX_IN_FLIGHT || already >= data.len() {
            return 0;
        }
        let mut accepted = 0;
        for &b in data.iter().skip(already) {
            if self.buffer.push_back(b).is_err() {
                break;
            }
            accepted += 1;
        }
        self.expected = self.expected.wrapping_add(accepted as u8);
        self.received_total += accepted as u64;
        accepted
    }

    /// The cumulative ack to send: the next offset expected.
    pub fn ack(&self) -> u8 {
        self.expected
    }

    /// Moves received bytes into `out`; returns the count.
    pub fn read(&mut self, out: &mut [u8]) -> usize {
        let mut n = 0;
        for dst in out.iter_mut() {
            match self.buffer.pop_front() {
                Some(b) => *dst = b,
                None => break,
            }
            n += 1;
        }
        n
    }

    /// Bytes waiting to be read.
    pub fn available(&self) -> usize {
        self.buffer.len()
    }

    /// Bytes accepted so far.
    pub fn received_total(&self) -> u64 {
        self.received_total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Loops a sender and receiver through a lossy half-duplex exchange: `burst` data frames
    /// of `chunk` bytes, then one ack, with a deterministic loss pattern.
    fn transfer(
        total: usize,
        chunk: usize,
        burst: usize,
        lose: impl Fn(usize) -> bool,
    ) -> (Vec<u8>, usize) {
        let source: Vec<u8> = (0..total).map(|i| (i * 7 + i / 256) as u8).collect();
        let mut tx = StreamSender::<512>::new();
        let mut rx = StreamReceiver::<256>::new();
        let mut written = 0;
        let mut got = Vec::new();
        let mut frames = 0usize;
        while got.len() < total {
            written += tx.write(&source[written..]);
            for _ in 0..burst {
                let mut buf = vec![0u8; chunk];
                let (seq, n) = tx.fill(&mut buf);
                frames += 1;
                if !lose(frames) {
                    rx.on_data(seq, &buf[..n]);
                }
            }
            frames += 1;
            if !lose(frames) {
                tx.on_ack(rx.ack());
            }
            let mut out = [0u8; 100];
            let n = rx.read(&mut out);
            got.extend_from_slice(&out[..n]);
            assert!(frames < 1_000_000, "stuck");
        }
        assert_eq!(got, source);
        (got, frames)
    }

    #[test]
    fn lossless_transfer_uses_every_frame() {
        let (_, frames) = transfer(10_000, 20, 3, |_| false);
        // 10 000 bytes / 60 per round; each round is 4 frames.
        assert_eq!(frames, 10_000usize.div_ceil(60) * 4);
    }

    #[test]
    fn survives_heavy_periodic_and_pseudo_random_loss() {
        transfer(5_000, 9, 7, |f| f % 3 == 0);
        transfer(5_000, 33, 1, |f| ((f * 2_654_435_761usize) >> 7) % 10 < 4);
        transfer(20_000, 1, 20, |f| f % 5 == 1);
    }

    #[test]
    fn receiver_skips_overlap_and_refuses_gaps() {
        let mut rx = StreamReceiver::<16>::new();
        assert_eq!(rx.on_data(0, b"abc"), 3);
        assert_eq!(rx.on_data(1, b"bcde"), 2);
        assert_eq!(rx.on_data(9, b"zz"), 0);
        assert_eq!(rx.on_data(0, b"ab"), 0);
        assert_eq!(rx.ack(), 5);
        let mut out = [0u8; 8];
        assert_eq!(rx.read(&mut out), 5);
        assert_eq!(&out[..5], b"abcde");
    }

    #[test]
    fn receiver_never_overfills() {
        let mut rx = StreamReceiver::<4>::new();
        assert_eq!(rx.on_data(0, b"abcdef"), 4);
        assert_eq!(rx.ack(), 4);
        let mut out = [0u8; 2];
        rx.read(&mut out);
        assert_eq!(rx.on_data(0, b"abcdef"), 2);
        assert_eq!(rx.ack(), 6);
    }

    #[test]
    fn a_restarted_receiver_is_resynchronised() {
        let mut tx = StreamSender::<64>::new();
        let mut rx = StreamReceiver::<64>::new();
        tx.write(b"0123456789");
        let mut buf = [0u8; 4];
        let (seq, n) = tx.fill(&mut buf);
        rx.on_data(seq, &buf[..n]);
        tx.on_ack(rx.ack());
        let (seq, n) = tx.fill(&mut buf); // "4567" sent, never delivered: the peer reboots
        assert_eq!((seq, n), (4, 4));
        let mut rx = StreamReceiver::<64>::new();
        let mut got = Vec::new();
        for _ in 0..20 {
            let (seq, n) = tx.fill(&mut buf);
            rx.on_data(seq, &buf[..n]);
            tx.on_ack(rx.ack());
            let mut out = [0u8; 16];
            let k = rx.read(&mut out);
            got.extend_from_slice(&out[..k]);
        }
        // Everything not acknowledged before the reboot arrives, in order.
        assert_eq!(got, b"456789");
    }

    #[test]
    fn ready_is_what_the_next_fill_sends() {
        let mut tx = StreamSender::<1024>::new();
        assert_eq!(tx.ready(10), 0);
        tx.write(&[7u8; 300]);
        let mut buf = [0u8; 50];
        // Limited by the room, then by the window of MAX_IN_FLIGHT, then by what is queued.
        for (room, want) in [(50, 50), (50, 50), (50, 27), (50, 0)] {
            assert_eq!(tx.ready(room), want);
            assert_eq!(tx.fill(&mut buf[..room]).1, want);
        }
        tx.on_ack(127);
        assert_eq!(tx.ready(200), MAX_IN_FLIGHT);
        assert_eq!(tx.ready(0), 0);
    }

    #[test]
    fn sender_limits_in_flight_and_ignores_stale_acks() {
        let mut tx = StreamSender::<1024>::new();
        assert_eq!(tx.write(&[1u8; 300]), 300);
        let mut buf = [0u8; 200];
        assert_eq!(tx.fill(&mut buf), (0, MAX_IN_FLIGHT));
        assert_eq!(tx.fill(&mut buf), (127, 0));
        tx.on_ack(200); // beyond what was sent: ignored
        assert_eq!(tx.pending(), 300);
        tx.on_ack(100);
        assert_eq!(tx.pending(), 200);
        assert_eq!(tx.acked_total(), 100);
        assert_eq!(tx.fill(&mut buf).0, 100);
    }
}
