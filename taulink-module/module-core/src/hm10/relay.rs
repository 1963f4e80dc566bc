//! The relay between the link's telemetry records and the phone behind the HM-10, in both
//! directions, with the connection state taken from the module's `OK+CONN` / `OK+LOST`
//! notifications (enabled with `AT+NOTI1` during configuration).
//!
//! While no phone is connected the HM-10 parses its UART input as AT commands (§5), so
//! records for the phone are only sent while connected; a disconnect clears what waits for
//! the phone (stale telemetry is worthless and counted as dropped).
//!
//! Records from the phone go on to the flight side unread, except module-addressed ones
//! (`telemetry::module_record`: their first byte is the module marker), which wait for the
//! module core ([`Relay::next_record_to_module`]).

use super::queue::{DropStats, RecordQueue};
use telemetry::cobs;

/// Longest record relayed (a CRSF frame is at most 64 bytes; link records are smaller).
pub const MAX_RECORD_LEN: usize = 64;
/// Longest frame on the HM-10 UART: the COBS encoding plus the 0x00 delimiter.
pub const MAX_FRAME_LEN: usize = cobs::max_encoded_len(MAX_RECORD_LEN) + 1;
/// Bytes buffered towards the phone: ≈ 1 s at the 1 kB/s a BLE 4.0 link sustains (§5).
const TO_PHONE_BYTES: usize = 1024;
const TO_PHONE_RECORDS: usize = 48;
/// Bytes buffered from the phone towards the flight side.
const TO_FLIGHT_BYTES: usize = 256;
const TO_FLIGHT_RECORDS: usize = 8;
/// Bytes buffered from the phone for the module itself (a key record is ≈ 35 bytes).
const TO_MODULE_BYTES: usize = 128;
const TO_MODULE_RECORDS: usize = 2;

/// The HM-10's connection notifications (`AT+NOTI1`), sent without CR/LF.
const CONNECTED: &[u8; 7] = b"OK+CONN";
const DISCONNECTED: &[u8; 7] = b"OK+LOST";

/// Something the phone side produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PhoneEvent<'a> {
    /// A complete record from the phone.
    Record(&'a [u8]),
    /// The HM-10 reported a connection.
    Connected,
    /// The HM-10 reported the connection lost.
    Disconnected,
    /// A frame that was not valid COBS (dropped).
    Malformed(cobs::Error),
    /// A frame longer than [`MAX_FRAME_LEN`] (dropped).
    Overlong,
}

/// Splits the byte stream from the HM-10 into records and connection notifications.
#[derive(Debug)]
pub struct PhoneReader {
    frame: heapless::Vec<u8, MAX_FRAME_LEN>,
    overlong: bool,
    /// The last record was handed out borrowed; forget it at the next byte.
    handed_out: bool,
    recent: [u8; 7],
}

impl Default for PhoneReader {
    fn default() -> Self {
        Self::new()
    }
}

impl PhoneReader {
    /// A reader at a frame boundary.
    pub const fn new() -> Self {
        Self {
            frame: heapless::Vec::new(),
            overlong: false,
            handed_out: false,
            recent: [0; 7],
        }
    }

    /// One byte from the HM-10.
    pub fn push_byte(&mut self, byte: u8) -> Option<PhoneEvent<'_>> {
        if self.handed_out {
            self.frame.clear();
            self.handed_out = false;
        }
        self.recent.rotate_left(1);
        if let Some(last) = self.recent.last_mut() {
            *last = byte;
        }
        // A notification is not payload: whatever partial frame it landed in is void.
        for (token, event) in [
            (CONNECTED, PhoneEvent::Connected),
            (DISCONNECTED, PhoneEvent::Disconnected),
        ] {
            if &self.recent == token {
                self.frame.clear();
                self.overlong = false;
                self.recent = [0; 7];
                return Some(event);
            }
        }
        if byte != 0 {
            if !self.overlong && self.frame.push(byte).is_err() {
                self.overlong = true;
                self.frame.clear();
            }
            return None;
        }
        if core::mem::take(&mut self.overlong) {
            return Some(PhoneEvent::Overlong);
        }
        if self.frame.is_empty() {
            return None;
        }
        self.handed_out = true;
        match cobs::decode_in_place(&mut self.frame) {
            Ok(length) => {
                // The decoded record is the front of the frame (cleared on the next byte).
                self.frame.truncate(length);
                Some(PhoneEvent::Record(&self.frame))
            }
            Err(error) => Some(PhoneEvent::Malformed(error)),
        }
    }
}

/// Counters of the relay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RelayStats {
    /// Dropped on the way to the phone (full buffer, disconnect, oversize).
    pub to_phone: DropStats,
    /// Dropped on the way to the flight side.
    pub to_flight: DropStats,
    /// Module-addressed records dropped (the core did not take them in time).
    pub to_module: DropStats,
    /// Frames from the phone that were malformed or overlong.
    pub bad_frames_from_phone: u32,
}

/// Both directions of the HM-10 relay.
#[derive(Debug)]
pub struct Relay {
    to_phone: RecordQueue<TO_PHONE_BYTES, TO_PHONE_RECORDS>,
    to_flight: RecordQueue<TO_FLIGHT_BYTES, TO_FLIGHT_RECORDS>,
    to_module: RecordQueue<TO_MODULE_BYTES, TO_MODULE_RECORDS>,
    reader: PhoneReader,
    connected: bool,
    bad_frames_from_phone: u32,
}

impl Relay {
    /// A relay; `connected` is the best knowledge at start (after a reset without
    /// configuration the module may still hold a phone connection).
    pub const fn new(connected: bool) -> Self {
        Self {
            to_phone: RecordQueue::new(MAX_RECORD_LEN),
            to_flight: RecordQueue::new(MAX_RECORD_LEN),
            to_module: RecordQueue::new(MAX_RECORD_LEN),
            reader: PhoneReader::new(),
            connected,
            bad_frames_from_phone: 0,
        }
    }

    /// A phone is connected as far as the HM-10 told us.
    pub fn is_connected(&self) -> bool {
        self.connected
    }

    /// Sets the connection state from outside knowledge (the configuration script saw the
    /// phone before the relay started).
    pub fn set_connected(&mut self, connected: bool) {
        self.connected = connected;
    }

    /// The counters.
    pub fn stats(&self) -> RelayStats {
        RelayStats {
            to_phone: self.to_phone.dropped(),
            to_flight: self.to_flight.dropped(),
            to_module: self.to_module.dropped(),
            bad_frames_from_phone: self.bad_frames_from_phone,
        }
    }

    /// A telemetry record from the link for the phone. Never blocks; without a phone the
    /// record is not queued.
    pub fn on_link_record(&mut self, record: &[u8]) {
        if self.connected {
            self.to_phone.push(record);
        }
    }

    /// The next frame for the HM-10 UART (COBS plus delimiter) into `out`, which must hold
    /// [`MAX_FRAME_LEN`] bytes; `None` when nothing is to be sent.
    pub fn next_frame_to_phone(&mut self, out: &mut [u8]) -> Option<usize> {
        // A short buffer would have to lose the record it pops: refuse before popping.
        if !self.connected || out.len() < MAX_FRAME_LEN {
            return None;
        }
        let mut record = [0u8; MAX_RECORD_LEN];
        let length = self.to_phone.pop_into(&mut record).ok()??;
        let encoded = cobs::encode(record.get(..length)?, out).ok()?;
        *out.get_mut(encoded)? = 0;
        Some(encoded + 1)
    }

    /// Bytes received from the HM-10 UART.
    pub fn on_phone_bytes(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            match self.reader.push_byte(byte) {
                None => {}
                Some(PhoneEvent::Record(record)) => {
                    // Only a connected phone's data reaches the UART.
                    self.connected = true;
                    if telemetry::module_record::is_module_payload(record) {
                        self.to_module.push(record);
                    } else if telemetry::crsf_record::is_crsf_payload(record) {
                        // Only the radio's line speaks for the device tool.
                        self.bad_frames_from_phone = self.bad_frames_from_phone.saturating_add(1);
                    } else {
                        self.to_flight.push(record);
                    }
                }
                Some(PhoneEvent::Connected) => self.connected = true,
                Some(PhoneEvent::Disconnected) => {
                    self.connected = false;
                    self.to_phone.clear();
                }
                Some(PhoneEvent::Malformed(_) | PhoneEvent::Overlong) => {
                    self.bad_frames_from_phone = self.bad_frames_from_phone.saturating_add(1);
                }
            }
        }
    }

    /// The next record from the phone for the flight side into `out` (≥ [`MAX_RECORD_LEN`]).
    pub fn next_record_to_flight(&mut self, out: &mut [u8]) -> Option<usize> {
        self.to_flight.pop_into(out).ok().flatten()
    }

    /// The next module-addressed record from the phone into `out` (≥ [`MAX_RECORD_LEN`]).
    pub fn next_record_to_module(&mut self, out: &mut [u8]) -> Option<usize> {
        self.to_module.pop_into(out).ok().flatten()
    }
}

#[cfg(test)]
#[path = "relay_tests.rs"]
mod tests;
