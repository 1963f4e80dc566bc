//! A simulated u-blox receiver: every [`GpsConfig::period_ms`] it reports the quad's true
//! position and velocity of [`GpsConfig::latency_ms`] earlier, with white noise, as the bytes
//! of a UBX NAV-PVT frame — what the flight firmware's GPS task hands to
//! `FlightApp::on_gps_bytes`, so the app's parser, configuration and latency compensation
//! run as on the board. During a dropout it reports "no fix" (the receiver still talks).

use std::collections::VecDeque;

use flight_app::sensors::ubx::{FixType, NavPvt, frame};
use telemetry::mock::SplitMix64;

/// The receiver's behaviour.
#[derive(Debug, Clone, PartialEq)]
pub struct GpsConfig {
    /// Solution period, ms (200 = 5 Hz).
    pub period_ms: u32,
    /// From the solution's epoch to its last byte at the flight controller, ms.
    pub latency_ms: u32,
    /// Horizontal position noise, m (1σ, white, per axis).
    pub position_noise_m: f64,
    /// Vertical position noise, m (1σ).
    pub altitude_noise_m: f64,
    /// Velocity noise, m/s (1σ, per axis).
    pub velocity_noise_mps: f64,
    /// Dropouts (no fix), scenario seconds [from, to).
    pub dropouts: Vec<(f64, f64)>,
}

impl Default for GpsConfig {
    /// 5 Hz, 100 ms latency, 0.5 m / 1.0 m / 0.1 m/s noise (an M8 in the open; its reported
    /// hAcc 1.2 m, vAcc 2.0 m, sAcc 0.2 m/s), no dropouts.
    fn default() -> Self {
        Self {
            period_ms: 200,
            latency_ms: 100,
            position_noise_m: 0.5,
            altitude_noise_m: 1.0,
            velocity_noise_mps: 0.1,
            dropouts: Vec::new(),
        }
    }
}

/// Where the simulated field is (a park near Zürich), deg·1e-7 and mm.
const HOME_LAT_E7: i32 = 473_977_420;
const HOME_LON_E7: i32 = 85_455_940;
const HOME_MSL_MM: i32 = 488_000;
const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// The receiver's state.
pub struct GpsSim {
    config: GpsConfig,
    noise: SplitMix64,
    /// Truth history (time ms, NED position m, NED velocity m/s), one per physics step,
    /// as long as the latency.
    history: VecDeque<(u64, [f64; 3], [f64; 3])>,
    next_fix_ms: u64,
}

impl GpsSim {
    /// A receiver with `config`, its noise seeded from `seed`.
    pub fn new(config: GpsConfig, seed: u64) -> Self {
        Self {
            config,
            noise: SplitMix64::new(seed ^ 0x6_95),
            history: VecDeque::new(),
            next_fix_ms: 0,
        }
    }

    /// Records the truth at `t_ms` and returns the bytes of a NAV-PVT when one is due.
    /// `scenario_s` decides dropouts.
    pub fn step(
        &mut self,
        t_ms: u64,
        scenario_s: f64,
        position_ned_m: [f64; 3],
        velocity_ned_mps: [f64; 3],
    ) -> Option<Vec<u8>> {
        self.history
            .push_back((t_ms, position_ned_m, velocity_ned_mps));
        let latency = u64::from(self.config.latency_ms);
        while self
            .history
            .front()
            .is_some_and(|(t, _, _)| t + latency < t_ms)
        {
            self.history.pop_front();
        }
        if t_ms < self.next_fix_ms {
            return None;
        }
        self.next_fix_ms = t_ms + u64::from(self.config.period_ms);
        let &(epoch_ms, p, v) = self.history.front()?;
        let dropout = self
            .config
            .dropouts
            .iter()
            .any(|(a, b)| (*a..*b).contains(&scenario_s));
        let c = &self.config;
        let (pn, pe, pd) = (
            p[0] + self.noise.normal(c.position_noise_m),
            p[1] + self.noise.normal(c.position_noise_m),
            p[2] + self.noise.normal(c.altitude_noise_m),
        );
        let vel = v.map(|x| x + self.noise.normal(c.velocity_noise_mps));
        let to_e7 = 180.0 / std::f64::consts::PI * 1e7;
        let lat0 = f64::from(HOME_LAT_E7) / to_e7;
        let pvt = NavPvt {
            itow_ms: u32::try_from(epoch_ms % 604_800_000).unwrap_or(0),
            fix_type: if dropout {
                FixType::NoFix
            } else {
                FixType::Fix3D
            },
            flags: u8::from(!dropout),
            num_sv: if dropout { 2 } else { 12 },
            lon_e7: HOME_LON_E7 + (pe / (EARTH_RADIUS_M * lat0.cos()) * to_e7).round() as i32,
            lat_e7: HOME_LAT_E7 + (pn / EARTH_RADIUS_M * to_e7).round() as i32,
            height_mm: HOME_MSL_MM + 48_000 - (pd * 1e3).round() as i32,
            h_msl_mm: HOME_MSL_MM - (pd * 1e3).round() as i32,
            h_acc_mm: 1_200,
            v_acc_mm: 2_000,
            vel_ned_mmps: vel.map(|x| (x * 1e3).round() as i32),
            g_speed_mmps: (vel[0].hypot(vel[1]) * 1e3).round() as i32,
            head_mot_e5: (vel[1].atan2(vel[0]).to_degrees() * 1e5).round() as i32,
            s_acc_mmps: 200,
            p_dop_e2: 120,
        };
        frame::encode(0x01, 0x07, &pvt.encode())
            .ok()
            .map(|f| f.to_vec())
    }
}
