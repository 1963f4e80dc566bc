//! The flight controller as a CRSF device (address 0xC8) behind the module: the radio's
//! device tool (ExpressLRS' Lua script on EdgeTX, "Other Devices") lists it and reads and
//! changes its settings through the link. The module relays the radio's frames addressed to
//! 0xC8 (and its broadcast pings) as CRSF records in the uplink stream
//! (`telemetry::crsf_record`); this module answers them from the settings table (the rows:
//! `tree`) with DEVICE_INFO and PARAMETER_SETTINGS_ENTRY chunks, which go down the
//! telemetry stream one at a time ahead of the telemetry rotation — the radio asks for the
//! next chunk when one arrives, so the walk runs at the link's telemetry goodput.
//!
//! **Changes** apply to the live settings at once, like the console's `set`, only while
//! disarmed and only over a keyed link (bound with a phrase: the frames are then
//! authenticated by the link; without a key anyone who knows the bind ID could write). A
//! refused write changes nothing; its row's unit then says why ("refused: armed") and the
//! "Last change" row too. **Save** (with a confirmation) writes them to flash; **Bind**
//! opens the bind window (after its answer is on its way: the link restarts into the bind)
//! without a phrase, so it binds only what `link.unauthenticated` lets through (a keyed
//! bind is the console's `bind PHRASE`);
//! **Magcal** starts a magnetometer calibration (finished from the console or the stick
//! gesture).

pub mod tree;

use heapless::{Deque, String, Vec};
use telemetry::crsf_record::{self, CrsfRecord, MAX_RECORD_PAYLOAD, MAX_RELAYED_CHUNK_DATA};
use telemetry::handset::crsf::device::DeviceInfo;
use telemetry::handset::crsf::frame::{MAX_PAYLOAD_LEN, address, frame_type};
use telemetry::handset::crsf::params::{
    CommandStatus, Entry, MAX_ENTRY_LEN, ParameterChunk, ParameterRead, ParameterWrite,
};
use telemetry::handset::crsf::responder::TAULINK_SERIAL;

use super::FlightApp;
use crate::settings::ParamError;
use tree::View;

/// The name the radio lists the flight controller under.
pub const DEVICE_NAME: &str = "TauLink FC";
/// Hardware id in DEVICE_INFO (the flight controller, not the module's 0x2201).
pub const FC_HARDWARE_ID: u32 = 0x0000_F405;
/// How often the radio polls a running command, 10 ms units.
const POLL_10MS: u8 = 50;

/// What the last change from the radio did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Note {
    /// Applied.
    Set,
    /// Refused: the motors are armed.
    Armed,
    /// Refused: the link is not keyed (no binding phrase), so the write is not authenticated.
    NotAuthenticated,
    /// Refused: out of the setting's range, or the whole set would not run.
    Invalid,
    /// Refused: a read-only row, or a write the row's type cannot carry.
    ReadOnly,
}

impl Note {
    /// The text the rows show.
    pub const fn text(self) -> &'static str {
        match self {
            Note::Set => "set",
            Note::Armed => "refused: armed",
            Note::NotAuthenticated => "refused: no phrase",
            Note::Invalid => "refused: invalid",
            Note::ReadOnly => "refused: read-only",
        }
    }
}

/// A command's state between the radio's steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum SaveStep {
    #[default]
    Idle,
    Confirming,
    Saved,
    Refused(Note),
}

/// The device's state between frames.
#[derive(Debug, Default)]
pub(super) struct DeviceSide {
    /// Records (payloads) for the downlink stream, oldest first.
    replies: Deque<Vec<u8, MAX_RECORD_PAYLOAD>, 2>,
    /// The row the last write named and what it did.
    last: Option<(u8, Note)>,
    save: SaveStep,
    /// How the last Bind / Magcal command ended.
    bind_note: Option<&'static str>,
    magcal_note: Option<&'static str>,
    /// The bind window opens once the Bind answer has left (the link restarts into it).
    bind_after_reply: bool,
    /// This board drives a VTX.
    pub(super) has_vtx: bool,
}

impl FlightApp {
    /// A CRSF record from the uplink stream (the module's relay of the radio's frame).
    pub(super) fn on_crsf_record(&mut self, payload: &[u8]) {
        let Ok(record) = crsf_record::decode(payload) else {
            return;
        };
        let chunk_len = usize::from(record.chunk_limit).clamp(1, MAX_RELAYED_CHUNK_DATA);
        match record.frame_type {
            frame_type::DEVICE_PING => {
                if let [destination, origin, ..] = record.payload
                    && matches!(
                        *destination,
                        address::BROADCAST | address::FLIGHT_CONTROLLER
                    )
                {
                    self.queue_device_info(*origin);
                }
            }
            frame_type::PARAMETER_READ => {
                if let Ok(read) = ParameterRead::from_payload(record.payload)
                    && read.destination == address::FLIGHT_CONTROLLER
                {
                    self.queue_chunk(read.origin, read.number, read.chunk, chunk_len);
                }
            }
            frame_type::PARAMETER_WRITE => {
                if let Ok(write) = ParameterWrite::from_payload(record.payload)
                    && write.destination == address::FLIGHT_CONTROLLER
                {
                    self.on_parameter_write(&write, chunk_len);
                }
            }
            _ => {}
        }
    }

    /// The next reply record for the downlink stream, if one waits; the bind window opens
    /// once the Bind command's answer has been taken.
    pub(super) fn take_device_reply(&mut self) -> Option<Vec<u8, MAX_RECORD_PAYLOAD>> {
        let reply = self.device.replies.pop_front();
        if reply.is_none() && self.device.bind_after_reply {
            self.device.bind_after_reply = false;
            // No phrase travels with the command: the window binds only what
            // `link.unauthenticated` lets through (a keyed bind is the console's
            // `bind PHRASE`).
            self.device.bind_note = Some(match self.request_bind("") {
                Ok(_) => "window open",
                Err(_) => "refused: armed",
            });
        }
        reply
    }

    /// Whether a reply waits (it goes ahead of the telemetry rotation).
    pub(super) fn device_reply_pending(&self) -> bool {
        !self.device.replies.is_empty() || self.device.bind_after_reply
    }

    /// This board has a VTX (the BrushedSparky's firmware says so at boot): its folder and
    /// rows show in the device tool.
    pub fn set_vtx_present(&mut self, present: bool) {
        self.device.has_vtx = present;
    }

    fn queue_device_info(&mut self, destination: u8) {
        let info = DeviceInfo {
            destination,
            origin: address::FLIGHT_CONTROLLER,
            name: String::try_from(DEVICE_NAME).unwrap_or_default(),
            serial: TAULINK_SERIAL,
            hardware_id: FC_HARDWARE_ID,
            firmware_id: 0x0000_0100,
            parameter_count: tree::PARAMETER_COUNT,
            parameter_protocol_version: 0,
        };
        if let Ok(payload) = info.to_payload() {
            self.queue_reply(frame_type::DEVICE_INFO, &payload);
        }
    }

    fn queue_chunk(&mut self, destination: u8, number: u8, chunk: u8, chunk_len: usize) {
        let Some(entry) = self.device_entry(number) else {
            return;
        };
        if let Some(chunk) = ParameterChunk::of_entry(
            &entry,
            chunk_len,
            chunk,
            number,
            destination,
            address::FLIGHT_CONTROLLER,
        ) {
            let payload = chunk.to_payload();
            self.queue_reply(frame_type::PARAMETER_SETTINGS_ENTRY, &payload);
        }
    }

    fn queue_reply(&mut self, frame_type: u8, payload: &[u8]) {
        let mut out = [0u8; MAX_RECORD_PAYLOAD];
        let record = CrsfRecord {
            chunk_limit: 0,
            frame_type,
            payload,
        };
        let Some(bytes) = record.encode(&mut out) else {
            return;
        };
        let Ok(bytes) = Vec::from_slice(bytes) else {
            return;
        };
        if self.device.replies.is_full() {
            // The radio asks one thing at a time and repeats it on its timeout.
            let _ = self.device.replies.pop_front();
        }
        let _ = self.device.replies.push_back(bytes);
    }

    /// Row `number`'s description now.
    fn device_entry(&self, number: u8) -> Option<Vec<u8, MAX_ENTRY_LEN>> {
        let note = self.device.last.map(|(n, note)| (n, note.text()));
        let view = View {
            has_vtx: self.device.has_vtx,
            note,
        };
        if let Some(entry) = tree::entry(number, &self.live, &view) {
            return Some(entry);
        }
        let entry = match number {
            tree::SAVE => {
                let (status, info) = match self.device.save {
                    SaveStep::Confirming => (CommandStatus::ConfirmationNeeded, "Save settings?"),
                    SaveStep::Saved => (CommandStatus::Ready, "Saved"),
                    SaveStep::Refused(note) => (CommandStatus::Ready, note.text()),
                    SaveStep::Idle => (CommandStatus::Ready, ""),
                };
                Entry::command(0, "Save", status, POLL_10MS, info)
            }
            tree::BIND => Entry::command(
                0,
                "Bind",
                CommandStatus::Ready,
                POLL_10MS,
                self.device.bind_note.unwrap_or(""),
            ),
            tree::MAGCAL => Entry::command(
                0,
                "Magcal",
                CommandStatus::Ready,
                POLL_10MS,
                self.device.magcal_note.unwrap_or(""),
            ),
            tree::LAST_CHANGE => {
                let mut text = tree::Text::new();
                if let Some((n, note)) = self.device.last {
                    if let Some((_, param)) = tree::setting(n) {
                        let _ = text.push_str(param.name);
                        let _ = text.push(' ');
                    }
                    let _ = text.push_str(note.text());
                }
                Entry::info(0, "Last change", &text)
            }
            tree::VTX_FREQUENCY => {
                let row = Entry::info(
                    tree::VTX_FOLDER,
                    "vtx frequency",
                    &tree::vtx_frequency_text(&self.live),
                );
                if self.device.has_vtx {
                    row
                } else {
                    row.hidden()
                }
            }
            _ => return None,
        };
        entry.finish().ok()
    }

    /// Why a change from the radio may not be made now, if it may not.
    fn write_refusal(&self) -> Option<Note> {
        if self.armed() {
            Some(Note::Armed)
        } else if self.live.link_key().is_none() {
            Some(Note::NotAuthenticated)
        } else {
            None
        }
    }

    fn on_parameter_write(&mut self, write: &ParameterWrite, chunk_len: usize) {
        let number = write.number;
        if let Some((_, param)) = tree::setting(number) {
            let note = match (
                self.write_refusal(),
                tree::written_value(param, &write.value),
            ) {
                (Some(refusal), _) => refusal,
                (None, None) => Note::ReadOnly,
                (None, Some(value)) => match self.live.set(param.name, value) {
                    Ok(()) => {
                        self.settings_changed();
                        Note::Set
                    }
                    Err(ParamError::OutOfRange | ParamError::Invalid(_)) => Note::Invalid,
                    Err(_) => Note::ReadOnly,
                },
            };
            self.device.last = Some((number, note));
            return;
        }
        let Some(step) = write
            .value
            .first()
            .copied()
            .and_then(CommandStatus::from_byte)
        else {
            return;
        };
        match number {
            tree::SAVE => self.save_step(step),
            tree::BIND if step == CommandStatus::Start => match self.write_refusal() {
                Some(note) => self.device.bind_note = Some(note.text()),
                None => {
                    self.device.bind_note = Some("window opens: bind the module");
                    self.device.bind_after_reply = true;
                }
            },
            tree::MAGCAL if step == CommandStatus::Start => {
                self.device.magcal_note = Some(match self.write_refusal() {
                    Some(note) => note.text(),
                    None => {
                        self.magcal.start();
                        "collecting: turn the frame"
                    }
                });
            }
            tree::BIND | tree::MAGCAL => {}
            _ => return,
        }
        // The radio's popup waits for the command's new status.
        self.queue_chunk(write.origin, number, 0, chunk_len);
    }

    fn save_step(&mut self, step: CommandStatus) {
        self.device.save = match (step, self.device.save) {
            (CommandStatus::Start, _) => match self.write_refusal() {
                Some(note) => SaveStep::Refused(note),
                None => SaveStep::Confirming,
            },
            (CommandStatus::Confirm, SaveStep::Confirming) => match self.write_refusal() {
                Some(note) => SaveStep::Refused(note),
                None => {
                    self.request_save();
                    SaveStep::Saved
                }
            },
            (CommandStatus::Cancel, _) => SaveStep::Idle,
            (_, current) => current,
        };
    }
}

/// The longest CRSF payload a reply carries fits a frame.
const _: () = assert!(crsf_record::MAX_CRSF_PAYLOAD <= MAX_PAYLOAD_LEN);

#[cfg(test)]
mod tests;
