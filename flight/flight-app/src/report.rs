//! The flight side of the telemetry stream: what the loop, the battery monitor, the baro and
//! the link follower know becomes `telemetry::messages` (attitude, battery, cell count,
//! barometric altitude and vario, link statistics, flight mode, arm/failsafe state,
//! system-identification results), one message per call in rotation ([`ROTATION`]) so a slow
//! downlink still carries every kind; and setting changes arriving from the module are
//! checked against the parameter table and echoed back.
//!
//! Setting values on the wire (`SettingChange::value`, "the setting's own fixed-point unit"):
//! whole numbers and choices as themselves, real numbers as their IEEE-754 bits — exact for
//! every range in the table (1e-9 … 1e9 do not fit one decimal fixed point).

use telemetry::messages::{
    ArmState, Attitude, Axis, Battery, Cells, LinkStats, Message, SettingChange, SysIdResult,
    Vertical,
};

use crate::battery::BatteryStatus;
use crate::pipeline::LoopOutput;
use crate::settings::{PARAMS, Param, ParamError, Settings, Value};
use crate::supervisor::ArmBlocker;
use crate::sysid::ekf::Identification;

/// What the flight side's link end sees.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkSeen {
    /// Uplink RSSI at the flight side, dBm.
    pub rssi_dbm: i8,
    /// Uplink LQ, %.
    pub lq_percent: u8,
    /// The module's report of the downlink (RSSI dBm, LQ %), if it sent one.
    pub downlink: Option<(i8, u8)>,
    /// Rate mode wire code.
    pub rate_mode: u8,
    /// Valid packets received.
    pub received: u32,
    /// Expected packets missed.
    pub missed: u32,
    /// Failsafe events since boot.
    pub failsafes: u16,
}

/// Everything one report may draw on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    /// The loop's latest output.
    pub out: LoopOutput,
    /// The latest battery reading.
    pub battery: Option<BatteryStatus>,
    /// The link as the flight side sees it.
    pub link: LinkSeen,
    /// Why arming would be refused now (see [`blocker_bit`]).
    pub arming_blockers: u16,
    /// A fresh identification result to send once.
    pub sysid: Option<SysIdResult>,
    /// Barometric altitude above the power-up point, m (`ClimbRate::altitude_m`), once the
    /// baro has read.
    pub altitude_m: Option<f32>,
    /// Vertical speed, m/s up (`FlightLoop::climb_estimate`), once the estimator has one.
    pub climb_mps: Option<f32>,
}

/// The bit of an arming blocker in `ArmState::arming_blockers`.
pub const fn blocker_bit(b: ArmBlocker) -> u16 {
    match b {
        ArmBlocker::LinkDown => 1,
        ArmBlocker::ThrottleNotLow => 2,
        ArmBlocker::SensorsUnhealthy => 4,
        ArmBlocker::GainsNotReady => 8,
        ArmBlocker::BatteryCritical => 16,
        ArmBlocker::SettingsProblem => 32,
        ArmBlocker::UsbConnected => 64,
    }
}

fn centidegrees(deg: f32) -> i16 {
    (deg * 100.0).clamp(-18_000.0, 18_000.0) as i16
}

/// Message kinds in rotation order: attitude every other message (the phone's horizon),
/// altitude and vario twice per pass (a vario tone wants updates more often than the
/// battery), everything else once. At the link task's ceiling of one message per
/// `app::REPORT_PERIOD_US` (50 /s) that is attitude 25 /s, vertical 7.1 /s, arm state,
/// battery, link statistics, flight mode and cell count 3.6 /s each; a kind with nothing to
/// say (no baro, no battery reading yet) gives its slot to the next one. State changes
/// (arming, failsafe, mode) go out of turn anyway.
pub const ROTATION: [Kind; 14] = [
    Kind::Attitude,
    Kind::ArmState,
    Kind::Attitude,
    Kind::Vertical,
    Kind::Attitude,
    Kind::Battery,
    Kind::Attitude,
    Kind::LinkStats,
    Kind::Attitude,
    Kind::Vertical,
    Kind::Attitude,
    Kind::FlightMode,
    Kind::Attitude,
    Kind::Cells,
];

/// A kind of message in the [`ROTATION`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `Message::Attitude`.
    Attitude,
    /// `Message::ArmState`.
    ArmState,
    /// `Message::Battery`.
    Battery,
    /// `Message::LinkStats`.
    LinkStats,
    /// `Message::FlightMode`.
    FlightMode,
    /// `Message::Vertical` (baro altitude and vario).
    Vertical,
    /// `Message::Cells` (the battery monitor's cell count).
    Cells,
}

/// Picks the next message to send.
#[derive(Debug, Clone, Copy, Default)]
pub struct Reporter {
    position: usize,
}

impl Reporter {
    /// Starts with attitude.
    pub const fn new() -> Self {
        Self { position: 0 }
    }

    /// The next message. A pending identification result goes first (the caller clears it
    /// after sending); a state change (arming, failsafe, mode) is the caller's cue to send
    /// [`Reporter::state`] out of turn.
    pub fn next(&mut self, snap: &Snapshot) -> Message {
        if let Some(r) = snap.sysid {
            return Message::SysIdResult(r);
        }
        loop {
            let kind = ROTATION
                .get(self.position)
                .copied()
                .unwrap_or(Kind::Attitude);
            self.position = (self.position + 1) % ROTATION.len();
            if let Some(m) = Self::message(kind, snap) {
                return m;
            }
        }
    }

    /// The arm/failsafe state message.
    pub fn state(snap: &Snapshot) -> Message {
        Message::ArmState(ArmState {
            armed: snap.out.armed,
            failsafe: snap.out.failsafe,
            arming_blockers: snap.arming_blockers,
        })
    }

    fn message(kind: Kind, snap: &Snapshot) -> Option<Message> {
        Some(match kind {
            Kind::Attitude => {
                let [r, p, y] = snap.out.attitude.deg();
                Message::Attitude(Attitude {
                    roll_cdeg: centidegrees(r),
                    pitch_cdeg: centidegrees(p),
                    yaw_cdeg: centidegrees(y),
                })
            }
            Kind::ArmState => Self::state(snap),
            Kind::Battery => {
                let b = snap.battery?;
                Message::Battery(Battery {
                    voltage_mv: u16::try_from(b.voltage_mv).unwrap_or(u16::MAX),
                    current_ca: i16::try_from(b.current_ma / 10).unwrap_or(i16::MAX),
                    used_mah: u16::try_from(b.consumed_mah).unwrap_or(u16::MAX),
                    // No capacity setting yet: remaining charge unknown.
                    remaining_percent: 0,
                })
            }
            Kind::LinkStats => {
                let l = &snap.link;
                let (down_rssi, down_lq) = l.downlink.unwrap_or((0, 0));
                Message::LinkStats(LinkStats {
                    uplink_rssi_dbm: l.rssi_dbm,
                    uplink_lq: l.lq_percent,
                    downlink_rssi_dbm: down_rssi,
                    downlink_lq: down_lq,
                    rate_mode: l.rate_mode,
                    received: l.received,
                    missed: l.missed,
                    failsafes: l.failsafes,
                })
            }
            // The mode flown is the mode reported: one type, no mapping.
            Kind::FlightMode => Message::FlightMode(snap.out.mode),
            Kind::Vertical => vertical_message(snap.altitude_m?, snap.climb_mps?),
            Kind::Cells => return cells_message(&snap.battery?),
        })
    }
}

/// Barometric altitude (m above the power-up point, e.g. `ClimbRate::altitude_m`) and
/// vertical speed (m/s up, e.g. `FlightLoop::climb_estimate`) as a message; when to send it
/// is the caller's cadence.
pub fn vertical_message(altitude_m: f32, climb_mps: f32) -> Message {
    let cm = |m: f32, limit: f32| {
        if m.is_finite() {
            libm::roundf(m * 100.0).clamp(-limit, limit)
        } else {
            0.0
        }
    };
    Message::Vertical(Vertical {
        altitude_cm: cm(altitude_m, 2.0e9) as i32,
        vario_cm_s: cm(climb_mps, f32::from(i16::MAX)) as i16,
    })
}

/// The flight battery's cell count as a message, once the monitor knows it.
pub fn cells_message(battery: &BatteryStatus) -> Option<Message> {
    (battery.cells > 0).then_some(Message::Cells(Cells {
        count: battery.cells,
    }))
}

/// The identification result of one axis as a message.
pub fn sysid_message(axis: Axis, beta1: f32, beta2: f32, tau_s: f32, noise: f32) -> SysIdResult {
    SysIdResult {
        axis,
        beta1,
        beta2,
        tau_s,
        noise,
    }
}

/// An identification as three messages (roll, pitch, yaw): β1 = e^(ln β), β2 = 0 (the EKF
/// models none), the shared τ, and the residual variance (RMS gyro innovation²).
pub fn sysid_messages(id: &Identification) -> [SysIdResult; 3] {
    let [lr, lp, ly] = id.ln_beta;
    let [nr, np, ny] = id.gyro_noise_dps;
    [
        (Axis::Roll, lr, nr),
        (Axis::Pitch, lp, np),
        (Axis::Yaw, ly, ny),
    ]
    .map(|(axis, ln_beta, noise)| {
        sysid_message(axis, libm::expf(ln_beta), 0.0, id.tau_s, noise * noise)
    })
}

fn to_wire(value: Value) -> i32 {
    match value {
        Value::F32(v) => v.to_bits() as i32,
        Value::U32(v) => i32::try_from(v).unwrap_or(i32::MAX),
    }
}

fn from_wire(param: &Param, value: i32) -> Result<Value, ParamError> {
    Ok(param.from_bits(value as u32)?)
}

/// Applies a change from the module (`id` = index in the parameter table). Returns the
/// report to echo: the new value, or the unchanged current one if the change was refused.
pub fn apply_setting(
    settings: &mut Settings,
    change: SettingChange,
) -> (Result<(), ParamError>, Option<SettingChange>) {
    let Some(param) = PARAMS.get(usize::from(change.id)) else {
        return (Err(ParamError::Unknown), None);
    };
    let result = from_wire(param, change.value).and_then(|v| settings.set(param.name, v));
    let echo = settings.by_name(param.name).map(|v| SettingChange {
        id: change.id,
        value: to_wire(v),
    });
    (result, echo)
}

/// The report of setting `id`'s current value.
pub fn setting_report(settings: &Settings, id: u16) -> Option<SettingChange> {
    let param = PARAMS.get(usize::from(id))?;
    let value = settings.by_name(param.name)?;
    Some(SettingChange {
        id,
        value: to_wire(value),
    })
}

/// The wire value for a real-number setting (module side and tests).
pub fn f32_value(v: f32) -> i32 {
    to_wire(Value::F32(v))
}

#[cfg(test)]
mod tests;
