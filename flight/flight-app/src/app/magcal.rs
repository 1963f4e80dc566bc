//! The magnetometer calibration session behind the console's `magcal` (disarmed only):
//! while it collects, the IMU's raw magnetometer readings are kept in a bounded buffer —
//! one whenever the reading has turned noticeably since the last kept one, so a frame left
//! still does not fill it — and `estimation::magcal::fit` turns them into a calibration,
//! checked (sample count, a rotation out of one plane, coverage of orientations, the
//! seed's "round circle" residual) before `magcal save` stores it in the settings
//! (`mag.offset_*`, `mag.xx`…`mag.yz`). The stored calibration is applied to every reading
//! the estimator gets ([`calibration`]).
//!
//! Without a computer, the same session runs from the sticks ([`MagcalGesture`]): disarmed,
//! with the link up, throttle low, yaw centred and the roll/pitch stick in its forward-left
//! corner (nose down, roll left) held for [`GESTURE_HOLD_MS`] starts collecting; the same
//! gesture again fits, checks and stores it. Tones confirm each step
//! (`alerts::Alert::MagcalStarted`, `MagcalStored`, `MagcalRefused`). It cannot be made in
//! flight: it counts only while disarmed (arming also ends a session), and a throttle-low
//! corner with yaw centred is neither arm gesture.

use heapless::Vec;

use crate::alerts::Alert;
use crate::estimation::magcal::{MagCalConfig, MagCalError, MagCalibration, fit};
use crate::settings::{ParamError, Settings, handles};
use crate::supervisor::Sticks;

/// Readings kept at most (≈ 30 s of turning; 12 bytes each).
pub const CAPACITY: usize = 300;
/// At most one reading kept per this long, ms.
pub const MIN_INTERVAL_MS: u32 = 50;
/// A reading is kept only if it differs from the last kept one by this fraction of its
/// size (≈ 1.1° of turn): a still frame adds nothing.
pub const MIN_CHANGE: f32 = 0.02;

/// How long the stick gesture is held, ms (twice the arm gesture's: deliberate).
pub const GESTURE_HOLD_MS: u32 = 2_000;

/// The calibration's stick gesture: throttle low, yaw centred, roll full left and pitch
/// full forward (nose down), held for [`GESTURE_HOLD_MS`]; fires once per hold.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MagcalGesture {
    since_ms: Option<u32>,
    fired: bool,
}

impl MagcalGesture {
    /// Whether `sticks` are in the gesture's position.
    pub fn position(sticks: &Sticks) -> bool {
        sticks.throttle_low() && sticks.yaw.abs() < 0.3 && sticks.roll < -0.9 && sticks.pitch < -0.9
    }

    /// One sample; `sticks` is `None` while the gesture may not count (armed, link down),
    /// which also restarts the hold. True when the gesture completes.
    pub fn update(&mut self, now_ms: u32, sticks: Option<&Sticks>) -> bool {
        if !sticks.is_some_and(Self::position) {
            *self = Self::default();
            return false;
        }
        let since = *self.since_ms.get_or_insert(now_ms);
        if !self.fired && now_ms.wrapping_sub(since) >= GESTURE_HOLD_MS {
            self.fired = true;
            return true;
        }
        false
    }
}

/// Why a calibration was not stored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StoreRefused {
    /// No session is collecting.
    NotStarted,
    /// The readings fail a check.
    Fit(MagCalError),
    /// A value is outside its parameter's range.
    Param(ParamError),
}

impl core::fmt::Display for StoreRefused {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotStarted => f.write_str("magcal start first"),
            Self::Fit(e) => write!(f, "{e}"),
            Self::Param(e) => write!(f, "{e}"),
        }
    }
}

/// The session's state.
#[derive(Debug, Clone, Default)]
pub struct MagcalSession {
    collecting: bool,
    samples: Vec<[f32; 3], CAPACITY>,
    last_kept_ms: Option<u32>,
}

fn norm2([x, y, z]: [f32; 3]) -> f32 {
    x * x + y * y + z * z
}

impl MagcalSession {
    /// Starts collecting from nothing.
    pub fn start(&mut self) {
        *self = Self {
            collecting: true,
            ..Self::default()
        };
    }

    /// Stops and drops the readings.
    pub fn cancel(&mut self) {
        *self = Self::default();
    }

    /// Whether readings are being collected.
    pub fn collecting(&self) -> bool {
        self.collecting
    }

    /// Readings kept so far.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Whether the buffer is full (collecting goes on without keeping more).
    pub fn is_full(&self) -> bool {
        self.samples.is_full()
    }

    /// A raw magnetometer reading at `now_ms`.
    pub fn offer(&mut self, now_ms: u32, raw: [f32; 3]) {
        if !self.collecting || raw.iter().any(|v| !v.is_finite()) {
            return;
        }
        if self
            .last_kept_ms
            .is_some_and(|t| now_ms.wrapping_sub(t) < MIN_INTERVAL_MS)
        {
            return;
        }
        if let Some(&last) = self.samples.last() {
            let [a, b, c] = last;
            let [x, y, z] = raw;
            let change = norm2([x - a, y - b, z - c]);
            if change < MIN_CHANGE * MIN_CHANGE * norm2(last) {
                return;
            }
        }
        if self.samples.push(raw).is_ok() {
            self.last_kept_ms = Some(now_ms);
        }
    }

    /// The fit of the readings kept, checked with the default limits.
    ///
    /// # Errors
    /// The first check the readings fail.
    pub fn fit(&self) -> Result<MagCalibration, MagCalError> {
        fit(&self.samples, &MagCalConfig::default())
    }
}

/// The calibration the settings hold (factory: zero offset, identity — readings unchanged).
pub fn calibration(settings: &Settings) -> MagCalibration {
    let [ox, oy, oz, xx, yy, zz, xy, xz, yz] = handles::MAG_CALIBRATION.map(|h| settings.get(h));
    MagCalibration {
        offset: [ox, oy, oz],
        matrix: [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]],
        field: 0.0,
        residual_pct: 0.0,
        coverage: 0.0,
    }
}

/// Writes `cal` into `settings` (all or nothing).
///
/// # Errors
/// A value outside its parameter's range (nothing changed).
pub fn store(settings: &mut Settings, cal: &MagCalibration) -> Result<(), ParamError> {
    let [ox, oy, oz] = cal.offset;
    let [[xx, xy, xz], [_, yy, yz], [_, _, zz]] = cal.matrix;
    use handles::*;
    settings.apply(&[
        MAG_OFFSET_X.to(ox),
        MAG_OFFSET_Y.to(oy),
        MAG_OFFSET_Z.to(oz),
        MAG_XX.to(xx),
        MAG_YY.to(yy),
        MAG_ZZ.to(zz),
        MAG_XY.to(xy),
        MAG_XZ.to(xz),
        MAG_YZ.to(yz),
    ])
}

impl super::FlightApp {
    /// Fits the session's readings and, if they pass the checks, stores the calibration in
    /// the live settings, ends the session and asks for a save (the console's `magcal save`
    /// and the second stick gesture).
    ///
    /// # Errors
    /// Why nothing was stored; the session goes on.
    pub(super) fn store_magcal(&mut self) -> Result<MagCalibration, StoreRefused> {
        if !self.magcal.collecting() {
            return Err(StoreRefused::NotStarted);
        }
        let cal = self.magcal.fit().map_err(StoreRefused::Fit)?;
        let mut changed = self.live.clone();
        store(&mut changed, &cal).map_err(StoreRefused::Param)?;
        self.live = changed;
        self.magcal.cancel();
        self.settings_changed();
        self.request_save();
        Ok(cal)
    }

    /// The stick gesture, after each loop: starts a session, or stores the one collecting
    /// (a refused one is dropped: the pilot starts again), with a tone either way.
    pub(super) fn on_magcal_gesture(&mut self, now_ms: u32) {
        let allowed = !self.armed() && self.link_input.up;
        let sticks = allowed.then_some(&self.link_input.sticks);
        if !self.magcal_gesture.update(now_ms, sticks) {
            return;
        }
        let alert = if !self.magcal.collecting() {
            self.magcal.start();
            Alert::MagcalStarted
        } else if self.store_magcal().is_ok() {
            Alert::MagcalStored
        } else {
            self.magcal.cancel();
            Alert::MagcalRefused
        };
        self.player.push(alert);
    }
}
