//! The magnetometer calibration session behind the console's `magcal` (disarmed only):
//! while it collects, the IMU's raw magnetometer readings are kept in a bounded buffer —
//! one whenever the reading has turned noticeably since the last kept one, so a frame left
//! still does not fill it — and `estimation::magcal::fit` turns them into a calibration,
//! checked (sample count, a rotation out of one plane, coverage of orientations, the
//! seed's "round circle" residual) before `magcal save` stores it in the settings
//! (`mag.offset_*`, `mag.xx`…`mag.yz`). The stored calibration is applied to every reading
//! the estimator gets ([`calibration`]).

use heapless::Vec;

use crate::estimation::magcal::{MagCalConfig, MagCalError, MagCalibration, fit};
use crate::settings::{ParamError, Settings, handles};

/// Readings kept at most (≈ 30 s of turning; 12 bytes each).
pub const CAPACITY: usize = 300;
/// At most one reading kept per this long, ms.
pub const MIN_INTERVAL_MS: u32 = 50;
/// A reading is kept only if it differs from the last kept one by this fraction of its
/// size (≈ 1.1° of turn): a still frame adds nothing.
pub const MIN_CHANGE: f32 = 0.02;

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
