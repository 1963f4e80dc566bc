//! The handset side of the JR line, built on `taulink_handset`: the CRSF decoder and
//! reply responder (CRSF input), the S.Port push scheduler and the FrSky D hub sender (PPM
//! input), chosen from the settings. Implements [`HandsetOutput`] for the module core.
//!
//! Line settings the firmware applies (CRSF spec and EdgeTX `radio/src/telemetry/crossfire.h`
//! for CRSF; EdgeTX `radio/src/pulses/ppm.cpp` and `telemetry/telemetry.cpp` for S.Port and
//! FrSky D): CRSF 400 kBd, not inverted,
//! half duplex; S.Port 57 600 Bd inverted, push only; FrSky D 9600 Bd inverted, push only.

pub mod state;

use taulink_handset::crsf::responder::{Config, LinkSchedule, Responder, taulink_device_info};
use taulink_handset::crsf::{Decoded, Decoder, Message};
use taulink_handset::frsky_d::Sender;
use taulink_handset::frsky_d::hub::SenderConfig;
use taulink_handset::sport::Scheduler;
use taulink_handset::sport::schedule::Config as SportConfig;

use heapless::Deque;
use taulink_handset::crsf::address;
use taulink_handset::crsf::params::ParameterChunk;

use crate::channels::ChannelFrame;
use crate::ports::{HandsetOutput, HandsetRequest, LinkStats, TagFailures};
use crate::settings::{InputProtocol, OutputProtocol, Role, Settings};
pub use state::FlightState;

/// CRSF line rate (EdgeTX's default, 400 kBd).
pub const CRSF_BAUD: u32 = 400_000;
/// The fastest CRSF rate the settings offer (`InputProtocol::Crsf921600`).
pub const CRSF_FAST_BAUD: u32 = 921_600;
/// The UARTE's fastest rate: EdgeTX's 1.87 MBd and above cannot be offered.
pub const UARTE_MAX_BAUD: u32 = 1_000_000;

/// The nRF52840 UARTE BAUDRATE register value for `baud`: Nordic's named preset where there
/// is one (115 200, 921 600, 1 M), else `baud · 2³² / 16 MHz` rounded to a multiple of 0x1000
/// (which reproduces the 115 200 preset, not the 921 600 one: at that rate the product
/// specification lists the preset's real rate as 941 176 Bd, so the register is not linear
/// there). `None` above the UARTE's 1 MBd.
///
/// | CRSF rate | register | rate on the line |
/// |---|---|---|
/// | 115 200 | 0x01D7_E000 (the preset) | 115 108 Bd (−0.08 %, PS table) |
/// | 400 000 | 0x0666_6000 (custom) | ≈ 399 994 Bd by the formula (−0.002 %); to be checked on a scope |
/// | 921 600 | 0x0EBE_D000 (the preset) | 941 176 Bd (+2.1 %, PS table): within a UART's tolerance only if the radio's side is exact; unverified on hardware |
/// | 1 870 000 | — | beyond the UARTE (max 1 MBd) |
pub const fn uarte_baudrate(baud: u32) -> Option<u32> {
    match baud {
        0 => return None,
        115_200 => return Some(0x01D7_E000),
        921_600 => return Some(0x0EBE_D000),
        1_000_000 => return Some(0x1000_0000),
        b if b > UARTE_MAX_BAUD => return None,
        _ => {}
    }
    let bits = ((baud as u64) << 32) / 16_000_000;
    Some(((bits + 0x800) as u32) & 0xFFFF_F000)
}

/// The slower CRSF rate the settings offer (`InputProtocol::Crsf115200`).
pub const CRSF_SLOW_BAUD: u32 = 115_200;
/// S.Port push rate.
pub const SPORT_BAUD: u32 = 57_600;
/// FrSky D rate.
pub const FRSKY_D_BAUD: u32 = 9_600;
/// Largest burst [`HandsetOutput::next_line_bytes`] writes (EdgeTX's CRSF receive buffer).
pub const MAX_LINE_BURST: usize = taulink_handset::crsf::responder::MAX_REPLY_BYTES;

/// How the JR line is driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineMode {
    /// CRSF, half duplex, not inverted.
    Crsf {
        /// Line rate.
        baud: u32,
    },
    /// Inverted, transmit-only pushes (S.Port or FrSky D).
    Push {
        /// Line rate.
        baud: u32,
    },
    /// Nothing on the line.
    Off,
}

/// The encoder in use.
#[derive(Debug)]
// One instance for the firmware's lifetime and no heap to box into; `allow`, not `expect`:
// on the 32-bit target the variants are close enough that the lint stays quiet.
#[allow(clippy::large_enum_variant)]
enum Protocol {
    /// CRSF input and telemetry.
    Crsf {
        decoder: Decoder,
        responder: Responder,
        baud: u32,
    },
    /// S.Port push (PPM input).
    SPort(Scheduler),
    /// FrSky D hub (PPM input).
    FrskyD(Sender),
    /// No telemetry to the handset.
    Off,
}

/// The handset codecs for the settings in force.
#[derive(Debug)]
pub struct Handset {
    protocol: Protocol,
    state: FlightState,
    /// Parameter reads/writes and bind commands waiting for the core.
    requests: Deque<HandsetRequest, REQUESTS>,
    /// Radio frames the CRSF decoder rejected.
    pub crsf_rejected: u32,
}

/// Requests held between two core polls (the radio sends one per frame period).
const REQUESTS: usize = 4;

impl Handset {
    /// The codec the settings call for: CRSF input always answers in CRSF (EdgeTX needs the
    /// DEVICE_INFO and LINK_STATISTICS); PPM input pushes S.Port or FrSky D; the receiver
    /// role has no handset.
    pub fn new(settings: &Settings) -> Self {
        let protocol = match (settings.role, settings.input, settings.output) {
            (Role::Receiver, _, _) => Protocol::Off,
            (
                Role::Transmitter,
                input @ (InputProtocol::Crsf
                | InputProtocol::Crsf115200
                | InputProtocol::Crsf921600),
                _,
            ) => {
                let baud = input.crsf_baud().unwrap_or(CRSF_BAUD);
                let mut info = taulink_device_info(0, 1, 0);
                info.parameter_count = crate::params::PARAMETER_COUNT;
                Protocol::Crsf {
                    decoder: Decoder::new(),
                    // The responder sizes its reply window from the line rate.
                    responder: Responder::new(Config::new(baud, info)),
                    baud,
                }
            }
            (Role::Transmitter, InputProtocol::Ppm, OutputProtocol::SPort) => {
                Protocol::SPort(Scheduler::new(SportConfig::default()))
            }
            (Role::Transmitter, InputProtocol::Ppm, OutputProtocol::FrskyHub) => {
                Protocol::FrskyD(Sender::new(SenderConfig::default()))
            }
            (Role::Transmitter, InputProtocol::Ppm, OutputProtocol::Off | OutputProtocol::Crsf) => {
                Protocol::Off
            }
        };
        Self {
            protocol,
            state: FlightState::new(settings.tx_power),
            requests: Deque::new(),
            crsf_rejected: 0,
        }
    }

    /// How the firmware drives the line.
    pub fn line_mode(&self) -> LineMode {
        match self.protocol {
            Protocol::Crsf { baud, .. } => LineMode::Crsf { baud },
            Protocol::SPort(_) => LineMode::Push { baud: SPORT_BAUD },
            Protocol::FrskyD(_) => LineMode::Push { baud: FRSKY_D_BAUD },
            Protocol::Off => LineMode::Off,
        }
    }

    /// What the handset is told.
    pub fn state(&self) -> &FlightState {
        &self.state
    }

    fn take_frames(
        feed: impl Iterator<Item = Decoded>,
        responder: &mut Responder,
        requests: &mut Deque<HandsetRequest, REQUESTS>,
        rejected: &mut u32,
        now_us: u64,
    ) -> Option<ChannelFrame> {
        let mut channels = None;
        for decoded in feed {
            match decoded {
                Decoded::Frame(frame) => {
                    let request = match responder.on_frame(now_us, &frame) {
                        Some(Message::RcChannels(rc)) => {
                            channels = Some(ChannelFrame::from_ticks(&rc.ticks));
                            None
                        }
                        Some(Message::ParameterRead(read)) if for_us(read.destination) => {
                            Some(HandsetRequest::Read {
                                origin: read.origin,
                                number: read.number,
                                chunk: read.chunk,
                            })
                        }
                        Some(Message::ParameterWrite(write)) if for_us(write.destination) => {
                            Some(HandsetRequest::Write {
                                origin: write.origin,
                                number: write.number,
                                value: write.value,
                            })
                        }
                        Some(Message::Bind(bind)) if for_us(bind.destination) => {
                            Some(HandsetRequest::Bind)
                        }
                        _ => None,
                    };
                    // Full: the radio repeats an unanswered request on its timeout.
                    if let Some(request) = request {
                        let _ = requests.push_back(request);
                    }
                }
                Decoded::Rejected(_) => *rejected = rejected.saturating_add(1),
            }
        }
        channels
    }
}

impl HandsetOutput for Handset {
    fn on_telemetry(&mut self, record: &[u8]) {
        self.state.on_record(record);
    }

    fn on_module_battery(&mut self, millivolts: u16) {
        self.state.on_module_battery(millivolts);
    }

    fn on_tag_failures(&mut self, failures: TagFailures) {
        self.state.on_tag_failures(failures);
    }

    fn on_link_stats(&mut self, stats: &LinkStats) {
        self.state.on_link_stats(stats);
        if let Protocol::Crsf { responder, .. } = &mut self.protocol {
            responder.set_link_schedule(stats.schedule.map(|s| LinkSchedule {
                period_us: s.period_us,
                phase_us: s.phase_us,
            }));
        }
    }

    fn on_line_bytes(&mut self, now_us: u64, bytes: &[u8]) -> Option<ChannelFrame> {
        match &mut self.protocol {
            Protocol::Crsf {
                decoder, responder, ..
            } => Self::take_frames(
                decoder.feed(bytes),
                responder,
                &mut self.requests,
                &mut self.crsf_rejected,
                now_us,
            ),
            // Push modes only send (a PPM-mode radio does not poll).
            Protocol::SPort(_) | Protocol::FrskyD(_) | Protocol::Off => None,
        }
    }

    fn on_line_idle(&mut self, now_us: u64) -> Option<ChannelFrame> {
        match &mut self.protocol {
            Protocol::Crsf {
                decoder, responder, ..
            } => Self::take_frames(
                decoder.idle(),
                responder,
                &mut self.requests,
                &mut self.crsf_rejected,
                now_us,
            ),
            Protocol::SPort(_) | Protocol::FrskyD(_) | Protocol::Off => None,
        }
    }

    fn next_line_bytes<'o>(&mut self, now_us: u64, out: &'o mut [u8]) -> &'o [u8] {
        let report = self.state.report();
        // An encode error (a frame longer than `out`, which callers size for the largest
        // reply) sends nothing this window: the line stays silent rather than carrying a
        // cut frame, and the next window tries again.
        let sent = match &mut self.protocol {
            Protocol::Crsf { responder, .. } => responder.reply(now_us, &report, out).ok(),
            Protocol::SPort(scheduler) => scheduler
                .next_frame(now_us, &report)
                .and_then(|frame| frame.encode(out).ok()),
            Protocol::FrskyD(sender) => sender
                .next_frame(now_us, &report)
                .and_then(|frame| frame.encode(out).ok()),
            Protocol::Off => None,
        };
        // Kept (the decision above): nothing is sent.
        sent.unwrap_or(&[])
    }

    fn take_request(&mut self) -> Option<HandsetRequest> {
        self.requests.pop_front()
    }

    fn parameter_chunk_len(&self) -> usize {
        match &self.protocol {
            Protocol::Crsf { responder, .. } => responder.parameter_chunk_len(),
            _ => taulink_handset::crsf::params::MAX_CHUNK_DATA,
        }
    }

    fn send_parameter_chunk(&mut self, chunk: ParameterChunk) {
        if let Protocol::Crsf { responder, .. } = &mut self.protocol {
            responder.queue_parameter_chunk(chunk);
        }
    }

    fn model_id(&self) -> Option<u8> {
        match &self.protocol {
            Protocol::Crsf { responder, .. } => responder.model_id(),
            _ => None,
        }
    }
}

/// Frames addressed to the module (or to everyone).
fn for_us(destination: u8) -> bool {
    matches!(destination, address::TX_MODULE | address::BROADCAST)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_choose_the_line() {
        let mut settings = Settings::default();
        assert_eq!(
            Handset::new(&settings).line_mode(),
            LineMode::Push { baud: 57_600 }
        );
        settings.output = OutputProtocol::FrskyHub;
        assert_eq!(
            Handset::new(&settings).line_mode(),
            LineMode::Push { baud: 9_600 }
        );
        settings.output = OutputProtocol::Off;
        assert_eq!(Handset::new(&settings).line_mode(), LineMode::Off);
        settings.input = InputProtocol::Crsf;
        assert_eq!(
            Handset::new(&settings).line_mode(),
            LineMode::Crsf { baud: 400_000 }
        );
        settings.input = InputProtocol::Crsf115200;
        assert_eq!(
            Handset::new(&settings).line_mode(),
            LineMode::Crsf { baud: 115_200 }
        );
        settings.input = InputProtocol::Crsf921600;
        assert_eq!(
            Handset::new(&settings).line_mode(),
            LineMode::Crsf { baud: 921_600 }
        );
        settings.role = Role::Receiver;
        assert_eq!(Handset::new(&settings).line_mode(), LineMode::Off);
    }

    #[test]
    fn uarte_registers_for_the_crsf_rates() {
        // nRF52840 PS UARTE BAUDRATE presets: 115 200 and 921 600 are the named values.
        assert_eq!(uarte_baudrate(115_200), Some(0x01D7_E000));
        assert_eq!(uarte_baudrate(921_600), Some(0x0EBE_D000));
        assert_eq!(uarte_baudrate(1_000_000), Some(0x1000_0000));
        assert_eq!(uarte_baudrate(400_000), Some(0x0666_6000));
        assert_eq!(uarte_baudrate(1_870_000), None);
        for input in [
            InputProtocol::Crsf,
            InputProtocol::Crsf115200,
            InputProtocol::Crsf921600,
        ] {
            assert!(uarte_baudrate(input.crsf_baud().unwrap()).is_some());
        }
    }

    #[test]
    fn sport_goes_quiet_between_slots_and_sends_rssi_zero_without_link() {
        let mut handset = Handset::new(&Settings::default());
        let mut out = [0u8; MAX_LINE_BURST];
        let sent = handset.next_line_bytes(0, &mut out);
        // 7E 98 10 01 F1 00 00 00 00 crc: RSSI 0 (no link), nothing stuffed.
        assert_eq!(sent.len(), 10);
        assert_eq!(&sent[..6], &[0x7E, 0x98, 0x10, 0x01, 0xF1, 0x00]);
        assert!(
            handset.next_line_bytes(11_999, &mut out).is_empty(),
            "12 ms slot"
        );
        assert!(!handset.next_line_bytes(100_000, &mut out).is_empty());
    }
}
