//! From the receiver to the INS: [`GpsAiding`] turns a UBX NAV-PVT into the filter's GPS
//! measurement — NED position relative to a home (the first usable fix unless set), NED
//! velocity, and the receiver's own accuracies (hAcc, vAcc, sAcc) as measurement noise —
//! and compensates its latency.
//!
//! **Latency.** A fix describes the vehicle some tens of milliseconds before its last byte
//! arrives (measurement, solution, serial transfer). Fusing it as "now" pulls the estimate
//! back along the path. Instead the estimate's own history is kept (one entry per
//! [`HISTORY_STEP_US`], bounded), and the measurement is moved forward by what the
//! estimate itself did since the fix's time: z_now = z + (x_now − x(t_fix)). This is the
//! delayed-state form of time-stamped fusion; it needs no filter re-run and costs two
//! vector subtractions per fix.
//!
//! Cost (m4count, `tests/m4-bench` `gps`): one [`GpsAiding::fuse`] of a usable fix —
//! checks, NED from home, compensation, three position and three velocity rows — is 8,100
//! Cortex-M4 instructions.

use heapless::Deque;
use ubx::NavPvt;

use super::{Aided, Ins};
use crate::Error;
use crate::ins::State;

/// Spacing of the estimate history (µs).
pub const HISTORY_STEP_US: u64 = 10_000;
/// History length: 64 × 10 ms covers latencies up to 630 ms.
pub const HISTORY_LEN: usize = 64;

/// Mean WGS-84 radius used for the local flat-earth NED frame (m); within 0.3 % of the true
/// radii at any latitude, 3 m per km of travel at worst.
const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// 1e-7 degree in radians.
const DEG_E7_TO_RAD: f64 = core::f64::consts::PI / 180.0 * 1e-7;

/// Tuning of the GPS aiding.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GpsAidingConfig {
    /// Time from the fix's epoch to its arrival (µs); 0 disables the compensation.
    pub latency_us: u32,
    /// Fewest satellites for a usable fix.
    pub min_satellites: u8,
    /// Largest reported horizontal accuracy for a usable fix (m).
    pub max_horizontal_accuracy_m: f32,
    /// Smallest position standard deviation used, whatever the receiver claims (m).
    pub min_position_std_m: f32,
    /// Smallest velocity standard deviation used (m/s).
    pub min_velocity_std_mps: f32,
    /// Whether the GPS height is fused (otherwise the barometer owns the vertical, as in
    /// the reference).
    pub use_height: bool,
}

impl Default for GpsAidingConfig {
    /// 100 ms latency (an M8/M10 at 10 Hz and 115200 Bd: ~50 ms solution + 9 ms transfer,
    /// plus scheduling), 6 satellites, 5 m, floors of 0.3 m and 0.1 m/s (receivers
    /// claim better than they deliver when standing still).
    fn default() -> Self {
        Self {
            latency_us: 100_000,
            min_satellites: 6,
            max_horizontal_accuracy_m: 5.0,
            min_position_std_m: 0.3,
            min_velocity_std_mps: 0.1,
            use_height: false,
        }
    }
}

/// The home: origin of the NED position.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Home {
    /// Latitude (deg·1e-7).
    pub lat_e7: i32,
    /// Longitude (deg·1e-7).
    pub lon_e7: i32,
    /// Height above mean sea level (mm).
    pub h_msl_mm: i32,
}

/// One GPS measurement as the INS takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GpsMeasurement {
    /// Position NED relative to home (m).
    pub position_ned_m: [f32; 3],
    /// Velocity NED (m/s).
    pub velocity_ned_mps: [f32; 3],
    /// Horizontal position variance (m²).
    pub horizontal_var_m2: f32,
    /// Vertical position variance (m²).
    pub vertical_var_m2: f32,
    /// Velocity variance per axis ((m/s)²).
    pub velocity_var_m2ps2: f32,
}

/// Why a NAV-PVT was not fused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unusable {
    /// No 3-D fix the receiver calls valid.
    NoFix,
    /// Too few satellites.
    FewSatellites,
    /// Reported horizontal accuracy too poor.
    Inaccurate,
}

/// What one NAV-PVT did.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GpsUpdate {
    /// Not fused; the fix counts as lost.
    Unusable(Unusable),
    /// Fused (each part may still have been gated, see [`Aided`]).
    Fused {
        /// The position's outcome.
        position: Aided,
        /// The velocity's outcome.
        velocity: Aided,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Past {
    time_us: u64,
    position_ned_m: [f32; 3],
    velocity_ned_mps: [f32; 3],
}

/// NAV-PVT → INS adapter with home and latency compensation.
#[derive(Debug, Clone)]
pub struct GpsAiding {
    config: GpsAidingConfig,
    home: Option<Home>,
    /// cos(home latitude), computed once per home: f64 trigonometry is soft-float on the
    /// Cortex-M4.
    home_cos_lat: f64,
    history: Deque<Past, HISTORY_LEN>,
    has_fix: bool,
}

fn sub3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a0 - b0, a1 - b1, a2 - b2]
}

fn add3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a0 + b0, a1 + b1, a2 + b2]
}

impl GpsAiding {
    /// An adapter without home and without history.
    #[must_use]
    pub fn new(config: GpsAidingConfig) -> Self {
        Self {
            config,
            home: None,
            home_cos_lat: 1.0,
            history: Deque::new(),
            has_fix: false,
        }
    }

    /// The home, once set.
    #[must_use]
    pub fn home(&self) -> Option<Home> {
        self.home
    }

    /// Sets the home explicitly (otherwise the first usable fix becomes home).
    pub fn set_home(&mut self, home: Home) {
        self.home = Some(home);
        // In f32: cos(latitude) to 1e-7 relative is a millimetre of east in 10 km, and the
        // f64 cosine's range reduction would be ≈ 3.4 KB of flash for this one call.
        let (_, cos_lat) = crate::math::sin_cos((f64::from(home.lat_e7) * DEG_E7_TO_RAD) as f32);
        self.home_cos_lat = f64::from(cos_lat);
    }

    /// Whether the last NAV-PVT was a usable fix.
    #[must_use]
    pub fn has_fix(&self) -> bool {
        self.has_fix
    }

    /// Remembers the estimate at `time_us`; call after every predict (entries closer than
    /// [`HISTORY_STEP_US`] to the previous one are skipped).
    pub fn record(&mut self, time_us: u64, state: &State) {
        if let Some(last) = self.history.back()
            && time_us < last.time_us.saturating_add(HISTORY_STEP_US)
        {
            return;
        }
        if self.history.is_full() {
            let _ = self.history.pop_front();
        }
        let _ = self.history.push_back(Past {
            time_us,
            position_ned_m: state.position_ned_m,
            velocity_ned_mps: state.velocity_ned_mps,
        });
    }

    /// Checks a fix against the configured quality limits.
    ///
    /// # Errors
    /// The first limit it fails.
    pub fn usable(&self, pvt: &NavPvt) -> Result<(), Unusable> {
        if !pvt.has_3d_fix() {
            Err(Unusable::NoFix)
        } else if pvt.num_sv < self.config.min_satellites {
            Err(Unusable::FewSatellites)
        } else if mm(pvt.h_acc_mm) > self.config.max_horizontal_accuracy_m {
            Err(Unusable::Inaccurate)
        } else {
            Ok(())
        }
    }

    /// The measurement a usable fix gives against the home (the first usable fix if none
    /// was set), not yet latency compensated; `None` before any home.
    #[must_use]
    pub fn measurement(&self, pvt: &NavPvt) -> Option<GpsMeasurement> {
        let home = self.home?;
        let c = &self.config;
        // Differences in integers first: 1e-7° is 1.1 cm, and an f32 of the absolute
        // latitude would lose metres.
        let dlat = f64::from(pvt.lat_e7.wrapping_sub(home.lat_e7)) * DEG_E7_TO_RAD;
        let dlon = f64::from(pvt.lon_e7.wrapping_sub(home.lon_e7)) * DEG_E7_TO_RAD;
        let north = dlat * EARTH_RADIUS_M;
        let east = dlon * EARTH_RADIUS_M * self.home_cos_lat;
        let down = -f64::from(pvt.h_msl_mm.wrapping_sub(home.h_msl_mm)) * 1e-3;
        let [vn, ve, vd] = pvt.vel_ned_mmps;
        let pos_std_h = max(mm(pvt.h_acc_mm), c.min_position_std_m);
        let pos_std_v = max(mm(pvt.v_acc_mm), c.min_position_std_m);
        let vel_std = max(mm(pvt.s_acc_mmps), c.min_velocity_std_mps);
        Some(GpsMeasurement {
            position_ned_m: [north as f32, east as f32, down as f32],
            velocity_ned_mps: [mmf(vn), mmf(ve), mmf(vd)],
            horizontal_var_m2: pos_std_h * pos_std_h,
            vertical_var_m2: pos_std_v * pos_std_v,
            velocity_var_m2ps2: vel_std * vel_std,
        })
    }

    /// Moves `m`, valid at `arrival_us − latency`, to the time of `now` (the estimate at
    /// `now_us`), by the estimate's own motion since then. Without history that far back
    /// the measurement is returned unchanged.
    #[must_use]
    pub fn compensate(&self, m: GpsMeasurement, arrival_us: u64, now: &State) -> GpsMeasurement {
        let target = arrival_us.saturating_sub(u64::from(self.config.latency_us));
        if self.config.latency_us == 0 {
            return m;
        }
        let Some(past) = self.closest(target) else {
            return m;
        };
        GpsMeasurement {
            position_ned_m: add3(
                m.position_ned_m,
                sub3(now.position_ned_m, past.position_ned_m),
            ),
            velocity_ned_mps: add3(
                m.velocity_ned_mps,
                sub3(now.velocity_ned_mps, past.velocity_ned_mps),
            ),
            ..m
        }
    }

    fn closest(&self, target_us: u64) -> Option<Past> {
        let oldest = self.history.front()?;
        if oldest.time_us > target_us.saturating_add(HISTORY_STEP_US) {
            return None;
        }
        self.history
            .iter()
            .min_by_key(|p| p.time_us.abs_diff(target_us))
            .copied()
    }

    /// Takes one NAV-PVT without fusing it: whether it is a usable fix, and the home from
    /// the first usable one. What every fix gets, fused or not: without the INS flying the
    /// home still goes to telemetry and the ground station.
    ///
    /// # Errors
    /// The limit the fix fails ([`GpsAiding::usable`]); it then counts as lost.
    pub fn observe(&mut self, pvt: &NavPvt) -> Result<(), Unusable> {
        if let Err(why) = self.usable(pvt) {
            self.has_fix = false;
            return Err(why);
        }
        self.has_fix = true;
        if self.home.is_none() {
            self.set_home(Home {
                lat_e7: pvt.lat_e7,
                lon_e7: pvt.lon_e7,
                h_msl_mm: pvt.h_msl_mm,
            });
        }
        Ok(())
    }

    /// Offers one NAV-PVT that arrived at `arrival_us` to `ins`.
    ///
    /// # Errors
    /// As [`Ins::gps_position_with_variance`] (non-finite input, divergence).
    pub fn fuse(
        &mut self,
        ins: &mut Ins,
        pvt: &NavPvt,
        arrival_us: u64,
    ) -> Result<GpsUpdate, Error> {
        if let Err(why) = self.observe(pvt) {
            return Ok(GpsUpdate::Unusable(why));
        }
        let Some(m) = self.measurement(pvt) else {
            return Ok(GpsUpdate::Unusable(Unusable::NoFix));
        };
        let m = self.compensate(m, arrival_us, &ins.state());
        let position = ins.gps_position_with_variance(
            m.position_ned_m,
            self.config.use_height,
            [m.horizontal_var_m2, m.vertical_var_m2],
        )?;
        let velocity = ins.gps_velocity_with_variance(m.velocity_ned_mps, m.velocity_var_m2ps2)?;
        Ok(GpsUpdate::Fused { position, velocity })
    }
}

fn mm(v: u32) -> f32 {
    v as f32 * 1e-3
}

fn mmf(v: i32) -> f32 {
    v as f32 * 1e-3
}

fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[cfg(test)]
mod tests;
