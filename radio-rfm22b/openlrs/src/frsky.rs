//! What an OpenLRSng TX writes to its handset's telemetry input (`frskytx.h`): FrSky D hub
//! frames at 9600 baud and S.Port frames at 57600.
//!
//! Upstream leaves some bytes uninitialised and so sends stack garbage: the unused data bytes
//! of a hub user frame (`7E FD n 00 d0..d5 7E` when n < 6) and S.Port value bytes v1..v3.
//! We send 0x00 in those places, as the vectors (built with zeroed locals) do.

use heapless::{Deque, Vec};
use taulink_handset::stuffing;

use super::telemetry;

/// Frame delimiter of both protocols.
pub const FRAME_START: u8 = stuffing::FRAME;
/// Byte-stuffing escape: 0x7E/0x7D go out as 0x7D, x ^ 0x20 ([`stuffing::escaped`]).
pub const ESCAPE: u8 = stuffing::ESCAPE;
/// Hub link frame type (A1, A2, RSSI).
pub const HUB_LINK: u8 = 0xFE;
/// Hub user-data frame type.
pub const HUB_USER_DATA: u8 = 0xFD;
/// Hub user data bytes per frame.
pub const HUB_USER_BYTES: usize = 6;
/// Every 6th hub frame (one per 180 ms at the 30 ms cadence) is a link frame.
pub const HUB_LINK_EVERY: u8 = 6;
/// The S.Port physical ID OpenLRSng answers as.
pub const SMARTPORT_PHYSICAL_ID: u8 = 0x98;
/// S.Port data frame header.
pub const SMARTPORT_DATA_FRAME: u8 = 0x10;
/// S.Port slots per cycle (one call per 12 ms); slots 4..35 send only the idle byte.
pub const SMARTPORT_SLOTS: u8 = 36;
/// Sensor ID carrying the TX profile number + 1 (no dedicated LQ sensor exists).
pub const SENSOR_SWR: u16 = 0xF105;
/// Sensor ID carrying min(RX, TX) composite RSSI scaled to 0..99.
pub const SENSOR_RSSI: u16 = 0xF101;
/// Sensor ID carrying the RX's analog 0 byte (A1).
pub const SENSOR_BATT: u16 = 0xF104;
/// Sensor ID carrying the RX's analog 1 byte (A2).
pub const SENSOR_A2: u16 = 0xF103;

/// Bytes for the handset UART; the longest frame, fully stuffed, is 20 bytes.
pub type Output = Vec<u8, 24>;

fn push_stuffed(out: &mut Output, byte: u8) {
    // Capacity covers every frame built here fully stuffed; a failed push cannot happen.
    match stuffing::escaped(byte) {
        Some(pair) => {
            let _ = out.extend_from_slice(&pair);
        }
        None => {
            let _ = out.push(byte);
        }
    }
}

/// Hub link frame: `7E FE A1 A2 RSSIrx/2 RSSItx 00 00 00 00 7E` (composite RSSI values).
pub fn hub_link_frame(a1: u8, a2: u8, rx_composite: u8, tx_composite: u8) -> Output {
    let mut out = Output::new();
    let _ = out.push(FRAME_START);
    for b in [HUB_LINK, a1, a2, rx_composite / 2, tx_composite, 0, 0, 0, 0] {
        push_stuffed(&mut out, b);
    }
    let _ = out.push(FRAME_START);
    out
}

/// Hub user-data frame with up to 6 bytes: `7E FD n 00 d0..d5 7E`, unused bytes 0.
pub fn hub_user_frame(data: &[u8]) -> Output {
    let n = data.len().min(HUB_USER_BYTES);
    let mut out = Output::new();
    let _ = out.push(FRAME_START);
    push_stuffed(&mut out, HUB_USER_DATA);
    push_stuffed(&mut out, n as u8);
    push_stuffed(&mut out, 0);
    for i in 0..HUB_USER_BYTES {
        push_stuffed(
            &mut out,
            data.get(i).copied().filter(|_| i < n).unwrap_or(0),
        );
    }
    let _ = out.push(FRAME_START);
    out
}

/// S.Port data frame `7E 98 10 idL idH v0 0 0 0 crc`, stuffed after the physical ID.
pub fn smartport_frame(sensor_id: u16, value: u8) -> Output {
    let [id_lo, id_hi] = sensor_id.to_le_bytes();
    let body = [SMARTPORT_DATA_FRAME, id_lo, id_hi, value, 0, 0, 0];
    // CRC: byte sum with the carry folded back in, then 0xFF − sum.
    let sum = body.iter().fold(0u16, |acc, &b| {
        let s = acc + u16::from(b);
        (s & 0xFF) + (s >> 8)
    });
    let crc = 0xFF - (sum as u8);
    let mut out = Output::new();
    let _ = out.extend_from_slice(&[FRAME_START, SMARTPORT_PHYSICAL_ID]);
    for b in body.into_iter().chain([crc]) {
        push_stuffed(&mut out, b);
    }
    out
}

/// What the S.Port slots report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SmartPortInputs {
    /// RX analog 0 byte.
    pub a1: u8,
    /// RX analog 1 byte.
    pub a2: u8,
    /// min(composite RX RSSI, composite TX RSSI).
    pub rssi: u8,
    /// Active TX profile 0..3.
    pub profile: u8,
}

/// The bytes of one S.Port slot: frames in slots 0..3, a bare 0x7E otherwise.
pub fn smartport_slot(slot: u8, inputs: &SmartPortInputs) -> Output {
    match slot {
        0 => smartport_frame(SENSOR_SWR, inputs.profile.wrapping_add(1)),
        1 => smartport_frame(SENSOR_RSSI, (u16::from(inputs.rssi) * 100 / 256) as u8),
        2 => smartport_frame(SENSOR_BATT, inputs.a1),
        3 => smartport_frame(SENSOR_A2, inputs.a2),
        // A one-byte array into a 24-byte Vec: the capacity is checked at compile time.
        _ => Vec::from_array([FRAME_START]),
    }
}

/// The TX's S.Port output: call [`SmartPortEncoder::next`] every 12 ms.
#[derive(Debug, Clone, Default)]
pub struct SmartPortEncoder {
    slot: u8,
}

impl SmartPortEncoder {
    /// Bytes for the current slot; advances the 36-slot cycle.
    pub fn next(&mut self, inputs: &SmartPortInputs) -> Output {
        let out = smartport_slot(self.slot, inputs);
        self.slot = (self.slot + 1) % SMARTPORT_SLOTS;
        out
    }
}

/// Capacity of the hub encoder's queue of downlink serial bytes.
pub const HUB_QUEUE_LEN: usize = 64;

/// The TX's FrSky hub output: queue RX serial bytes, call [`HubEncoder::next`] every 30 ms.
#[derive(Debug, Clone, Default)]
pub struct HubEncoder {
    queue: Deque<u8, HUB_QUEUE_LEN>,
    frame_counter: u8,
}

/// Link values for the hub link frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HubLink {
    /// RX analog 0 byte.
    pub a1: u8,
    /// RX analog 1 byte.
    pub a2: u8,
    /// Composite RX RSSI (halved on output).
    pub rx_composite: u8,
    /// Composite TX RSSI.
    pub tx_composite: u8,
}

impl HubEncoder {
    /// Queues serial bytes from the downlink; returns how many did not fit (dropped).
    pub fn push_serial(&mut self, data: &[u8]) -> usize {
        data.iter()
            .filter(|&&b| self.queue.push_back(b).is_err())
            .count()
    }

    /// The next user-data frame (up to 6 queued bytes), or nothing if the queue is empty.
    pub fn user_frame(&mut self) -> Output {
        let mut chunk: Vec<u8, HUB_USER_BYTES> = Vec::new();
        while chunk.len() < HUB_USER_BYTES {
            match self.queue.pop_front() {
                Some(b) => {
                    let _ = chunk.push(b);
                }
                None => break,
            }
        }
        if chunk.is_empty() {
            Output::new()
        } else {
            hub_user_frame(&chunk)
        }
    }

    /// Bytes for this 30 ms tick: a link frame every 6th tick, user data otherwise.
    pub fn next(&mut self, link: &HubLink) -> Output {
        let counter = self.frame_counter;
        self.frame_counter = (counter + 1) % HUB_LINK_EVERY;
        if counter == 0 {
            hub_link_frame(link.a1, link.a2, link.rx_composite, link.tx_composite)
        } else {
            self.user_frame()
        }
    }
}

/// Everything the TX forwards to its handset, fed from the downlink (`frskyUpdate` in
/// TX.h): composite RX and TX RSSI, the RX analog bytes, and the RX serial stream (hub mode).
#[derive(Debug, Clone, Default)]
pub struct HandsetTelemetry {
    hub: HubEncoder,
    smartport: SmartPortEncoder,
    link: Option<(telemetry::LinkInfo, u8)>,
}

impl HandsetTelemetry {
    /// A link-info frame arrived; `tx_rssi` is the TX's own RSSI reading of the reply.
    pub fn on_link_info(&mut self, info: telemetry::LinkInfo, tx_rssi: u8) {
        self.link = Some((info, tx_rssi));
    }

    /// RX serial bytes (forwarded as hub user data); returns how many were dropped.
    pub fn on_serial(&mut self, data: &[u8]) -> usize {
        self.hub.push_serial(data)
    }

    fn composites(&self, tx_link_quality: u8) -> Option<(telemetry::LinkInfo, u8, u8)> {
        let (info, tx_rssi) = self.link?;
        let rx = telemetry::composite_rssi(info.link_quality, info.rssi);
        let tx = telemetry::composite_rssi(tx_link_quality, tx_rssi);
        Some((info, rx, tx))
    }

    /// Hub bytes for this 30 ms tick at 9600 baud; nothing before the first report (the
    /// TX only talks to the handset once telemetry has been heard).
    pub fn hub_tick(&mut self, tx_link_quality: u8) -> Output {
        match self.composites(tx_link_quality) {
            Some((info, rx, tx)) => self.hub.next(&HubLink {
                a1: info.analog0,
                a2: info.analog1,
                rx_composite: rx,
                tx_composite: tx,
            }),
            None => Output::new(),
        }
    }

    /// S.Port bytes for this 12 ms tick at 57600 baud; `profile` is the TX profile 0..3.
    pub fn smartport_tick(&mut self, tx_link_quality: u8, profile: u8) -> Output {
        match self.composites(tx_link_quality) {
            Some((info, rx, tx)) => self.smartport.next(&SmartPortInputs {
                a1: info.analog0,
                a2: info.analog1,
                rssi: rx.min(tx),
                profile,
            }),
            None => Output::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hub_link_stuffs_delimiters() {
        let f = hub_link_frame(0x7E, 1, 0, 0x7D);
        assert_eq!(
            f.as_slice(),
            &[0x7E, 0xFE, 0x7D, 0x5E, 1, 0, 0x7D, 0x5D, 0, 0, 0, 0, 0x7E]
        );
    }

    #[test]
    fn hub_cadence() {
        let mut e = HubEncoder::default();
        let link = HubLink {
            a1: 1,
            a2: 2,
            rx_composite: 4,
            tx_composite: 5,
        };
        assert_eq!(e.push_serial(&[9; 3]), 0);
        assert_eq!(e.next(&link)[1], HUB_LINK);
        assert_eq!(
            e.next(&link).as_slice(),
            &[0x7E, 0xFD, 3, 0, 9, 9, 9, 0, 0, 0, 0x7E]
        );
        assert!(e.next(&link).is_empty());
    }

    #[test]
    fn handset_telemetry_uses_composite_rssi() {
        let mut t = HandsetTelemetry::default();
        assert!(t.hub_tick(15).is_empty());
        let info = telemetry::LinkInfo {
            rssi: 200,
            analog0: 10,
            analog1: 20,
            afc: 0,
            link_quality: 15,
        };
        t.on_link_info(info, 100);
        // RX composite (200 >> 1) + 128 = 228, sent halved (114); TX at LQ 10 → 90.
        assert_eq!(
            t.hub_tick(10).as_slice(),
            &[0x7E, 0xFE, 10, 20, 114, 90, 0, 0, 0, 0, 0x7E]
        );
        // S.Port slot 0 is SWR = profile + 1, slot 1 min(228, 90) · 100 / 256 = 35.
        assert_eq!(t.smartport_tick(10, 2)[3..6], [0x05, 0xF1, 3]);
        assert_eq!(t.smartport_tick(10, 2)[3..6], [0x01, 0xF1, 35]);
    }
}
