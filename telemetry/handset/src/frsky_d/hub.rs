//! The FrSky hub byte stream that user frames carry: `5E id lo hi` records with 0x5D stuffing
//! (EdgeTX `parseTelemHubByte`: the byte after 0x5D is XORed with 0x60), and the sender that
//! turns [`HandsetTelemetry`] into link and user frames at openLRSng's pace.

use heapless::{Deque, Vec};

use super::{Frame, LinkFrame, USER_DATA_MAX};
use crate::report::{HandsetTelemetry, scaled_u16};

/// Record start.
pub const HUB_START: u8 = 0x5E;
/// Hub escape byte.
pub const HUB_STUFF: u8 = 0x5D;
/// XOR applied to an escaped hub byte.
pub const HUB_STUFF_XOR: u8 = 0x60;
/// Largest record ID EdgeTX accepts.
pub const HUB_LAST_ID: u8 = 0x3F;
/// Longest encoded record: start + 3 bytes that may each be escaped.
pub const RECORD_MAX_LEN: usize = 7;

/// Hub record IDs (EdgeTX `frsky.h`).
pub mod id {
    /// Temperature 1, °C (we put the flight-mode number here; rename it "FM").
    pub const TEMP1: u8 = 0x02;
    /// Fuel, %.
    pub const FUEL: u8 = 0x04;
    /// Current, 0.1 A.
    pub const CURRENT: u8 = 0x28;
    /// VFAS: below 2000 in 0.1 V; from 2000 up, 0.01 V plus 2000 (EdgeTX `VFAS_D_HIPREC_OFFSET`).
    pub const VFAS: u8 = 0x39;
    /// Barometric altitude, whole metres (signed), sent before [`BARO_ALT_AP`].
    pub const BARO_ALT_BP: u8 = 0x10;
    /// Barometric altitude after the point. We send decimetres (0…9): EdgeTX takes values
    /// ≤ 9 as decimetres until it has seen one > 9, so this is never misread.
    pub const BARO_ALT_AP: u8 = 0x21;
    /// Vertical speed, cm/s (signed).
    pub const VARIO: u8 = 0x30;
    /// One cell (EdgeTX `VOLTS_ID`, "Cels"): see [`super::HubRecord::cell`].
    pub const CELLS: u8 = 0x06;
}

/// Largest 12-bit cell value (1/500 V steps): 8.19 V.
pub const CELL_RAW_MAX: u16 = 0x0FFF;

/// Offset marking a high-precision (0.01 V) VFAS value.
pub const VFAS_HIGH_PRECISION_OFFSET: u16 = 2000;

/// One hub record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HubRecord {
    /// Record ID, 0x00…0x3F.
    pub id: u8,
    /// Value (little-endian on the wire).
    pub value: u16,
}

impl HubRecord {
    /// VFAS in high precision: 0.01 V + 2000 (so up to 634.35 V).
    pub fn vfas_mv(voltage_mv: u32) -> Self {
        let centivolts = scaled_u16(voltage_mv, 10).min(u16::MAX - VFAS_HIGH_PRECISION_OFFSET);
        Self {
            id: id::VFAS,
            value: centivolts + VFAS_HIGH_PRECISION_OFFSET,
        }
    }

    /// Cell `index` (0…15) at `cell_mv`, as EdgeTX's `processHubPacket` unpacks VOLTS_ID:
    /// the index in bits 4–7, the voltage in 1/500 V (12 bits, cut to the 2 mV step) with its
    /// top nibble in bits 0–3 and its low byte in bits 8–15. EdgeTX counts the cells from the
    /// highest index it has seen.
    pub fn cell(index: u8, cell_mv: u16) -> Self {
        let raw = (cell_mv / 2).min(CELL_RAW_MAX);
        Self {
            id: id::CELLS,
            value: ((raw & 0xFF) << 8) | (u16::from(index & 0x0F) << 4) | (raw >> 8),
        }
    }

    /// `5E id lo hi` with 0x5E/0x5D escaped; returns the encoded bytes.
    pub fn encode(&self) -> Vec<u8, RECORD_MAX_LEN> {
        let mut out = Vec::new();
        let [lo, hi] = self.value.to_le_bytes();
        // At most 1 + 3 × 2 = 7 bytes: the pushes cannot fail.
        let _ = out.push(HUB_START);
        for byte in [self.id, lo, hi] {
            if matches!(byte, HUB_START | HUB_STUFF) {
                let _ = out.push(HUB_STUFF);
                let _ = out.push(byte ^ HUB_STUFF_XOR);
            } else {
                let _ = out.push(byte);
            }
        }
        out
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HubState {
    Idle,
    Id,
    Low { id: u8 },
    High { id: u8, low: u8 },
}

/// Streaming hub parser with EdgeTX's rules: 0x5E restarts, IDs above 0x3F drop the record.
#[derive(Debug, Clone)]
pub struct HubDecoder {
    state: HubState,
    escaped: bool,
    dropped: u32,
}

impl Default for HubDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl HubDecoder {
    /// An idle parser.
    pub const fn new() -> Self {
        Self {
            state: HubState::Idle,
            escaped: false,
            dropped: 0,
        }
    }

    /// Records dropped for an ID above 0x3F.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Takes one hub byte (from a user frame's data).
    pub fn push(&mut self, byte: u8) -> Option<HubRecord> {
        if byte == HUB_START {
            self.state = HubState::Id;
            self.escaped = false;
            return None;
        }
        if self.state == HubState::Idle {
            return None;
        }
        if byte == HUB_STUFF && !self.escaped {
            self.escaped = true;
            return None;
        }
        let byte = if self.escaped {
            byte ^ HUB_STUFF_XOR
        } else {
            byte
        };
        self.escaped = false;
        match self.state {
            HubState::Idle => None,
            HubState::Id if byte > HUB_LAST_ID => {
                self.dropped = self.dropped.saturating_add(1);
                self.state = HubState::Idle;
                None
            }
            HubState::Id => {
                self.state = HubState::Low { id: byte };
                None
            }
            HubState::Low { id } => {
                self.state = HubState::High { id, low: byte };
                None
            }
            HubState::High { id, low } => {
                self.state = HubState::Idle;
                Some(HubRecord {
                    id,
                    value: u16::from_le_bytes([low, byte]),
                })
            }
        }
    }
}

/// Pace and scaling of the hub sender.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SenderConfig {
    /// Frame spacing (openLRSng: 30 ms; a stuffed frame takes ≤ 20 ms at 9600 Bd).
    pub slot_interval_us: u32,
    /// Every n-th slot is a link frame (openLRSng: 6).
    pub link_every: u8,
    /// Battery voltage that reads as A1 = 255 (EdgeTX's default A1 ratio is 13.2 V).
    pub a1_full_scale_mv: u32,
}

impl Default for SenderConfig {
    fn default() -> Self {
        Self {
            slot_interval_us: 30_000,
            link_every: 6,
            a1_full_scale_mv: 13_200,
        }
    }
}

/// Produces one frame per slot: link frames (A1 = battery, A2 = uplink LQ, RSSI = downlink
/// LQ, TX RSSI = uplink LQ; RSSI 0 with no link) and, while the link streams, user frames
/// with VFAS, current, fuel, the flight-mode number in Temp1, baro altitude, vario and the
/// cells (two per round, in turn). Records run on across link frames and are never cut.
#[derive(Debug, Clone)]
pub struct Sender {
    config: SenderConfig,
    last_slot_us: Option<u64>,
    slot: u8,
    queue: Deque<u8, 64>,
    /// The next cell to send (cells go [`CELLS_PER_ROUND`] per refill, in turn).
    next_cell: u8,
}

/// Cell records per refill: a 6S pack's cells take three rounds, and a round (9 records of
/// at most 7 bytes) fits the queue.
pub const CELLS_PER_ROUND: u8 = 2;

impl Sender {
    /// A sender that has sent nothing.
    pub fn new(config: SenderConfig) -> Self {
        Self {
            config,
            last_slot_us: None,
            slot: 0,
            queue: Deque::new(),
            next_cell: 0,
        }
    }

    /// The frame for the slot starting at `now_us`, or `None` between slots.
    pub fn next_frame(&mut self, now_us: u64, telemetry: &HandsetTelemetry) -> Option<Frame> {
        if let Some(last) = self.last_slot_us
            && now_us.saturating_sub(last) < u64::from(self.config.slot_interval_us)
        {
            return None;
        }
        self.last_slot_us = Some(now_us);
        let slot = self.slot;
        self.slot = (slot + 1) % self.config.link_every.max(1);
        if !telemetry.link_streaming() {
            self.drop_unstarted_records();
            return Some(Frame::Link(self.link_frame(telemetry)));
        }
        if slot == 0 {
            // The queue carries over: EdgeTX parses the hub stream across user frames, and a
            // record cut here would be dropped at the next 0x5E.
            return Some(Frame::Link(self.link_frame(telemetry)));
        }
        if self.queue.is_empty() {
            self.refill(telemetry);
        }
        if self.queue.is_empty() {
            // Nothing for the hub: an empty user frame would say nothing, a link frame does.
            return Some(Frame::Link(self.link_frame(telemetry)));
        }
        let mut data = Vec::new();
        while data.len() < USER_DATA_MAX {
            let Some(byte) = self.queue.pop_front() else {
                break;
            };
            let _ = data.push(byte);
        }
        Some(Frame::User(data))
    }

    /// Drops the queued records not yet begun (their values are stale once the link is
    /// back) but keeps the rest of the one in flight, so that no record is ever cut. A raw
    /// 0x5E only ever starts a record (stuffing escapes it elsewhere).
    fn drop_unstarted_records(&mut self) {
        let begun = self
            .queue
            .iter()
            .position(|&byte| byte == HUB_START)
            .unwrap_or(self.queue.len());
        while self.queue.len() > begun {
            let _ = self.queue.pop_back();
        }
    }

    fn link_frame(&self, telemetry: &HandsetTelemetry) -> LinkFrame {
        let a1 = telemetry.battery.map_or(0, |battery| {
            let raw = u64::from(battery.voltage_mv) * 255
                / u64::from(self.config.a1_full_scale_mv.max(1));
            raw.min(255) as u8
        });
        match telemetry.link {
            Some(link) => LinkFrame {
                a1,
                a2: link.uplink_lq_percent.min(100),
                rssi: link.downlink_lq_percent.clamp(1, 100),
                tx_rssi: link.uplink_lq_percent.min(100),
            },
            None => LinkFrame {
                a1,
                ..LinkFrame::default()
            },
        }
    }

    fn refill(&mut self, telemetry: &HandsetTelemetry) {
        let mut records: Vec<HubRecord, 9> = Vec::new();
        if let Some(battery) = telemetry.battery {
            let _ = records.push(HubRecord::vfas_mv(battery.voltage_mv));
            let _ = records.push(HubRecord {
                id: id::CURRENT,
                value: scaled_u16(battery.current_ma, 100),
            });
            let _ = records.push(HubRecord {
                id: id::FUEL,
                value: u16::from(battery.remaining_percent.min(100)),
            });
        }
        if let Some(mode) = &telemetry.flight_mode {
            let _ = records.push(HubRecord {
                id: id::TEMP1,
                value: u16::from(mode.number),
            });
        }
        if let Some(vertical) = telemetry.vertical {
            // Metres and decimetres, both carrying the sign (EdgeTX subtracts the part after
            // the point for a negative altitude).
            let dm = vertical.altitude_cm / 10;
            let metres = (dm / 10).clamp(i32::from(i16::MIN), i32::from(i16::MAX));
            let _ = records.push(HubRecord {
                id: id::BARO_ALT_BP,
                value: metres as i16 as u16,
            });
            // EdgeTX reads `100·BP ± AP`, so −0.9…−0.1 m has no encoding: it goes as 0.
            let decimetres = if metres == 0 && dm < 0 { 0 } else { dm % 10 };
            let _ = records.push(HubRecord {
                id: id::BARO_ALT_AP,
                value: decimetres.unsigned_abs() as u16,
            });
            let _ = records.push(HubRecord {
                id: id::VARIO,
                value: vertical.vario_cm_s as u16,
            });
        }
        if let (Some(count), Some(cell_mv)) = (telemetry.cells, telemetry.cell_mv()) {
            // EdgeTX has 4 bits of index: a pack above 16S is not sent.
            if (1..=16).contains(&count) {
                for _ in 0..CELLS_PER_ROUND.min(count) {
                    let index = if self.next_cell < count {
                        self.next_cell
                    } else {
                        0
                    };
                    let _ = records.push(HubRecord::cell(index, cell_mv));
                    self.next_cell = index + 1;
                }
            }
        }
        // 9 records × ≤ 7 bytes = 63 ≤ 64.
        for byte in records.iter().flat_map(HubRecord::encode) {
            let _ = self.queue.push_back(byte);
        }
    }
}
