//! The flight log: what the application records while it flies, and how that becomes a
//! ULog file (PX4's format: pyulog, PlotJuggler and Flight Review read it).
//!
//! Owned here: the topics and their records (`topics`), the profiles the pilot chooses
//! between with `log.profile` (`profile`), the [`Recorder`] — a ring of fixed-size
//! [`Entry`]s that the application's `on_*` calls copy into, and nothing more: no encoding,
//! no I/O, no floating-point work beyond what the loop already computed — and the
//! [`Encoder`], which a logging task (the firmware's, the simulator's, a host tool's) runs
//! outside the loop to turn the entries into ULog bytes in whatever buffers its sink takes
//! (a flash page, a telemetry frame, a file). On the Sparky2 that sink is its M25P16's log
//! area (`store`: pages that survive a power cut, erases ahead of time, sans-IO so the
//! flash task schedules each operation between radio slots).
//!
//! When the ring is full, entries are dropped and the gap is marked: the next entry that
//! fits is preceded by an [`Entry::Dropout`] of the lost time, which the encoder writes as
//! ULog's dropout message. A log therefore never silently misses data.

mod encoder;
mod profile;
pub mod store;
mod topics;

pub use encoder::{Encoder, MIN_BUFFER, TOPICS, Topic, param_name};
pub use profile::{Profile, Rates};
pub use topics::{
    Battery, Entry, Estimate, Event, Identification, LinkStats, Motors, SensorBaro, SensorGps,
    SensorImu, Setpoint, Status, imu_flags,
};

use heapless::Deque;

use crate::app::ImuFault;
use crate::battery::{BatteryLevel, BatteryStatus};
pub use crate::loop_side::LoopSnapshot;
use crate::pipeline::{LoopOutput, Source};
use crate::report::LinkSeen;
use crate::supervisor::Decision;
use crate::sysid::ekf;

/// The Sparky2's log area: sectors 16–31 of its M25P16, 64 KiB each, where the Tau Labs
/// firmware's flash map for the board puts its log stream (0–5 settings, 6–10 waypoints).
pub const SPARKY2_LOG_AREA_BYTES: u32 = 16 * 64 * 1024;

/// Entries the ring holds: 80 ms of the full profile's four loop topics at 1 kHz less the
/// rest, far more for the others; the logging task drains it every few milliseconds.
pub const RING_ENTRIES: usize = 96;

/// What a loop sample is recorded with: the loop's snapshot and the app's side of the
/// moment.
#[derive(Debug, Clone, Copy)]
pub struct LoopContext<'a> {
    /// The loop's step.
    pub snapshot: &'a LoopSnapshot,
    /// Its output.
    pub out: &'a LoopOutput,
    /// Barometric altitude above the power-up point, m.
    pub baro_altitude_m: Option<f32>,
    /// Arming blockers (telemetry's bit set).
    pub arming_blockers: u16,
    /// Standing IMU fault.
    pub imu_fault: Option<ImuFault>,
}

/// Counters of the loop topics' dividers.
#[derive(Debug, Clone, Copy, Default)]
struct Dividers {
    imu: u32,
    estimate: u32,
    setpoint: u32,
    motors: u32,
    status: u32,
    identification: u32,
}

/// The ring the application records into.
#[derive(Debug, Clone)]
pub struct Recorder {
    profile: Profile,
    rates: Rates,
    every: Dividers,
    loops: u32,
    baro: u32,
    gps: u32,
    battery: u32,
    link: u32,
    ring: Deque<Entry, RING_ENTRIES>,
    /// The span of dropped entries not yet marked, µs.
    lost: Option<(u64, u64)>,
    /// Entries dropped since boot.
    dropped: u32,
    last_fallbacks: u16,
}

impl Recorder {
    /// A recorder for `profile` with the loop at `loop_hz`.
    pub fn new(profile: Profile, loop_hz: u32) -> Self {
        let rates = profile.rates();
        Self {
            profile,
            rates,
            every: Dividers {
                imu: profile::divider(rates.imu_hz, loop_hz),
                estimate: profile::divider(rates.estimate_hz, loop_hz),
                setpoint: profile::divider(rates.setpoint_hz, loop_hz),
                motors: profile::divider(rates.motors_hz, loop_hz),
                status: profile::divider(rates.status_hz, loop_hz),
                identification: profile::divider(rates.identification_hz, loop_hz),
            },
            loops: 0,
            baro: 0,
            gps: 0,
            battery: 0,
            link: 0,
            ring: Deque::new(),
            lost: None,
            dropped: 0,
            last_fallbacks: 0,
        }
    }

    /// Switches to `profile` with the loop at `loop_hz` (a new setup), keeping what waits.
    pub fn reconfigure(&mut self, profile: Profile, loop_hz: u32) {
        let fresh = Self::new(profile, loop_hz);
        self.profile = fresh.profile;
        self.rates = fresh.rates;
        self.every = fresh.every;
    }

    /// The profile recorded.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// Entries dropped since boot because the ring was full (a loop sample that never
    /// reached the recorder counts as one).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Entries waiting.
    pub fn len(&self) -> usize {
        self.ring.len()
    }

    /// Nothing waiting.
    pub fn is_empty(&self) -> bool {
        self.ring.is_empty()
    }

    /// The oldest entry, for the logging task.
    pub fn pop(&mut self) -> Option<Entry> {
        self.ring.pop_front()
    }

    fn push(&mut self, t_us: u64, entry: Entry) {
        if let Some((from, to)) = self.lost {
            if self.ring.capacity() - self.ring.len() < 2 {
                self.lose(t_us);
                return;
            }
            let ms = (to.saturating_sub(from) / 1000).clamp(1, u64::from(u16::MAX)) as u16;
            let _ = self.ring.push_back(Entry::Dropout(from, ms));
            self.lost = None;
        }
        if self.ring.push_back(entry).is_err() {
            self.lose(t_us);
        }
    }

    fn lose(&mut self, t_us: u64) {
        self.dropped = self.dropped.saturating_add(1);
        self.lost = Some(match self.lost {
            Some((from, _)) => (from, t_us),
            None => (t_us, t_us),
        });
    }

    /// Whether the `n`-th occurrence is due at divider `every` (0: never).
    fn due(n: u32, every: u32) -> bool {
        every != 0 && n.is_multiple_of(every)
    }

    /// One flight-loop sample at `now_ms`.
    pub fn on_loop(&mut self, now_ms: u32, c: &LoopContext) {
        if self.profile == Profile::Off {
            return;
        }
        let t = u64::from(now_ms) * 1000;
        let n = self.loops;
        self.loops = n.wrapping_add(1);
        let every = self.every;
        if Self::due(n, every.imu) {
            self.push(t, Entry::Imu(imu_record(t, c)));
        }
        if Self::due(n, every.estimate) {
            self.push(t, Entry::Estimate(estimate_record(t, c)));
        }
        if Self::due(n, every.setpoint) {
            let l = c.snapshot.link;
            self.push(
                t,
                Entry::Setpoint(Setpoint {
                    timestamp: t,
                    sticks: [
                        l.sticks.roll,
                        l.sticks.pitch,
                        l.sticks.yaw,
                        l.sticks.throttle,
                    ],
                    mode_channel: l.mode_channel,
                    arm_switch: l.arm_switch.map_or(2, u8::from),
                    link_up: l.up,
                }),
            );
        }
        if Self::due(n, every.motors) {
            let command = c.out.motors.map(|m| match m {
                crate::outputs::Command::Throttle(x) => x,
                crate::outputs::Command::Stopped => -1.0,
            });
            self.push(
                t,
                Entry::Motors(Motors {
                    timestamp: t,
                    command,
                }),
            );
        }
        if Self::due(n, every.status) {
            self.push(t, Entry::Status(status_record(t, c)));
        }
        if Self::due(n, every.identification)
            && let Some(id) = c.snapshot.identification
        {
            self.push(t, Entry::Identification(identification(t, &id, false)));
        }
        self.loop_events(t, c);
    }

    fn loop_events(&mut self, t: u64, c: &LoopContext) {
        if c.out.decision != Decision::Steady {
            self.push(t, Entry::Event(t, Event::Decision(c.out.decision)));
        }
        if c.out.mode_changed {
            self.push(t, Entry::Event(t, Event::Mode(c.out.mode)));
        }
        let fallbacks = c.snapshot.fallbacks;
        if fallbacks != self.last_fallbacks {
            self.last_fallbacks = fallbacks;
            self.push(t, Entry::Event(t, Event::EstimatorFallback));
        }
    }

    /// `steps` loop samples up to `now_ms` that never reached the recorder (the loop's
    /// reports merged while the app's side was busy): marked as lost, like a full ring's.
    pub fn on_loops_missed(&mut self, now_ms: u32, steps: u32) {
        if self.profile == Profile::Off || steps == 0 {
            return;
        }
        self.loops = self.loops.wrapping_add(steps);
        self.lose(u64::from(now_ms) * 1000);
        self.dropped = self.dropped.saturating_add(steps - 1);
    }

    /// An event at `now_ms`.
    pub fn on_event(&mut self, now_ms: u32, event: Event) {
        if self.profile != Profile::Off {
            let t = u64::from(now_ms) * 1000;
            self.push(t, Entry::Event(t, event));
        }
    }

    /// A finished identification.
    pub fn on_identified(&mut self, now_ms: u32, id: &ekf::Identification) {
        if self.profile != Profile::Off {
            let t = u64::from(now_ms) * 1000;
            self.push(t, Entry::Identification(identification(t, id, true)));
        }
    }

    /// A baro altitude handed to the estimator.
    pub fn on_baro(&mut self, now_ms: u32, altitude_m: f32) {
        let n = self.baro;
        self.baro = n.wrapping_add(1);
        if Self::due(n, u32::from(self.rates.baro_every)) {
            let t = u64::from(now_ms) * 1000;
            self.push(
                t,
                Entry::Baro(SensorBaro {
                    timestamp: t,
                    altitude_m,
                }),
            );
        }
    }

    /// A NAV-PVT handed to the estimator.
    pub fn on_gps(&mut self, now_ms: u32, pvt: &ubx::NavPvt) {
        let n = self.gps;
        self.gps = n.wrapping_add(1);
        if Self::due(n, u32::from(self.rates.gps_every)) {
            let t = u64::from(now_ms) * 1000;
            self.push(t, Entry::Gps(gps_record(t, pvt)));
        }
    }

    /// A battery reading.
    pub fn on_battery(&mut self, now_ms: u32, b: &BatteryStatus) {
        let n = self.battery;
        self.battery = n.wrapping_add(1);
        if Self::due(n, u32::from(self.rates.battery_every)) {
            let t = u64::from(now_ms) * 1000;
            let level = match b.level {
                BatteryLevel::Ok => 0,
                BatteryLevel::Warning => 1,
                BatteryLevel::Critical => 2,
            };
            self.push(
                t,
                Entry::Battery(Battery {
                    timestamp: t,
                    voltage_v: b.voltage_mv as f32 * 1e-3,
                    current_a: b.current_ma as f32 * 1e-3,
                    consumed_mah: b.consumed_mah,
                    cells: b.cells,
                    level,
                }),
            );
        }
    }

    /// The link's figures at a telemetry report.
    pub fn on_link(&mut self, now_us: u64, seen: &LinkSeen) {
        let n = self.link;
        self.link = n.wrapping_add(1);
        if Self::due(n, u32::from(self.rates.link_every)) {
            let (down_rssi_dbm, down_lq_percent) = seen.downlink.unwrap_or((0, 0));
            self.push(
                now_us,
                Entry::Link(LinkStats {
                    timestamp: now_us,
                    rssi_dbm: seen.rssi_dbm,
                    lq_percent: seen.lq_percent,
                    down_rssi_dbm,
                    down_lq_percent,
                    rate_mode: seen.rate_mode,
                    received: seen.received,
                    missed: seen.missed,
                    failsafes: seen.failsafes,
                }),
            );
        }
    }
}

fn imu_record(t: u64, c: &LoopContext) -> SensorImu {
    let s = &c.snapshot.sample;
    let mut flags = 0;
    if s.mag.is_some() {
        flags |= imu_flags::MAG;
    }
    if c.snapshot.accel_corrected {
        flags |= imu_flags::ACCEL_CORRECTS;
    }
    if c.snapshot.armed_before {
        flags |= imu_flags::ARMED;
    }
    SensorImu {
        timestamp: t,
        gyro_radps: s.gyro_radps,
        accel_mps2: s.accel_mps2,
        mag: s.mag.unwrap_or([0.0; 3]),
        flags,
    }
}

fn estimate_record(t: u64, c: &LoopContext) -> Estimate {
    let l = c.snapshot;
    let nan3 = [f32::NAN; 3];
    let ins = l.ins;
    Estimate {
        timestamp: t,
        q: l.attitude,
        // The yaw angle is left to the encoder (an atan2 the loop does not need).
        euler_deg: [c.out.attitude.roll_deg, c.out.attitude.pitch_deg, f32::NAN],
        velocity_ned_mps: ins.map_or(nan3, |s| s.velocity_ned_mps),
        position_ned_m: ins.map_or(nan3, |s| s.position_ned_m),
        gyro_bias_radps: ins.map_or(nan3, |s| s.gyro_bias_radps),
        accel_bias_z_mps2: ins.map_or(f32::NAN, |s| s.accel_bias_z_mps2),
        altitude_m: l.ins_altitude_m.or(c.baro_altitude_m).unwrap_or(f32::NAN),
        climb_mps: l.climb_mps.unwrap_or(f32::NAN),
        source: source_code(c.out.estimator),
    }
}

fn source_code(s: Source) -> u8 {
    match s {
        Source::Complementary => 0,
        Source::Ins => 1,
    }
}

fn status_record(t: u64, c: &LoopContext) -> Status {
    Status {
        timestamp: t,
        armed: c.out.armed,
        mode: c.out.mode.id(),
        failsafe: c.out.failsafe,
        estimator: source_code(c.out.estimator),
        arming_blockers: c.arming_blockers,
        imu_fault: match c.imu_fault {
            None => 0,
            Some(ImuFault::Stalled) => 1,
            Some(ImuFault::ReadError) => 2,
            Some(ImuFault::Frozen) => 3,
            Some(ImuFault::AllZero) => 4,
        },
    }
}

fn identification(t: u64, id: &ekf::Identification, finished: bool) -> Identification {
    Identification {
        timestamp: t,
        ln_beta: id.ln_beta,
        tau_s: id.tau_s,
        bias: id.bias,
        sigma_ln_beta: id.sigma_ln_beta,
        sigma_ln_tau: id.sigma_ln_tau,
        gyro_noise_dps: id.gyro_noise_dps,
        samples: id.samples,
        finished,
    }
}

/// The log record of a NAV-PVT.
pub fn gps_record(t: u64, p: &ubx::NavPvt) -> SensorGps {
    SensorGps {
        timestamp: t,
        itow_ms: p.itow_ms,
        fix_type: fix_code(p.fix_type),
        flags: p.flags,
        num_sv: p.num_sv,
        lon_e7: p.lon_e7,
        lat_e7: p.lat_e7,
        height_mm: p.height_mm,
        h_msl_mm: p.h_msl_mm,
        h_acc_mm: p.h_acc_mm,
        v_acc_mm: p.v_acc_mm,
        vel_ned_mmps: p.vel_ned_mmps,
        g_speed_mmps: p.g_speed_mmps,
        head_mot_e5: p.head_mot_e5,
        s_acc_mmps: p.s_acc_mmps,
        p_dop_e2: p.p_dop_e2,
    }
}

/// The NAV-PVT a log record holds (what a replay hands the estimator).
pub fn gps_from_record(r: &SensorGps) -> ubx::NavPvt {
    ubx::NavPvt {
        itow_ms: r.itow_ms,
        fix_type: ubx::FixType::from(r.fix_type),
        flags: r.flags,
        num_sv: r.num_sv,
        lon_e7: r.lon_e7,
        lat_e7: r.lat_e7,
        height_mm: r.height_mm,
        h_msl_mm: r.h_msl_mm,
        h_acc_mm: r.h_acc_mm,
        v_acc_mm: r.v_acc_mm,
        vel_ned_mmps: r.vel_ned_mmps,
        g_speed_mmps: r.g_speed_mmps,
        head_mot_e5: r.head_mot_e5,
        s_acc_mmps: r.s_acc_mmps,
        p_dop_e2: r.p_dop_e2,
    }
}

/// The wire code of a fix type (the inverse of `FixType::from`).
fn fix_code(f: ubx::FixType) -> u8 {
    use ubx::FixType as F;
    match f {
        F::NoFix => 0,
        F::DeadReckoning => 1,
        F::Fix2D => 2,
        F::Fix3D => 3,
        F::GnssDeadReckoning => 4,
        F::TimeOnly => 5,
        F::Unknown(code) => code,
    }
}
