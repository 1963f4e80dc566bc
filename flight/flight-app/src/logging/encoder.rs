//! Turning recorded entries into ULog: the definitions (header, flag bits, information,
//! formats, every setting as a parameter, subscriptions), then one message per entry and a
//! parameter message for each setting changed since. The encoder is resumable: it writes
//! what fits into the caller's [`Writer`] and continues where it stopped after the caller
//! has moved the bytes on, so any sink — a flash page, a link frame, a file — can drive it
//! with its own buffer of at least [`MIN_BUFFER`] bytes.

use taulink_ulog::{Error, Level, Record, Writer};

use super::topics::{
    Battery, Entry, Estimate, Event, Identification, LinkStats, Motors, SensorBaro, SensorGps,
    SensorImu, Setpoint, Status,
};
use crate::settings::{Settings, Value, handles};
use crate::supervisor::{ArmBlocker, Decision};
use telemetry::settings::{COUNT, MODES};

/// The smallest writer buffer every message fits in (the longest is `sensor_gps`'s
/// format, checked by a test).
pub const MIN_BUFFER: usize = 512;

/// A logged topic: its ULog name and format. Its message id is its index in [`TOPICS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topic {
    /// ULog message name.
    pub name: &'static str,
    /// ULog format string.
    pub format: &'static str,
}

const fn topic<R: Record>() -> Topic {
    Topic {
        name: R::NAME,
        format: R::FORMAT,
    }
}

/// Every topic, in message-id order.
pub const TOPICS: [Topic; 10] = [
    topic::<SensorImu>(),
    topic::<SensorBaro>(),
    topic::<SensorGps>(),
    topic::<Estimate>(),
    topic::<Setpoint>(),
    topic::<Motors>(),
    topic::<Status>(),
    topic::<Battery>(),
    topic::<LinkStats>(),
    topic::<Identification>(),
];

/// The message id of a record type (its index in [`TOPICS`]).
fn id_of<R: Record>() -> u16 {
    TOPICS.iter().position(|t| t.name == R::NAME).unwrap_or(0) as u16
}

/// The ULog parameter name of a setting: the dotted name with `/` for `.` (ULog names
/// allow `a-zA-Z0-9_-/`), written into `out`.
pub fn param_name<'o>(name: &str, out: &'o mut [u8; 48]) -> Option<&'o str> {
    let bytes = name.as_bytes();
    let o = out.get_mut(..bytes.len())?;
    for (o, &b) in o.iter_mut().zip(bytes) {
        *o = if b == b'.' { b'/' } else { b };
    }
    core::str::from_utf8(o).ok()
}

/// Where the definitions stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Header,
    FlagBits,
    Info(u8),
    Formats(u8),
    Params(u8),
    Subscriptions(u8),
    Data,
}

/// The encoder of one log.
#[derive(Debug, Clone)]
pub struct Encoder {
    phase: Phase,
    start_us: u64,
    /// The board, for `ver_hw`.
    board: &'static str,
    /// Each setting's bits as last logged.
    logged: [u32; COUNT],
    /// An entry taken from the source that did not fit the last buffer.
    pending: Option<Entry>,
}

fn write_param(w: &mut Writer, name: &str, value: Value) -> Result<usize, Error> {
    let mut buf = [0u8; 48];
    let name = param_name(name, &mut buf).ok_or(Error::InvalidText)?;
    match value {
        Value::F32(v) => w.param_f32(name, v),
        // ULog parameters are int32_t or float: whole numbers travel as their bits.
        Value::U32(v) => w.param_i32(name, v as i32),
    }
}

impl Encoder {
    /// An encoder for a log whose time starts at `start_us`, written on `board`.
    pub fn new(start_us: u64, board: &'static str) -> Self {
        Self {
            phase: Phase::Header,
            start_us,
            board,
            logged: [0; COUNT],
            pending: None,
        }
    }

    /// The definitions are written: entries may follow.
    pub fn ready(&self) -> bool {
        self.phase == Phase::Data
    }

    /// Writes what fits of the definitions, `settings` as the initial parameters. `true`
    /// once they are all written.
    pub fn definitions(&mut self, w: &mut Writer, settings: &Settings) -> bool {
        while self.phase != Phase::Data {
            match self.definition(w, settings) {
                Err(Error::Full) => return false,
                // A message this encoder cannot write is left out; the log stays readable.
                Ok(_) | Err(_) => self.phase = self.next_phase(),
            }
        }
        true
    }

    fn definition(&mut self, w: &mut Writer, settings: &Settings) -> Result<usize, Error> {
        match self.phase {
            Phase::Header => w.header(self.start_us),
            Phase::FlagBits => w.flag_bits(),
            Phase::Info(0) => w.info_str("sys_name", "TauLink"),
            Phase::Info(1) => w.info_str("ver_hw", self.board),
            Phase::Info(2) => w.info_str("ver_sw", env!("CARGO_PKG_VERSION")),
            Phase::Info(_) => {
                let profile = settings.get(handles::LOG_PROFILE);
                w.info_str("log_type", super::Profile::from_index(profile).name())
            }
            Phase::Formats(i) => match TOPICS.get(usize::from(i)) {
                Some(t) => w.format(t.format),
                None => Ok(0),
            },
            Phase::Params(i) => {
                let Some((p, v)) = settings.iter().nth(usize::from(i)) else {
                    return Ok(0);
                };
                let n = write_param(w, p.name, v)?;
                if let Some(slot) = self.logged.get_mut(usize::from(i)) {
                    *slot = v.to_bits();
                }
                Ok(n)
            }
            Phase::Subscriptions(i) => match TOPICS.get(usize::from(i)) {
                Some(t) => w.subscribe(0, u16::from(i), t.name),
                None => Ok(0),
            },
            Phase::Data => Ok(0),
        }
    }

    fn next_phase(&self) -> Phase {
        let topics = TOPICS.len() as u8;
        match self.phase {
            Phase::Header => Phase::FlagBits,
            Phase::FlagBits => Phase::Info(0),
            Phase::Info(i) if i < 3 => Phase::Info(i + 1),
            Phase::Info(_) => Phase::Formats(0),
            Phase::Formats(i) if i + 1 < topics => Phase::Formats(i + 1),
            Phase::Formats(_) => Phase::Params(0),
            Phase::Params(i) if usize::from(i) + 1 < COUNT => Phase::Params(i + 1),
            Phase::Params(_) => Phase::Subscriptions(0),
            Phase::Subscriptions(i) if i + 1 < topics => Phase::Subscriptions(i + 1),
            Phase::Subscriptions(_) | Phase::Data => Phase::Data,
        }
    }

    /// Writes into `w` what is due — the rest of the definitions, parameter changes, then
    /// entries taken from `source` — until `w` is full or `source` runs dry. `true`: `w` is
    /// full, move its bytes on and call again; `false`: everything is written.
    pub fn feed(
        &mut self,
        w: &mut Writer,
        settings: &Settings,
        mut source: impl FnMut() -> Option<Entry>,
    ) -> bool {
        if !self.definitions(w, settings) || self.parameter_changes(w, settings).is_err() {
            return true;
        }
        loop {
            let Some(entry) = self.pending.take().or_else(&mut source) else {
                return false;
            };
            match self.entry(w, &entry) {
                // Larger than an empty buffer: never writable here, dropped.
                Err(Error::Full) if w.is_empty() => {}
                Err(Error::Full) => {
                    self.pending = Some(entry);
                    return true;
                }
                Ok(_) | Err(_) => {}
            }
        }
    }

    /// Writes one entry (after the definitions).
    ///
    /// # Errors
    /// [`Error::Full`]: nothing was written, flush and try again.
    pub fn entry(&mut self, w: &mut Writer, entry: &Entry) -> Result<usize, Error> {
        match entry {
            Entry::Imu(r) => w.data(id_of::<SensorImu>(), r),
            Entry::Baro(r) => w.data(id_of::<SensorBaro>(), r),
            Entry::Gps(r) => w.data(id_of::<SensorGps>(), r),
            Entry::Estimate(r) => {
                let mut r = *r;
                let [_, _, yaw] = &mut r.euler_deg;
                *yaw = yaw_deg(r.q);
                w.data(id_of::<Estimate>(), &r)
            }
            Entry::Setpoint(r) => w.data(id_of::<Setpoint>(), r),
            Entry::Motors(r) => w.data(id_of::<Motors>(), r),
            Entry::Status(r) => w.data(id_of::<Status>(), r),
            Entry::Battery(r) => w.data(id_of::<Battery>(), r),
            Entry::Link(r) => w.data(id_of::<LinkStats>(), r),
            Entry::Identification(r) => w.data(id_of::<Identification>(), r),
            Entry::Event(t, e) => event(w, *t, *e),
            Entry::Dropout(_, ms) => w.dropout(*ms),
        }
    }

    /// Writes a parameter message for each setting whose value differs from the one last
    /// logged (a change made in flight or on the ground while logging).
    ///
    /// # Errors
    /// [`Error::Full`]: the changes not yet written are written by the next call.
    pub fn parameter_changes(&mut self, w: &mut Writer, settings: &Settings) -> Result<(), Error> {
        for ((p, v), logged) in settings.iter().zip(self.logged.iter_mut()) {
            if v.to_bits() != *logged {
                write_param(w, p.name, v)?;
                *logged = v.to_bits();
            }
        }
        Ok(())
    }
}

/// Yaw of a body → NED quaternion, deg.
fn yaw_deg([w, x, y, z]: [f32; 4]) -> f32 {
    libm::atan2f(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)).to_degrees()
}

fn event(w: &mut Writer, t: u64, e: Event) -> Result<usize, Error> {
    let (level, parts): (Level, [&str; 2]) = match e {
        Event::Decision(d) => match decision_text(d) {
            Some(x) => x,
            None => return Ok(0),
        },
        Event::Mode(m) => (
            Level::Notice,
            [
                "mode ",
                MODES.get(usize::from(m.id())).copied().unwrap_or("?"),
            ],
        ),
        Event::EstimatorFallback => (
            Level::Warning,
            ["INS diverged: ", "the complementary filter flies"],
        ),
        Event::LoopRestarted => (Level::Info, ["new setup installed: ", "loop restarted"]),
        Event::ImuFault => (Level::Error, ["IMU fault: ", "riding through"]),
    };
    w.logging_parts(level, t, &parts)
}

fn decision_text(d: Decision) -> Option<(Level, [&'static str; 2])> {
    Some(match d {
        Decision::Steady => return None,
        Decision::Armed => (Level::Notice, ["armed", ""]),
        Decision::ArmRefused(b) => (
            Level::Warning,
            [
                "arm refused: ",
                match b {
                    ArmBlocker::LinkDown => "link down",
                    ArmBlocker::ThrottleNotLow => "throttle not low",
                    ArmBlocker::SensorsUnhealthy => "sensors unhealthy",
                    ArmBlocker::GainsNotReady => "gains not ready",
                    ArmBlocker::BatteryCritical => "battery critical",
                    ArmBlocker::SettingsProblem => "settings problem",
                    ArmBlocker::UsbConnected => "USB connected",
                },
            ],
        ),
        Decision::DisarmedByPilot => (Level::Notice, ["disarmed: ", "by the pilot"]),
        Decision::DisarmedIdle => (Level::Notice, ["disarmed: ", "idle on the ground"]),
        Decision::DisarmedFailsafe => (Level::Warning, ["disarmed: ", "failsafe touchdown"]),
        Decision::DisarmedLastResort => (Level::Critical, ["disarmed: ", "failsafe last resort"]),
        Decision::FailsafeEntered => (Level::Critical, ["link failsafe", ""]),
        Decision::ControlRecovered => (Level::Notice, ["link back: ", "pilot in control"]),
        Decision::DisarmedSensorFault => (Level::Critical, ["disarmed: ", "IMU fault"]),
        Decision::Resumed => (
            Level::Critical,
            ["armed again: ", "flight resumed after a reset"],
        ),
    })
}
