//! What both link ends do alike, written once for [`Master`](super::Master) and
//! [`Follower`](super::Follower): the report an end sends
//! about how it hears the other, and the telemetry streams' share of each frame (filling a
//! frame's room, taking a received frame's stream bytes and ack).

use crate::frame::{LinkReport, StreamHeader};
use crate::link::bind::LinkParams;
use crate::link::quality::{LqWindow, RssiFilter};
use crate::link::stream::{StreamReceiver, StreamSender};

use super::tag_extra;

/// How this end hears the other, as its frames report it: smoothed RSSI and LQ.
pub(super) fn report(rssi: &RssiFilter, lq: &LqWindow) -> LinkReport {
    LinkReport {
        rssi_dbm: rssi.report_dbm(),
        lq_percent: lq.percent(),
    }
}

/// Room for stream bytes in a frame of the link's rate mode that carries `overhead` bytes
/// besides (and a tag instead of the CRC when `keyed`).
pub(super) fn stream_room(params: &LinkParams, overhead: usize, keyed: bool) -> usize {
    params
        .rate
        .max_frame_bytes()
        .saturating_sub(overhead)
        .saturating_sub(tag_extra(keyed))
}

/// The most stream bytes one frame carries (a frame is at most one FIFO).
pub(super) const STREAM_CHUNK_BYTES: usize = 64;

/// How many stream bytes [`stream_out`] would put into a frame with `room` for them now;
/// None where it would send nothing.
pub(super) fn stream_ready<const T: usize>(send: &StreamSender<T>, room: usize) -> Option<usize> {
    (room <= STREAM_CHUNK_BYTES).then(|| send.ready(room))
}

/// The streams' share of a frame to send: up to `room` bytes from `send` copied into `data`,
/// with the header carrying their sequence number and the ack of what `receive` has taken.
/// None if `room` exceeds `data` (the caller then sends nothing rather than a cut frame).
pub(super) fn stream_out<'d, const T: usize, const R: usize>(
    send: &mut StreamSender<T>,
    receive: &StreamReceiver<R>,
    room: usize,
    data: &'d mut [u8; STREAM_CHUNK_BYTES],
) -> Option<(StreamHeader, &'d [u8])> {
    let data = data.get_mut(..room)?;
    let (seq, n) = send.fill(data);
    let stream = StreamHeader {
        seq,
        ack: receive.ack(),
    };
    let data: &'d [u8] = data;
    Some((stream, data.get(..n)?))
}

/// The streams' share of a frame taken: the other end's ack of what we sent, and its data
/// for `receive`.
pub(super) fn stream_in<const T: usize, const R: usize>(
    send: &mut StreamSender<T>,
    receive: &mut StreamReceiver<R>,
    stream: StreamHeader,
    data: &[u8],
) {
    send.on_ack(stream.ack);
    receive.on_data(stream.seq, data);
}
