//! The message set carried in the telemetry stream (both directions) and relayed to a phone:
//! postcard-encoded, then framed ([`crate::framing`]: COBS + CRC-16). Integer units in the
//! names keep the encoding compact (postcard varints) and exact.

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

use crate::framing::{Deframed, Deframer, FramingError, frame, framed_len};

/// Attitude estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Attitude {
    /// Roll, centidegrees (−18000..18000).
    pub roll_cdeg: i16,
    /// Pitch, centidegrees.
    pub pitch_cdeg: i16,
    /// Yaw (heading), centidegrees.
    pub yaw_cdeg: i16,
}

/// Flight battery.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Battery {
    /// Pack voltage, mV.
    pub voltage_mv: u16,
    /// Current, 10 mA units (negative while charging).
    pub current_ca: i16,
    /// Charge used since arming, mAh.
    pub used_mah: u16,
    /// Estimated remaining charge, %.
    pub remaining_percent: u8,
}

/// Link statistics of one end, as it sees them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// RSSI of the uplink at the flight side, dBm.
    pub uplink_rssi_dbm: i8,
    /// Uplink LQ, % of the last 100 expected packets.
    pub uplink_lq: u8,
    /// RSSI of the downlink at the module, dBm.
    pub downlink_rssi_dbm: i8,
    /// Downlink LQ, %.
    pub downlink_lq: u8,
    /// Rate mode wire code (`link::RateMode::code`).
    pub rate_mode: u8,
    /// Valid packets received.
    pub received: u32,
    /// Expected packets missed.
    pub missed: u32,
    /// Failsafe events since boot.
    pub failsafes: u16,
}

/// The flight mode: what the controller flies and what the link reports — one type for both
/// ends, so the mode the quad flies is the mode the handset and the phone show.
///
/// **The variant order is the wire and the settings.** postcard encodes the variant index,
/// and that index is [`FlightMode::id`], the number the flight side's settings store for the
/// mode-switch positions (`mode.switch_low/mid/high`, [`crate::settings::MODES`]
/// in the same order). So stored switch choices keep their meaning and the wire byte is the
/// stable id: new modes are appended, never inserted, reordered or removed (a retired mode
/// keeps its variant). The flight-only policy of each mode (which loops run) lives in
/// `flight_core`, not here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum FlightMode {
    /// Sticks command body rates, PID controller (acro).
    RatePid = 0,
    /// Sticks command body rates, LQG controller.
    RateLqg = 1,
    /// Sticks command roll/pitch angles (self-levelling).
    Attitude = 2,
    /// Attitude near centre, rate at full deflection.
    Horizon = 3,
    /// System identification: the shake excitation on top of rate control.
    SystemId = 4,
    /// Attitude with the altitude held (throttle centred) or climbing at a rate (deflected).
    AltitudeHold = 5,
    /// Altitude hold, and the position held while the roll/pitch sticks are centred (GPS).
    PositionHold = 6,
    /// Altitude hold, and the sticks move the held position at a bounded speed (GPS).
    Loiter = 7,
}

impl FlightMode {
    /// Every mode, in id order.
    pub const ALL: [FlightMode; 8] = [
        FlightMode::RatePid,
        FlightMode::RateLqg,
        FlightMode::Attitude,
        FlightMode::Horizon,
        FlightMode::SystemId,
        FlightMode::AltitudeHold,
        FlightMode::PositionHold,
        FlightMode::Loiter,
    ];

    /// The stable number: the wire's variant index, the stored mode-switch choice, and the
    /// number the handset's numeric sensors show (S.Port DIY 0x5101, FrSky hub Temp1).
    pub const fn id(self) -> u8 {
        self as u8
    }

    /// The mode with stable number `id`, if there is one.
    pub const fn from_id(id: u8) -> Option<FlightMode> {
        Some(match id {
            0 => FlightMode::RatePid,
            1 => FlightMode::RateLqg,
            2 => FlightMode::Attitude,
            3 => FlightMode::Horizon,
            4 => FlightMode::SystemId,
            5 => FlightMode::AltitudeHold,
            6 => FlightMode::PositionHold,
            7 => FlightMode::Loiter,
            _ => return None,
        })
    }

    /// Short name, at most 5 characters in Betaflight/INAV's style (CRSF FLIGHT_MODE as
    /// EdgeTX shows it, the flight console, logs).
    pub const fn name(self) -> &'static str {
        match self {
            FlightMode::RatePid => "RATE",
            FlightMode::RateLqg => "LQG",
            FlightMode::Attitude => "ANGL",
            FlightMode::Horizon => "HOR",
            FlightMode::SystemId => "SYSID",
            FlightMode::AltitudeHold => "ALTH",
            FlightMode::PositionHold => "POSH",
            FlightMode::Loiter => "LOIT",
        }
    }
}

/// Arming and failsafe state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArmState {
    /// Motors armed.
    pub armed: bool,
    /// Radio failsafe active.
    pub failsafe: bool,
    /// Why arming is refused (0 = nothing), a bit set defined by the flight code.
    pub arming_blockers: u16,
}

/// GNSS fix quality.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GpsFix {
    /// No fix.
    None,
    /// 2-D fix.
    Fix2d,
    /// 3-D fix.
    Fix3d,
}

/// GNSS position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gps {
    /// Latitude, 1e-7 degrees.
    pub latitude_e7: i32,
    /// Longitude, 1e-7 degrees.
    pub longitude_e7: i32,
    /// Altitude above mean sea level, cm.
    pub altitude_cm: i32,
    /// Ground speed, cm/s.
    pub ground_speed_cm_s: u16,
    /// Course over ground, centidegrees (0..36000).
    pub course_cdeg: u16,
    /// Satellites used.
    pub satellites: u8,
    /// Fix quality.
    pub fix: GpsFix,
}

/// Body axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// Roll.
    Roll,
    /// Pitch.
    Pitch,
    /// Yaw.
    Yaw,
}

/// Result of a system-identification run on one axis (`flight/flight-core/src/control/LQG.md`
/// §1: ω' = β1·ν + β2·(u − ν), ν' = (u − ν)/τ, with ν the lagged actuator).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SysIdResult {
    /// Axis identified.
    pub axis: Axis,
    /// Actuator gain β1, (deg/s²) per unit of actuator.
    pub beta1: f32,
    /// Lag-free term β2 (0 on roll/pitch; yaw reaction torque), (deg/s²) per unit.
    pub beta2: f32,
    /// Motor time constant τ, s.
    pub tau_s: f32,
    /// Fit quality: variance of the residual.
    pub noise: f32,
}

/// Change one setting (module → flight), or report its value (flight → module).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SettingChange {
    /// Setting identifier: the row's index in the schema, [`crate::settings::PARAMS`].
    pub id: u16,
    /// New value: the row's 32 stored bits (a real as IEEE-754, a whole number or a
    /// choice's index as itself; [`crate::settings::Param::from_bits`] reads it).
    pub value: i32,
}

/// Barometric altitude and vertical speed (the flight side's MS5611 and vertical filter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vertical {
    /// Altitude above the power-up point, cm (up positive).
    pub altitude_cm: i32,
    /// Vertical speed, cm/s (climb positive).
    pub vario_cm_s: i16,
}

/// Cells in series of the flight battery, as the battery monitor detected them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cells {
    /// Cell count (0 = not known yet).
    pub count: u8,
}

/// A setting change from the phone, authenticated (spec §12.5, [`crate::change_auth`]):
/// `tag` is the MAC of the flight side's session, `counter` and the change under the key
/// derived from the link key. The only change from the phone the flight side applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SignedChange {
    /// The change.
    pub change: SettingChange,
    /// Above every counter the flight side accepted in this session.
    pub counter: u32,
    /// SipHash-2-4 tag (`change_auth::ChangeKey::tag`).
    pub tag: [u8; 8],
}

/// Why the flight side refused a change from the phone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RefuseReason {
    /// The motors are armed: no change in flight.
    Armed,
    /// No valid tag (another phrase, a forgery, or no signature at all).
    NotAuthenticated,
    /// The counter is not above the highest accepted (a replay, or a stale session).
    Replayed,
    /// The flight side has no binding phrase: nothing can be authenticated.
    NoPhrase,
    /// Authenticated, but the value is out of range or the set would not run.
    Invalid,
}

/// The flight side's answer to a refused change, with what a fresh one must carry: its
/// session (drawn at boot) and the highest counter accepted so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChangeRefused {
    /// The setting the refused change named.
    pub id: u16,
    /// Why.
    pub reason: RefuseReason,
    /// The flight side's session nonce for this boot.
    pub session: u32,
    /// The highest counter accepted in the session (sign with a greater one).
    pub counter: u32,
}

/// The home: where the flight side's GNSS position is measured from (its first usable fix,
/// or one set explicitly); where a return-to-home would fly to (no mode flies one yet).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Home {
    /// Latitude, 1e-7 degrees.
    pub latitude_e7: i32,
    /// Longitude, 1e-7 degrees.
    pub longitude_e7: i32,
    /// Altitude above mean sea level, cm.
    pub altitude_cm: i32,
    /// Whether a home is set (false: the position fields mean nothing).
    pub set: bool,
}

/// What the flight controller's firmware has to say about itself (flight → ground; sent
/// when it changes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// Flags, the flight code's bit set ([`Health::BARO_FAILED`] …).
    pub flags: u8,
    /// IMU samples the flight loop missed since boot (saturating).
    pub imu_missed: u16,
    /// Flight-loop steps that ran past the next sample since boot (saturating).
    pub loop_overruns: u16,
}

impl Health {
    /// The barometer is declared failed (the hold modes fall back).
    pub const BARO_FAILED: u8 = 1;
    /// The crystal did not start: the clocks run from the internal RC.
    pub const CLOCK_FALLBACK: u8 = 2;
    /// This boot resumed a flight after a reset in the air.
    pub const RESUMED: u8 = 4;
    /// The hardware random generator failed: seeds from a weaker source.
    pub const RNG_FALLBACK: u8 = 8;
    /// A USB host is connected (arming refused).
    pub const USB_CONNECTED: u8 = 16;
}

/// The air link's authentication failures at the flight side (spec §12.2, "Tag failures"):
/// sent when they change, at most once a second; a clean link never sends it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkSecurity {
    /// Uplinks whose tag failed since the flight side started.
    pub tag_failures: u32,
    /// They run above what noise explains (`telemetry::link::alarm`).
    pub alert: bool,
}

/// Everything the telemetry stream carries.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message {
    /// Attitude.
    Attitude(Attitude),
    /// Battery.
    Battery(Battery),
    /// Link statistics.
    LinkStats(LinkStats),
    /// Retired (wire number 3): the six-mode flight mode of the first message set (Rate,
    /// Attitude, AltitudeHold, PositionHold, ReturnToHome, SystemId by index), kept so the
    /// variants after it keep their numbers. Nothing sends it; a reader ignores it (an older
    /// flight side's mode cannot be mapped to [`FlightMode`] without guessing).
    RetiredFlightMode(u8),
    /// Arming / failsafe.
    ArmState(ArmState),
    /// GNSS.
    Gps(Gps),
    /// System identification result.
    SysIdResult(SysIdResult),
    /// Setting change / report.
    SettingChange(SettingChange),
    /// Barometric altitude and vario (appended: earlier variants keep their wire numbers).
    Vertical(Vertical),
    /// Flight battery cell count.
    Cells(Cells),
    /// An authenticated setting change (phone → flight).
    SignedChange(SignedChange),
    /// A refused change, with the session and counter to sign the next one with
    /// (flight → phone).
    ChangeRefused(ChangeRefused),
    /// The home position (flight → ground; appended: earlier variants keep their numbers).
    Home(Home),
    /// The flight mode (flight → ground; wire number 13, replacing the retired number 3: an
    /// older reader drops it as unknown instead of misreading the eight modes).
    FlightMode(FlightMode),
    /// The link's authentication failures at the flight side (flight → module and ground;
    /// appended).
    LinkSecurity(LinkSecurity),
    /// The firmware's health (flight → ground; appended: earlier variants keep their numbers).
    Health(Health),
}

/// Largest postcard encoding of a [`Message`].
pub const MESSAGE_MAX_BYTES: usize = Message::POSTCARD_MAX_SIZE;
/// Largest framed [`Message`].
pub const FRAMED_MAX_BYTES: usize = framed_len(MESSAGE_MAX_BYTES);

/// Encoding a message failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// postcard could not serialise it (cannot happen for these types within the bound).
    Serialize,
    /// The output buffer is too small.
    Framing(FramingError),
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::Serialize => f.write_str("postcard serialisation failed"),
            EncodeError::Framing(e) => write!(f, "framing: {e}"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Encodes and frames `message` into `out`; returns the bytes to put in the stream.
pub fn encode_message<'o>(message: &Message, out: &'o mut [u8]) -> Result<&'o [u8], EncodeError> {
    let mut scratch = [0u8; MESSAGE_MAX_BYTES];
    let payload = postcard::to_slice(message, &mut scratch).map_err(|_| EncodeError::Serialize)?;
    frame(payload, out).map_err(EncodeError::Framing)
}

/// The message a deframed payload holds (`None`: not a message this set knows — another
/// record kind, or a newer protocol's).
pub fn decode_payload(payload: &[u8]) -> Option<Message> {
    postcard::from_bytes::<Message>(payload).ok()
}

/// Wire number of [`Message::SettingChange`].
const SETTING_CHANGE_TAG: u32 = 7;
/// Wire number of [`Message::SignedChange`].
const SIGNED_CHANGE_TAG: u32 = 10;

/// The phone's setting change a deframed payload holds, plain or signed — what
/// [`decode_payload`] reads from such a payload, and `None` for every other message. The
/// flight side acts on nothing else from the phone, and reading the variant's number first
/// keeps the other sixteen variants' decoders out of its image (4 112 B of the Sparky2's
/// flash, measured).
pub fn decode_change(payload: &[u8]) -> Option<Message> {
    // postcard writes an enum's variant as a varint `u32`, which this reads alike.
    let (tag, fields) = postcard::take_from_bytes::<u32>(payload).ok()?;
    match tag {
        SETTING_CHANGE_TAG => postcard::from_bytes(fields)
            .ok()
            .map(Message::SettingChange),
        SIGNED_CHANGE_TAG => postcard::from_bytes(fields).ok().map(Message::SignedChange),
        _ => None,
    }
}

/// What one delimiter in the stream produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Decoded {
    /// A message.
    Message(Message),
    /// A frame was dropped (corrupt, oversize, or not a known message — e.g. from a newer
    /// protocol version).
    Dropped,
}

/// Stream decoder: feed bytes, get messages.
#[derive(Debug, Default)]
pub struct MessageReader {
    deframer: Deframer<FRAMED_MAX_BYTES>,
}

impl MessageReader {
    /// A reader waiting for the first delimiter's frame.
    pub const fn new() -> Self {
        Self {
            deframer: Deframer::new(),
        }
    }

    /// Feeds one byte.
    pub fn push(&mut self, byte: u8) -> Option<Decoded> {
        match self.deframer.push(byte)? {
            Deframed::Frame { .. } => Some(
                match postcard::from_bytes::<Message>(self.deframer.payload()) {
                    Ok(m) => Decoded::Message(m),
                    Err(_) => Decoded::Dropped,
                },
            ),
            Deframed::Overflow | Deframed::Corrupt => Some(Decoded::Dropped),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples() -> [Message; 9] {
        [
            Message::Attitude(Attitude {
                roll_cdeg: -1234,
                pitch_cdeg: 250,
                yaw_cdeg: 17999,
            }),
            Message::Battery(Battery {
                voltage_mv: 16_420,
                current_ca: -150,
                used_mah: 850,
                remaining_percent: 64,
            }),
            Message::LinkStats(LinkStats {
                uplink_rssi_dbm: -87,
                uplink_lq: 98,
                downlink_rssi_dbm: -91,
                downlink_lq: 95,
                rate_mode: 3,
                received: 123_456,
                missed: 789,
                failsafes: 1,
            }),
            Message::FlightMode(FlightMode::AltitudeHold),
            Message::ArmState(ArmState {
                armed: true,
                failsafe: false,
                arming_blockers: 0,
            }),
            Message::Gps(Gps {
                latitude_e7: 473_977_419,
                longitude_e7: 85_455_938,
                altitude_cm: 48_830,
                ground_speed_cm_s: 1_250,
                course_cdeg: 27_000,
                satellites: 14,
                fix: GpsFix::Fix3d,
            }),
            Message::SysIdResult(SysIdResult {
                axis: Axis::Pitch,
                beta1: 10.7,
                beta2: 6.2,
                tau_s: 0.042,
                noise: 0.01,
            }),
            Message::SettingChange(SettingChange { id: 42, value: -7 }),
            Message::Home(Home {
                latitude_e7: -338_568_100,
                longitude_e7: 1_512_152_970,
                altitude_cm: -1_250,
                set: true,
            }),
        ]
    }

    #[test]
    fn every_message_round_trips_through_the_stream() {
        let mut stream = Vec::new();
        for m in samples() {
            let mut buf = [0u8; FRAMED_MAX_BYTES];
            let n = encode_message(&m, &mut buf).unwrap().len();
            assert!(n <= FRAMED_MAX_BYTES);
            stream.extend_from_slice(&buf[..n]);
        }
        let mut reader = MessageReader::new();
        let got: Vec<_> = stream.iter().filter_map(|&b| reader.push(b)).collect();
        let want: Vec<_> = samples().into_iter().map(Decoded::Message).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn a_change_is_read_alike_by_decode_change_and_nothing_else_is() {
        let signed = Message::SignedChange(SignedChange {
            change: SettingChange {
                id: 300,
                value: i32::MIN,
            },
            counter: u32::MAX,
            tag: [1, 2, 3, 4, 5, 6, 7, 0xFF],
        });
        let mut payloads: Vec<Vec<u8>> = Vec::new();
        for m in samples().into_iter().chain([signed]) {
            let mut buf = [0u8; MESSAGE_MAX_BYTES];
            let bytes = postcard::to_slice(&m, &mut buf).unwrap().to_vec();
            // Whole, cut short, with a byte more, and every byte flipped in turn.
            for n in 0..=bytes.len() {
                payloads.push(bytes[..n].to_vec());
            }
            payloads.push([bytes.as_slice(), &[0x80]].concat());
            for i in 0..bytes.len() {
                for flip in [0x01, 0x80, 0xFF] {
                    let mut b = bytes.clone();
                    b[i] ^= flip;
                    payloads.push(b);
                }
            }
        }
        // Every two-byte payload, and non-canonical varint numbers of both changes.
        payloads.extend((0..=u16::MAX).map(|v| v.to_le_bytes().to_vec()));
        payloads.push(vec![0x87, 0x00, 0x01, 0x02]);
        payloads.push(vec![
            0x8A, 0x80, 0x00, 0x01, 0x02, 0x03, 0, 0, 0, 0, 0, 0, 0, 0,
        ]);
        let mut changes = 0;
        for p in &payloads {
            let want = decode_payload(p)
                .filter(|m| matches!(m, Message::SettingChange(_) | Message::SignedChange(_)));
            changes += usize::from(want.is_some());
            assert_eq!(decode_change(p), want, "{p:02x?}");
        }
        assert!(changes > 20, "{changes} changes among the payloads");
    }

    #[test]
    fn sizes_are_compact() {
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        // Tag 0, three zig-zag varints of 2–3 bytes, CRC 2, COBS 1, delimiter 1.
        let n = encode_message(&samples()[0], &mut buf).unwrap().len();
        assert_eq!(n, 1 + 2 + 2 + 3 + 2 + 1 + 1);
        // Largest: GPS, tag + 3 × i32 varint (5) + 2 × u16 (3) + u8 + fix tag.
        assert_eq!(MESSAGE_MAX_BYTES, 24);
    }

    #[test]
    fn home_keeps_the_wire_number_after_every_earlier_variant() {
        let m = Message::Home(Home {
            latitude_e7: 1,
            longitude_e7: -1,
            altitude_cm: 2,
            set: true,
        });
        let mut buf = [0u8; MESSAGE_MAX_BYTES];
        let bytes = postcard::to_slice(&m, &mut buf).unwrap();
        // Tag 12 (after ChangeRefused = 11), zig-zag 1, -1, 2, then true.
        assert_eq!(bytes, &[12, 2, 1, 4, 1]);
    }

    #[test]
    fn a_flight_mode_is_its_stable_id_on_the_wire() {
        for (id, mode) in (0u8..).zip(FlightMode::ALL) {
            assert_eq!(mode.id(), id);
            assert_eq!(FlightMode::from_id(id), Some(mode));
            let mut buf = [0u8; MESSAGE_MAX_BYTES];
            assert_eq!(postcard::to_slice(&mode, &mut buf).unwrap(), &[id]);
            // Message number 13 (after Home = 12), then the mode's id.
            let bytes = postcard::to_slice(&Message::FlightMode(mode), &mut buf).unwrap();
            assert_eq!(bytes, &[13, id]);
        }
        assert_eq!(FlightMode::from_id(8), None);
        assert!(postcard::from_bytes::<FlightMode>(&[8]).is_err());
    }

    #[test]
    fn an_older_flight_sides_mode_is_read_as_retired_not_as_a_mode() {
        // The first message set sent Attitude as [3, 1]; today 1 would be RateLqg.
        assert_eq!(
            postcard::from_bytes::<Message>(&[3, 1]).unwrap(),
            Message::RetiredFlightMode(1)
        );
    }

    #[test]
    fn a_damaged_frame_is_dropped_and_the_next_one_read() {
        let mut a = [0u8; FRAMED_MAX_BYTES];
        let n = encode_message(&samples()[1], &mut a).unwrap().len();
        let mut reader = MessageReader::new();
        let mut out = Vec::new();
        for (i, &b) in a[..n].iter().chain(&a[..n]).enumerate() {
            let b = if i == 2 { b ^ 0x01 } else { b };
            out.extend(reader.push(b));
        }
        assert_eq!(out, vec![Decoded::Dropped, Decoded::Message(samples()[1])]);
    }
}
