//! Which S.Port value to push when, in PPM mode where the radio never polls (EdgeTX ≥ 2.11
//! "SPort", OpenTX 2.2/2.3): one frame per slot, RSSI often enough to keep
//! EdgeTX's 1 s streaming gate open, the rest by rate and age: VFAS, LQ, vario (0x0110) and
//! altitude (0x0100) at the fast rate; current, flight mode and the cells (0x0300, two per
//! frame, each the pack's average) at the slow rate; fuel, the module's own supply (A2,
//! raw over 13.2 V) and a keyed link's tag failures and tag alert (DIY 0x5102, 0x5103) at
//! 1 Hz.

use super::{Frame, physical_id, value_id};
use crate::report::{HandsetTelemetry, scaled_u16};

/// How link quality reaches the radio.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LqEncoding {
    /// LQ % under a DIY value ID (default 0x5100, which the user renames "LQ").
    Diy(u16),
    /// EdgeTX's VFR sensor 0xF010, which shows 100 − value: we send 100 − LQ.
    Vfr,
}

/// What the RSSI sensor (0xF101) carries. EdgeTX alarms act on it (defaults 45 / 42).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RssiSource {
    /// Downlink LQ % (as many long-range links do): alarms then fire on packet loss.
    LinkQuality,
    /// Downlink RSSI as dB above `floor_dbm`, clamped to 1…100.
    SignalAboveFloor {
        /// dBm shown as 0 (about the receiver's sensitivity).
        floor_dbm: i16,
    },
}

/// Rates and IDs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Physical ID every frame carries.
    pub physical_id: u8,
    /// Minimum spacing of frames (openLRSng: 12 ms; a stuffed frame takes ≤ 3.2 ms at 57 600).
    pub slot_interval_us: u32,
    /// RSSI meaning.
    pub rssi: RssiSource,
    /// LQ encoding.
    pub lq: LqEncoding,
    /// Value ID of the flight-mode number.
    pub flight_mode_value_id: u16,
    /// Period of RSSI (≥ several per second: EdgeTX's gate times out after 1 s).
    pub rssi_interval_us: u32,
    /// Period of VFAS and LQ.
    pub fast_interval_us: u32,
    /// Period of current and flight mode.
    pub slow_interval_us: u32,
    /// Period of fuel.
    pub fuel_interval_us: u32,
}

impl Default for Config {
    /// Physical ID 0x98, 12 ms slots, RSSI = LQ at 10 Hz, VFAS/LQ 5 Hz, current/FM 2 Hz,
    /// fuel 1 Hz.
    fn default() -> Self {
        Self {
            physical_id: physical_id::RECEIVER,
            slot_interval_us: 12_000,
            rssi: RssiSource::LinkQuality,
            lq: LqEncoding::Diy(value_id::TAULINK_LQ),
            flight_mode_value_id: value_id::TAULINK_FLIGHT_MODE,
            rssi_interval_us: 100_000,
            fast_interval_us: 200_000,
            slow_interval_us: 500_000,
            fuel_interval_us: 1_000_000,
        }
    }
}

/// Items in priority order (ties in lateness go to the earlier one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Item {
    Rssi,
    Vfas,
    LinkQuality,
    Current,
    FlightMode,
    Fuel,
    Vario,
    Altitude,
    Cells,
    ModuleBattery,
    TagFailures,
    TagAlert,
}

const ITEMS: [Item; 12] = [
    Item::Rssi,
    Item::Vfas,
    Item::LinkQuality,
    Item::Vario,
    Item::Altitude,
    Item::Current,
    Item::FlightMode,
    Item::Fuel,
    Item::Cells,
    Item::ModuleBattery,
    Item::TagFailures,
    Item::TagAlert,
];

/// The push scheduler.
#[derive(Debug, Clone)]
pub struct Scheduler {
    config: Config,
    last_slot_us: Option<u64>,
    last_sent_us: [Option<u64>; ITEMS.len()],
    /// First cell of the next FLVSS frame (cells go two per frame, in turn).
    next_cell: u8,
}

impl Scheduler {
    /// A scheduler that has sent nothing.
    pub fn new(config: Config) -> Self {
        Self {
            config,
            last_slot_us: None,
            last_sent_us: [None; ITEMS.len()],
            next_cell: 0,
        }
    }

    /// The RSSI value for `telemetry`: 0 with no link (EdgeTX: "telemetry lost"), else ≥ 1.
    pub fn rssi_value(&self, telemetry: &HandsetTelemetry) -> u32 {
        let Some(link) = telemetry.link else {
            return 0;
        };
        let value = match self.config.rssi {
            RssiSource::LinkQuality => i32::from(link.downlink_lq_percent),
            RssiSource::SignalAboveFloor { floor_dbm } => {
                i32::from(link.downlink_rssi_dbm) - i32::from(floor_dbm)
            }
        };
        value.clamp(1, 100) as u32
    }

    /// The frame to push now, if a slot is free and something is due; `None` = stay quiet
    /// (or send a lone 0x7E as openLRSng does in idle slots).
    pub fn next_frame(&mut self, now_us: u64, telemetry: &HandsetTelemetry) -> Option<Frame> {
        if let Some(last) = self.last_slot_us
            && now_us.saturating_sub(last) < u64::from(self.config.slot_interval_us)
        {
            return None;
        }
        let mut best: Option<(usize, u64, Frame)> = None;
        for (index, &item) in ITEMS.iter().enumerate() {
            let interval = u64::from(self.interval_us(item));
            let last = self.last_sent_us.get(index).copied().flatten();
            // Lateness past the due time; never sent counts as the latest of all.
            let lateness = match last {
                None => u64::MAX,
                Some(last) => match now_us.saturating_sub(last).checked_sub(interval) {
                    Some(late) => late,
                    None => continue,
                },
            };
            if best
                .as_ref()
                .is_some_and(|(_, best_late, _)| *best_late >= lateness)
            {
                continue;
            }
            if let Some(frame) = self.frame_for(item, telemetry) {
                best = Some((index, lateness, frame));
            }
        }
        let (index, _, frame) = best?;
        if let Some(slot) = self.last_sent_us.get_mut(index) {
            *slot = Some(now_us);
        }
        if ITEMS.get(index) == Some(&Item::Cells) {
            let count = telemetry.cells.unwrap_or(0);
            self.next_cell = if self.next_cell + 2 < count {
                self.next_cell + 2
            } else {
                0
            };
        }
        self.last_slot_us = Some(now_us);
        Some(frame)
    }

    fn interval_us(&self, item: Item) -> u32 {
        match item {
            Item::Rssi => self.config.rssi_interval_us,
            Item::Vfas | Item::LinkQuality | Item::Vario | Item::Altitude => {
                self.config.fast_interval_us
            }
            // Two cells per frame: a 6S pack needs three frames per round.
            Item::Current | Item::FlightMode | Item::Cells => self.config.slow_interval_us,
            Item::Fuel | Item::ModuleBattery | Item::TagFailures | Item::TagAlert => {
                self.config.fuel_interval_us
            }
        }
    }

    /// The frame for `item`, or `None` when its data is missing. With the link down only RSSI
    /// (= 0) goes out: EdgeTX discards every other value then anyway.
    fn frame_for(&self, item: Item, telemetry: &HandsetTelemetry) -> Option<Frame> {
        let id = self.config.physical_id;
        if item == Item::Rssi {
            return Some(Frame::data(id, value_id::RSSI, self.rssi_value(telemetry)));
        }
        if !telemetry.link_streaming() {
            return None;
        }
        match item {
            Item::Rssi => None,
            Item::Vfas => telemetry
                .battery
                .map(|b| Frame::data(id, value_id::VFAS, u32::from(scaled_u16(b.voltage_mv, 10)))),
            Item::Current => telemetry.battery.map(|b| {
                Frame::data(
                    id,
                    value_id::CURRENT,
                    u32::from(scaled_u16(b.current_ma, 100)),
                )
            }),
            Item::Fuel => telemetry
                .battery
                .map(|b| Frame::data(id, value_id::FUEL, u32::from(b.remaining_percent.min(100)))),
            Item::LinkQuality => telemetry.link.map(|link| {
                let lq = u32::from(link.uplink_lq_percent.min(100));
                match self.config.lq {
                    LqEncoding::Diy(value_id) => Frame::data(id, value_id, lq),
                    LqEncoding::Vfr => Frame::data(id, value_id::VFR, 100 - lq),
                }
            }),
            Item::FlightMode => telemetry.flight_mode.as_ref().map(|mode| {
                Frame::data(id, self.config.flight_mode_value_id, u32::from(mode.number))
            }),
            // Signed values travel as their 32-bit two's complement.
            Item::Vario => telemetry
                .vertical
                .map(|v| Frame::data(id, value_id::VARIO, i32::from(v.vario_cm_s) as u32)),
            Item::Altitude => telemetry
                .vertical
                .map(|v| Frame::data(id, value_id::ALT, v.altitude_cm as u32)),
            // The module's own supply as A2 (raw 0…255 over EdgeTX's default 13.2 V ratio).
            Item::ModuleBattery => telemetry.module_battery_mv.map(|mv| {
                let raw = (u32::from(mv) * 255 / 13_200).min(255);
                Frame::data(id, value_id::A2, raw)
            }),
            Item::TagFailures => telemetry
                .link_security
                .map(|s| Frame::data(id, value_id::TAULINK_TAG_FAILURES, s.tag_failures)),
            Item::TagAlert => telemetry
                .link_security
                .map(|s| Frame::data(id, value_id::TAULINK_TAG_ALERT, u32::from(s.alert))),
            Item::Cells => {
                let count = telemetry.cells.filter(|c| (1..=15).contains(c))?;
                let first = if self.next_cell < count {
                    self.next_cell
                } else {
                    0
                };
                let cell_mv = telemetry.cell_mv()?;
                Some(Frame::data(
                    id,
                    value_id::CELLS,
                    super::flvss_value(count, first, cell_mv),
                ))
            }
        }
    }
}
