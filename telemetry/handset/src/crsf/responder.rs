//! The module's side of the half-duplex JR line (sans-IO): after each radio frame it decides
//! what to send in the reply window — DEVICE_INFO for a ping, the 0x3A timing frame that pulls
//! the radio onto the link's packet rate, and rotating telemetry (ExpressLRS/EdgeTX).

use heapless::String;

use super::device::{DeviceInfo, TimingCorrection};
use super::frame::{Error, Frame, address, frame_type};
use super::message::Message;
use super::params::{CHUNK_HEADER_LEN, MAX_CHUNK_DATA, ParameterChunk};
use super::sensors::{
    Attitude, BaroAltitude, Battery, FlightModeFrame, Gps, LinkStatistics, Vario,
};
use crate::report::HandsetTelemetry;

/// EdgeTX's receive buffer for one burst (`TELEMETRY_RX_PACKET_SIZE`).
pub const MAX_REPLY_BYTES: usize = 128;
/// Serial number we report. Anything but "ELRS": EdgeTX would enable ExpressLRS-only
/// features for that.
pub const TAULINK_SERIAL: [u8; 4] = *b"TAUL";
/// Hardware id we report (RFM22B module on nRF52840, revision 1).
pub const TAULINK_HARDWARE_ID: u32 = 0x0000_2201;
/// Device name we report.
pub const TAULINK_NAME: &str = "TauLink";

/// Our DEVICE_INFO reply to the radio for firmware `major.minor.patch`.
pub fn taulink_device_info(major: u8, minor: u8, patch: u8) -> DeviceInfo {
    DeviceInfo {
        destination: address::RADIO,
        origin: address::TX_MODULE,
        // Kept default: a 7-byte constant in the name's 32-byte string cannot fail.
        name: String::try_from(TAULINK_NAME).unwrap_or_default(),
        serial: TAULINK_SERIAL,
        hardware_id: TAULINK_HARDWARE_ID,
        firmware_id: u32::from_be_bytes([0, major, minor, patch]),
        parameter_count: 0,
        parameter_protocol_version: 0,
    }
}

/// How long before the link latches an uplink's channels the radio's channel frame should
/// have ended: EdgeTX's frames leave ±50 µs around their tick (its mixer run), and the
/// module needs some tens of µs to parse one; ExpressLRS keeps 100 µs
/// (`OpenTXsyncOffsetSafeMargin`). Every µs of it is a µs of stick latency (it was 1 ms:
/// taulink-sim measured F700's synced p99 at 3.5 ms with it, issue 17).
pub const DEFAULT_TIMING_LEAD_US: u32 = 200;

/// Reply timing and rates.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Config {
    /// Line speed, for the reply budget.
    pub baud: u32,
    /// What we answer to a ping.
    pub device_info: DeviceInfo,
    /// LINK_STATISTICS period (EdgeTX needs ≥ 2–5 Hz; 1 s timeout).
    pub link_statistics_interval_us: u32,
    /// Period of each other sensor frame.
    pub sensor_interval_us: u32,
    /// Period of the timing frame (ExpressLRS: 200 ms).
    pub timing_interval_us: u32,
    /// How long before an air packet the radio's channel frame should have arrived.
    pub timing_lead_us: u32,
}

impl Config {
    /// Defaults for `baud`: 10 Hz link statistics, 5 Hz sensors, 5 Hz timing, 200 µs lead.
    pub fn new(baud: u32, device_info: DeviceInfo) -> Self {
        Self {
            baud,
            device_info,
            link_statistics_interval_us: 100_000,
            sensor_interval_us: 200_000,
            timing_interval_us: 200_000,
            timing_lead_us: DEFAULT_TIMING_LEAD_US,
        }
    }

    /// EdgeTX's frame period before any timing frame.
    pub fn default_radio_period_us(&self) -> u32 {
        match self.baud {
            0..=115_200 => 16_000,
            115_201..=400_000 => 4_000,
            _ => 2_000,
        }
    }

    /// Shortest period we ask the radio for: 5 ms at ≤ 115 200 Bd, 2 ms faster (ExpressLRS'
    /// half-duplex minimums).
    pub fn min_radio_period_us(&self) -> u32 {
        if self.baud <= 115_200 { 5_000 } else { 2_000 }
    }
}

/// When the link sends its air packets: at `phase_us + k · period_us`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkSchedule {
    /// Air packet period.
    pub period_us: u32,
    /// Time of any one air packet.
    pub phase_us: u64,
}

/// Telemetry kinds after LINK_STATISTICS, in rotation order.
const SENSORS: [u8; 6] = [
    frame_type::BATTERY_SENSOR,
    frame_type::ATTITUDE,
    frame_type::VARIO,
    frame_type::FLIGHT_MODE,
    frame_type::BARO_ALTITUDE,
    frame_type::GPS,
];

/// The reply state machine.
#[derive(Debug, Clone)]
pub struct Responder {
    config: Config,
    /// A ping addressed to us waits for its DEVICE_INFO.
    ping_pending: bool,
    /// A radio frame ended and we have not used its reply window yet: `(end time, length)`.
    window: Option<(u64, usize)>,
    /// End time of the previous radio frame, for the measured period.
    last_frame_us: Option<u64>,
    radio_period_us: u32,
    /// End time of the last channel frame, the phase the timing frame corrects.
    last_channels_us: Option<u64>,
    schedule: Option<LinkSchedule>,
    last_timing_us: Option<u64>,
    last_link_statistics_us: Option<u64>,
    last_sensor_us: [Option<u64>; SENSORS.len()],
    next_sensor: usize,
    model_id: Option<u8>,
    /// A parameter chunk waiting for a reply window.
    parameter_chunk: Option<ParameterChunk>,
}

impl Responder {
    /// A responder that has heard nothing yet.
    pub fn new(config: Config) -> Self {
        let radio_period_us = config.default_radio_period_us();
        Self {
            config,
            ping_pending: false,
            window: None,
            last_frame_us: None,
            radio_period_us,
            last_channels_us: None,
            schedule: None,
            last_timing_us: None,
            last_link_statistics_us: None,
            last_sensor_us: [None; SENSORS.len()],
            next_sensor: 0,
            model_id: None,
            parameter_chunk: None,
        }
    }

    /// Model id from the radio's last model-select command.
    pub fn model_id(&self) -> Option<u8> {
        self.model_id
    }

    /// The radio's frame period as last measured (or EdgeTX's default before that).
    pub fn radio_period_us(&self) -> u32 {
        self.radio_period_us
    }

    /// Sends `chunk` (a parameter description piece, or a command's new status) in the next
    /// reply window, ahead of telemetry; a newer one replaces one not yet sent (the radio
    /// asks again on its timeout).
    pub fn queue_parameter_chunk(&mut self, chunk: ParameterChunk) {
        self.parameter_chunk = Some(chunk);
    }

    /// Whether a parameter chunk still waits for a window.
    pub fn parameter_chunk_pending(&self) -> bool {
        self.parameter_chunk.is_some()
    }

    /// Data bytes per parameter chunk: what fits one reply window at the shortest radio
    /// period we ask for, after a full RC channel frame (26 bytes) on the line, so a chunk
    /// never waits for a longer window. 35 bytes at 400 kBd (2 ms), 16 at 115 200 Bd (5 ms).
    pub fn parameter_chunk_len(&self) -> usize {
        const RC_FRAME_LEN: usize = 26;
        const FRAME_OVERHEAD: usize = 4;
        let line_bytes =
            u64::from(self.config.baud) * u64::from(self.config.min_radio_period_us()) * 87
                / (10 * 100 * 1_000_000);
        usize::try_from(line_bytes)
            .unwrap_or(usize::MAX)
            .min(MAX_REPLY_BYTES)
            .saturating_sub(RC_FRAME_LEN + FRAME_OVERHEAD + CHUNK_HEADER_LEN)
            .clamp(1, MAX_CHUNK_DATA)
    }

    /// Sets (or clears) the air schedule the radio should follow.
    pub fn set_link_schedule(&mut self, schedule: Option<LinkSchedule>) {
        self.schedule = schedule.filter(|s| s.period_us > 0);
    }

    /// A checked frame from the radio ended at `now_us`. Opens the reply window and returns
    /// the decoded message (channels, ping, model select) for the caller.
    pub fn on_frame(&mut self, now_us: u64, frame: &Frame) -> Option<Message> {
        if let Some(previous) = self.last_frame_us {
            let period = now_us.saturating_sub(previous);
            // Gaps longer than EdgeTX's slowest period are outages, not periods.
            if (500..=50_000).contains(&period) {
                self.radio_period_us = period as u32;
            }
        }
        self.last_frame_us = Some(now_us);
        self.window = Some((now_us, frame.wire_len()));
        let message = Message::from_frame(frame).ok()?;
        match &message {
            Message::RcChannels(_) => self.last_channels_us = Some(now_us),
            Message::DevicePing(ping) => {
                if matches!(ping.destination, address::BROADCAST | address::TX_MODULE) {
                    self.ping_pending = true;
                }
            }
            Message::ModelSelect(command) => self.model_id = Some(command.model_id),
            _ => {}
        }
        Some(message)
    }

    /// Bytes we may send in one window: ExpressLRS' rule `baud/10 · period · 0.87`, minus the
    /// radio's own frame (which shares the line), capped at EdgeTX's 128-byte buffer.
    pub fn reply_budget(&self, radio_frame_len: usize) -> usize {
        let line_bytes = u64::from(self.config.baud) * u64::from(self.radio_period_us) * 87
            / (10 * 100 * 1_000_000);
        let budget = usize::try_from(line_bytes).unwrap_or(usize::MAX);
        budget.saturating_sub(radio_frame_len).min(MAX_REPLY_BYTES)
    }

    /// Fills `out` with whole frames for the reply window opened by the last radio frame and
    /// returns them (empty: stay silent — no window, window missed, or nothing due). Send
    /// them as one burst right away; EdgeTX reads a burst on its UART idle interrupt.
    ///
    /// # Errors
    /// [`Error::BufferTooSmall`] if the frames written overran `out` (ruled out by the
    /// writer; the caller sends nothing rather than a cut frame).
    pub fn reply<'o>(
        &mut self,
        now_us: u64,
        telemetry: &HandsetTelemetry,
        out: &'o mut [u8],
    ) -> Result<&'o [u8], Error> {
        let Some((frame_end_us, radio_frame_len)) = self.window.take() else {
            return Ok(&[]);
        };
        // Starting later than half a period risks colliding with the radio's next frame on
        // the shared wire (the budget assumes we start right after its frame).
        if now_us.saturating_sub(frame_end_us) > u64::from(self.radio_period_us / 2) {
            return Ok(&[]);
        }
        let budget = self.reply_budget(radio_frame_len).min(out.len());
        if self.ping_pending {
            // EdgeTX ≥ 2.11 sends no channels until it has our DEVICE_INFO, so the answer goes
            // out even if the window is short; it then has the window to itself.
            let info = Message::DeviceInfo(self.config.device_info.clone());
            let fits = info
                .to_frame(address::FLIGHT_CONTROLLER)
                .is_ok_and(|frame| frame.wire_len() <= budget);
            let limit = if fits {
                budget
            } else {
                out.len().min(MAX_REPLY_BYTES)
            };
            let mut writer = Writer::new(out, limit);
            if writer.put(&info) {
                self.ping_pending = false;
            }
            if !fits {
                return writer.into_written();
            }
            return self.fill(now_us, telemetry, writer);
        }
        self.fill(now_us, telemetry, Writer::new(out, budget))
    }

    /// Adds what is due after a possible DEVICE_INFO: a parameter chunk, timing, link
    /// statistics, sensors.
    fn fill<'o>(
        &mut self,
        now_us: u64,
        telemetry: &HandsetTelemetry,
        mut writer: Writer<'o>,
    ) -> Result<&'o [u8], Error> {
        if let Some(chunk) = self.parameter_chunk.take()
            && !writer.put(&Message::ParameterChunk(chunk.clone()))
        {
            self.parameter_chunk = Some(chunk);
        }
        if self.timing_due(now_us)
            && let Some(timing) = self.timing_correction()
            && writer.put(&Message::TimingCorrection(timing))
        {
            self.last_timing_us = Some(now_us);
        }
        if due(
            self.last_link_statistics_us,
            now_us,
            self.config.link_statistics_interval_us,
        ) {
            // No link: LQ 0 tells EdgeTX "telemetry lost" at once instead of after 1 s (the
            // all-zero default is the report, deliberately).
            let stats = telemetry
                .link
                .as_ref()
                .map(LinkStatistics::from)
                .unwrap_or_default();
            if writer.put(&Message::LinkStatistics(stats)) {
                self.last_link_statistics_us = Some(now_us);
            }
        }
        if telemetry.link_streaming() {
            self.rotate_sensors(now_us, telemetry, &mut writer);
        }
        writer.into_written()
    }

    /// One pass over the sensors from where the last window stopped; sends every due one that
    /// is available and fits.
    fn rotate_sensors(&mut self, now_us: u64, telemetry: &HandsetTelemetry, writer: &mut Writer) {
        let start = self.next_sensor;
        for step in 0..SENSORS.len() {
            let index = (start + step) % SENSORS.len();
            let Some(last) = self.last_sensor_us.get(index).copied() else {
                continue;
            };
            if !due(last, now_us, self.config.sensor_interval_us) {
                continue;
            }
            let message = match SENSORS.get(index).copied() {
                Some(frame_type::BATTERY_SENSOR) => telemetry
                    .battery
                    .as_ref()
                    .map(|b| Message::Battery(Battery::from(b))),
                Some(frame_type::ATTITUDE) => telemetry
                    .attitude
                    .as_ref()
                    .map(|a| Message::Attitude(Attitude::from(a))),
                Some(frame_type::FLIGHT_MODE) => telemetry
                    .flight_mode_shown()
                    .as_ref()
                    .map(|m| Message::FlightMode(FlightModeFrame::from(m))),
                Some(frame_type::GPS) => telemetry.gps.as_ref().map(|g| Message::Gps(Gps::from(g))),
                Some(frame_type::VARIO) => telemetry.vertical.map(|v| {
                    Message::Vario(Vario {
                        vertical_speed_cm_s: v.vario_cm_s,
                    })
                }),
                Some(frame_type::BARO_ALTITUDE) => telemetry
                    .vertical
                    .map(|v| Message::BaroAltitude(BaroAltitude::from_cm(v.altitude_cm))),
                _ => None,
            };
            if let Some(message) = message
                && writer.put(&message)
            {
                if let Some(slot) = self.last_sensor_us.get_mut(index) {
                    *slot = Some(now_us);
                }
                self.next_sensor = (index + 1) % SENSORS.len();
            }
        }
    }

    fn timing_due(&self, now_us: u64) -> bool {
        self.schedule.is_some()
            && self.last_channels_us.is_some()
            && due(self.last_timing_us, now_us, self.config.timing_interval_us)
    }

    /// The timing frame for the current schedule and the last channel frame's arrival.
    pub fn timing_correction(&self) -> Option<TimingCorrection> {
        let schedule = self.schedule?;
        let arrival_us = self.last_channels_us?;
        let period = i64::from(schedule.period_us);
        // Ask for a whole multiple of the air period that the line can carry.
        let multiple = self
            .config
            .min_radio_period_us()
            .div_ceil(schedule.period_us)
            .max(1);
        let interval_us = schedule.period_us.saturating_mul(multiple).min(50_000);
        // Desired arrivals are `lead` before each air packet; the offset is how early the
        // radio's frame was, wrapped into [−P/2, P/2) (positive = early, EdgeTX delays).
        let desired = schedule.phase_us as i64 - i64::from(self.config.timing_lead_us);
        let error = (desired - arrival_us as i64).rem_euclid(period);
        let offset_us = if error >= period / 2 + period % 2 {
            error - period
        } else {
            error
        };
        Some(TimingCorrection {
            destination: address::RADIO,
            origin: address::TX_MODULE,
            interval_100ns: interval_us.saturating_mul(10),
            offset_100ns: i32::try_from(offset_us * 10).unwrap_or(0),
        })
    }
}

fn due(last_us: Option<u64>, now_us: u64, interval_us: u32) -> bool {
    last_us.is_none_or(|last| now_us.saturating_sub(last) >= u64::from(interval_us))
}

/// Appends whole frames to the reply buffer; a frame that does not fit is left out.
struct Writer<'a> {
    out: &'a mut [u8],
    used: usize,
    /// Bytes the window allows (at most `out.len()`).
    limit: usize,
}

impl<'a> Writer<'a> {
    fn new(out: &'a mut [u8], limit: usize) -> Self {
        let limit = limit.min(out.len());
        Self {
            out,
            used: 0,
            limit,
        }
    }

    /// True if `message` was written. Module → radio frames start with 0xC8 (as ExpressLRS
    /// sends them; EdgeTX accepts 0xC8 and 0xEA).
    fn put(&mut self, message: &Message) -> bool {
        let Some(free) = self.out.get_mut(self.used..self.limit) else {
            return false;
        };
        match message.encode(address::FLIGHT_CONTROLLER, free) {
            Ok(written) => {
                self.used += written.len();
                true
            }
            Err(_) => false,
        }
    }

    /// The whole frames written, in order.
    fn into_written(self) -> Result<&'a [u8], Error> {
        let used = self.used;
        let out: &'a [u8] = self.out;
        out.get(..used)
            .ok_or(Error::BufferTooSmall { needed: used })
    }
}
