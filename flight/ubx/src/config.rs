//! Boot configuration of the receiver and its acknowledgement. Two generations are
//! supported, because both are on the GPS modules sold for these boards:
//!
//! * **M8** (NEO-M8N, the Tau Labs era): legacy CFG-PRT (UART1 baud, UBX in/out only, which
//!   also silences NMEA), CFG-RATE, CFG-MSG (NAV-PVT every solution), CFG-NAV5 (airborne
//!   dynamic model);
//! * **M9/M10** (the legacy messages are gone on M10): one CFG-VALSET for the baud and one
//!   with the protocol, rate, NAV-PVT output and dynamic model keys, RAM layer only (a
//!   receiver we configure at every boot keeps no surprises in its flash).
//!
//! The baud message is sent first, at the receiver's default baud, and is *not* waited for:
//! its ACK (if any) comes at a baud that is changing. Every other message is sent at the
//! new baud and waits for ACK-ACK; a NAK or too many timeouts stop the sequence and say
//! which message failed. Time is injected (ms), nothing here blocks.

use heapless::Vec;

use super::frame::{self, MAX_FRAME};
use super::{Message, nav_pvt};

/// CFG class.
pub const CLASS_CFG: u8 = 0x06;
/// CFG-PRT id (M8).
pub const ID_PRT: u8 = 0x00;
/// CFG-MSG id (M8).
pub const ID_MSG: u8 = 0x01;
/// CFG-RATE id (M8).
pub const ID_RATE: u8 = 0x08;
/// CFG-NAV5 id (M8).
pub const ID_NAV5: u8 = 0x24;
/// CFG-VALSET id (M9/M10).
pub const ID_VALSET: u8 = 0x8A;

/// CFG-UART1-BAUDRATE (U4).
pub const KEY_UART1_BAUDRATE: u32 = 0x4052_0001;
/// CFG-UART1INPROT-UBX (L).
pub const KEY_UART1INPROT_UBX: u32 = 0x1073_0001;
/// CFG-UART1OUTPROT-UBX (L).
pub const KEY_UART1OUTPROT_UBX: u32 = 0x1074_0001;
/// CFG-UART1OUTPROT-NMEA (L).
pub const KEY_UART1OUTPROT_NMEA: u32 = 0x1074_0002;
/// CFG-RATE-MEAS (U2, ms).
pub const KEY_RATE_MEAS: u32 = 0x3021_0001;
/// CFG-RATE-NAV (U2, measurements per solution).
pub const KEY_RATE_NAV: u32 = 0x3021_0002;
/// CFG-MSGOUT-UBX_NAV_PVT_UART1 (U1, every n solutions).
pub const KEY_MSGOUT_NAV_PVT_UART1: u32 = 0x2091_0007;
/// CFG-NAVSPG-DYNMODEL (E1).
pub const KEY_NAVSPG_DYNMODEL: u32 = 0x2011_0021;

/// Dynamic platform model "airborne < 2 g" (same number in CFG-NAV5 and the key).
pub const DYN_MODEL_AIRBORNE_2G: u8 = 7;

/// Receiver generation (which configuration messages it understands).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Generation {
    /// u-blox 8 (legacy CFG-PRT/MSG/RATE/NAV5).
    M8,
    /// u-blox 9 and 10 (CFG-VALSET keys).
    M9M10,
}

/// What to ask of the receiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// UART1 baud after configuration.
    pub baud: u32,
    /// Measurement period (ms): 100 = 10 Hz, 200 = 5 Hz.
    pub meas_period_ms: u16,
    /// Dynamic platform model.
    pub dyn_model: u8,
}

impl Default for Settings {
    /// 115200 Bd (a 100-byte NAV-PVT at 10 Hz takes 9 % of it), 10 Hz, airborne < 2 g.
    fn default() -> Self {
        Self {
            baud: 115_200,
            meas_period_ms: 100,
            dyn_model: DYN_MODEL_AIRBORNE_2G,
        }
    }
}

/// One encoded frame.
pub type Bytes = Vec<u8, MAX_FRAME>;

/// Every payload here has a fixed-size type far below `MAX_PAYLOAD` (checked when
/// compiling), so no message can come out empty.
fn frame<P: frame::BoundedPayload>(class: u8, id: u8, payload: &P) -> Bytes {
    frame::encode_bounded(class, id, payload)
}

/// The baud-rate message, to be sent at the receiver's current baud (M8 default 9600,
/// M10 default 38400; send it at each candidate).
#[must_use]
pub fn baud_message(generation: Generation, settings: &Settings) -> Bytes {
    match generation {
        Generation::M8 => m8_prt(settings.baud),
        Generation::M9M10 => {
            let mut p: Vec<u8, 16> = Vec::new();
            let _ = p.extend_from_slice(&VALSET_HEADER);
            let _ = p.extend_from_slice(&KEY_UART1_BAUDRATE.to_le_bytes());
            let _ = p.extend_from_slice(&settings.baud.to_le_bytes());
            frame(CLASS_CFG, ID_VALSET, &p)
        }
    }
}

/// CFG-VALSET header: version 0, layers = RAM, 2 reserved bytes.
const VALSET_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// M8 CFG-PRT for UART1: 8N1 at `baud`, UBX in and out only.
fn m8_prt(baud: u32) -> Bytes {
    let mut p = [0u8; 20];
    let mode: u32 = 0x0000_08D0; // 8 data bits, no parity, 1 stop bit
    let fields: [(usize, &[u8]); 5] = [
        (0, &[1]), // portID 1 = UART1
        (4, &mode.to_le_bytes()),
        (8, &baud.to_le_bytes()),
        (12, &1u16.to_le_bytes()), // inProtoMask: UBX
        (14, &1u16.to_le_bytes()), // outProtoMask: UBX (NMEA off)
    ];
    for (at, bytes) in fields {
        for (dst, &src) in p.iter_mut().skip(at).zip(bytes) {
            *dst = src;
        }
    }
    frame(CLASS_CFG, ID_PRT, &p)
}

/// The acknowledged messages, in order, sent at the new baud.
#[must_use]
pub fn acked_messages(generation: Generation, settings: &Settings) -> Vec<Bytes, 4> {
    let mut out = Vec::new();
    match generation {
        Generation::M8 => {
            // CFG-PRT again at the new baud: its ACK proves the port settings took.
            let _ = out.push(m8_prt(settings.baud));
            let mut rate = [0u8; 6];
            let [m0, m1] = settings.meas_period_ms.to_le_bytes();
            rate.copy_from_slice(&[m0, m1, 1, 0, 1, 0]); // navRate 1, timeRef GPS
            let _ = out.push(frame(CLASS_CFG, ID_RATE, &rate));
            let _ = out.push(frame(CLASS_CFG, ID_MSG, &[nav_pvt::CLASS, nav_pvt::ID, 1]));
            let mut nav5 = [0u8; 36];
            nav5.iter_mut()
                .zip([0x01, 0x00, settings.dyn_model]) // mask: dyn only; dynModel
                .for_each(|(d, s)| *d = s);
            let _ = out.push(frame(CLASS_CFG, ID_NAV5, &nav5));
        }
        Generation::M9M10 => {
            let mut p: Vec<u8, 64> = Vec::new();
            let _ = p.extend_from_slice(&VALSET_HEADER);
            let one_byte = [
                (KEY_UART1INPROT_UBX, 1u8),
                (KEY_UART1OUTPROT_UBX, 1),
                (KEY_UART1OUTPROT_NMEA, 0),
                (KEY_MSGOUT_NAV_PVT_UART1, 1),
                (KEY_NAVSPG_DYNMODEL, settings.dyn_model),
            ];
            for (key, value) in one_byte {
                let _ = p.extend_from_slice(&key.to_le_bytes());
                let _ = p.push(value);
            }
            for (key, value) in [(KEY_RATE_MEAS, settings.meas_period_ms), (KEY_RATE_NAV, 1)] {
                let _ = p.extend_from_slice(&key.to_le_bytes());
                let _ = p.extend_from_slice(&value.to_le_bytes());
            }
            let _ = out.push(frame(CLASS_CFG, ID_VALSET, &p));
        }
    }
    out
}

/// Where the boot configuration stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// Waiting for the ACK of message `step` (0-based in [`acked_messages`]).
    Pending {
        /// Index of the message in flight.
        step: u8,
    },
    /// Every message acknowledged.
    Done,
    /// The receiver refused (NAK) this CFG message.
    Refused {
        /// CFG id of the refused message.
        id: u8,
    },
    /// No answer to this CFG message after every retry.
    NoAnswer {
        /// CFG id of the unanswered message.
        id: u8,
    },
}

/// Sends the acknowledged messages one at a time and follows their ACK/NAK.
#[derive(Debug, Clone)]
pub struct Configurator {
    messages: Vec<Bytes, 4>,
    step: usize,
    sent_at_ms: Option<u32>,
    tries: u8,
    status: Status,
}

impl Configurator {
    /// Wait for an ACK this long before sending again (the receiver answers within one
    /// navigation epoch, ≤ 200 ms here).
    pub const TIMEOUT_MS: u32 = 250;
    /// Sends per message before giving up.
    pub const TRIES: u8 = 4;

    /// A configurator for `generation` with `settings`.
    #[must_use]
    pub fn new(generation: Generation, settings: &Settings) -> Self {
        Self {
            messages: acked_messages(generation, settings),
            step: 0,
            sent_at_ms: None,
            tries: 0,
            status: Status::Pending { step: 0 },
        }
    }

    /// Current status.
    #[must_use]
    pub fn status(&self) -> Status {
        self.status
    }

    fn pending_id(&self) -> Option<u8> {
        self.messages.get(self.step)?.get(3).copied()
    }

    /// The frame to write now, if any: the next message, or the current one again after
    /// [`Self::TIMEOUT_MS`] without an answer.
    pub fn poll(&mut self, now_ms: u32) -> Option<&[u8]> {
        if !matches!(self.status, Status::Pending { .. }) {
            return None;
        }
        let due = match self.sent_at_ms {
            None => true,
            Some(t) => now_ms.wrapping_sub(t) >= Self::TIMEOUT_MS,
        };
        if !due {
            return None;
        }
        if self.tries >= Self::TRIES {
            self.status = Status::NoAnswer {
                id: self.pending_id().unwrap_or(0),
            };
            return None;
        }
        self.tries = self.tries.saturating_add(1);
        self.sent_at_ms = Some(now_ms);
        self.messages.get(self.step).map(|m| m.as_slice())
    }

    /// Follows an ACK or NAK; other messages are ignored.
    pub fn on_message(&mut self, message: &Message) {
        let Status::Pending { .. } = self.status else {
            return;
        };
        let Some(pending) = self.pending_id() else {
            return;
        };
        match *message {
            Message::Ack { class, id } if class == CLASS_CFG && id == pending => {
                self.step = self.step.saturating_add(1);
                self.sent_at_ms = None;
                self.tries = 0;
                self.status = if self.step >= self.messages.len() {
                    Status::Done
                } else {
                    Status::Pending {
                        step: u8::try_from(self.step).unwrap_or(u8::MAX),
                    }
                };
            }
            Message::Nak { class, id } if class == CLASS_CFG && id == pending => {
                self.status = Status::Refused { id };
            }
            _ => {}
        }
    }
}
