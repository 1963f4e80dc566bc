//! The receiver's side of the telemetry handshake (RX.h): the 9-byte frame it last sent, its
//! sequence bits (bit 6 new-frame toggle, bit 7 uplink-serial acknowledge) and the queue of
//! RX UART bytes waiting to go down.

use heapless::{Deque, Vec};

use super::telemetry::{self, Frame, LinkInfo};
use super::uplink;

/// Capacity of the RX-UART → downlink queue (OpenLRSng uses 32 bytes).
pub const SERIAL_QUEUE_LEN: usize = 32;

/// The RX's downlink state.
#[derive(Debug, Clone)]
pub struct DownlinkSender {
    frame: Frame,
    serial_out: Deque<u8, SERIAL_QUEUE_LEN>,
}

impl Default for DownlinkSender {
    fn default() -> Self {
        Self::new()
    }
}

impl DownlinkSender {
    /// Nothing sent yet, nothing queued.
    pub const fn new() -> Self {
        Self {
            frame: [0; telemetry::DOWNLINK_FRAME_LEN],
            serial_out: Deque::new(),
        }
    }

    /// Queues RX UART bytes; returns how many did not fit.
    pub fn queue_serial(&mut self, data: &[u8]) -> usize {
        data.iter()
            .filter(|&&b| self.serial_out.push_back(b).is_err())
            .count()
    }

    /// Bytes [`DownlinkSender::queue_serial`] still takes whole (so a caller can keep a
    /// framed message in one piece).
    pub fn serial_free(&self) -> usize {
        self.serial_out.capacity() - self.serial_out.len()
    }

    /// An uplink serial packet arrived: `true` if it is new data (bit 7 differs from our
    /// acknowledge bit), which then flips so the next frame acknowledges it.
    pub fn accept_uplink_serial(&mut self, uplink_header: u8) -> bool {
        let [header, ..] = &mut self.frame;
        if (uplink_header ^ *header) & uplink::SEQ_UPLINK_SERIAL != 0 {
            *header ^= telemetry::SEQ_UPLINK_ACK;
            true
        } else {
            false
        }
    }

    /// The frame to answer an uplink packet with. If the TX has not acknowledged our last
    /// frame (its bit 6 differs from ours) the same frame goes again; otherwise bit 6
    /// toggles and the frame carries up to 8 queued bytes, or `info` when none are queued.
    pub fn reply(&mut self, uplink_header: u8, info: &LinkInfo) -> Frame {
        let [header, ..] = self.frame;
        if (uplink_header ^ header) & telemetry::SEQ_DOWNLINK != 0 {
            return self.frame;
        }
        let sequence_bits = (header & 0xC0) ^ telemetry::SEQ_DOWNLINK;
        let mut chunk: Vec<u8, { telemetry::MAX_SERIAL_BYTES }> = Vec::new();
        while chunk.len() < telemetry::MAX_SERIAL_BYTES {
            match self.serial_out.pop_front() {
                Some(b) => {
                    let _ = chunk.push(b);
                }
                None => break,
            }
        }
        self.frame = telemetry::serial_frame(sequence_bits, &chunk)
            .unwrap_or_else(|| telemetry::link_info_frame(sequence_bits, info));
        self.frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resends_until_acknowledged_then_sends_queued_serial() {
        let info = LinkInfo {
            rssi: 99,
            analog0: 1,
            analog1: 2,
            afc: 3,
            link_quality: 15,
        };
        let mut d = DownlinkSender::new();
        assert_eq!(d.serial_free(), SERIAL_QUEUE_LEN);
        assert_eq!(d.queue_serial(b"xy"), 0);
        assert_eq!(d.serial_free(), SERIAL_QUEUE_LEN - 2);
        let first = d.reply(0x00, &info);
        assert_eq!(&first[..3], &[0x40 | (0x38 + 1), b'x', b'y']);
        // TX has not copied bit 6 yet: the same frame again.
        assert_eq!(d.reply(0x00, &info), first);
        // Acknowledged: a new frame, link info since the queue is empty.
        assert_eq!(d.reply(0x40, &info), [0x00, 99, 1, 2, 0, 3, 15, 0, 0]);
        assert!(d.accept_uplink_serial(0x80 | 0x38));
        assert!(!d.accept_uplink_serial(0x80 | 0x38));
        assert_eq!(d.reply(0x00, &info)[0], 0x80 | 0x40);
    }
}
