//! The motor-output path between the flight loop and the motors' torque, to the resolution
//! of microseconds: when the output timer starts a pulse, when the ESC acts on it (at the
//! pulse's falling edge), and what it does with it (optionally averaging the last pulses).
//!
//! What makes OneShot125 faster than conventional PWM is timing, not the motor:
//! - **PWM at 400 Hz, asynchronous** to the sensor loop: the timer runs freely with a 2.5 ms
//!   period; a pulse carries the last output written before it starts, and is 1–2 ms long.
//!   An output waits up to a period for the next pulse, then the pulse width, before the
//!   ESC sees it.
//! - **OneShot125, synchronous**: the loop starts a 125–250 µs pulse right after computing
//!   the output; the ESC acts at its end.
//!
//! The plant behind the ESC is the per-axis model of [`crate::axis`] (first-order motor lag
//! τ, authority β), integrated exactly (ZOH) over ticks of [`TICK_US`] µs; each axis has its
//! own pulse (a motor pair's differential command), all on one timer.

use flight_core::model::{AxisModel, LqrMatrices};
use sim_rng::{GOLDEN_GAMMA, SplitMix64};
use std::collections::VecDeque;

/// Simulation tick, µs: pulse edges are placed on this grid (±2.5 µs).
pub const TICK_US: u64 = 5;

/// How the flight loop's outputs reach the ESCs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum OutputTiming {
    /// Conventional PWM (1000–2000 µs pulses) from a free-running timer at `rate_hz`,
    /// asynchronous to the loop.
    PwmAsync {
        /// Timer rate, Hz.
        rate_hz: u32,
    },
    /// OneShot125 (125–250 µs pulses), one pulse started right after each loop.
    OneShot125Sync,
}

impl OutputTiming {
    /// Pulse width range (min, max), µs.
    #[must_use]
    pub fn pulse_range_us(self) -> (f64, f64) {
        match self {
            OutputTiming::PwmAsync { .. } => (1000.0, 2000.0),
            OutputTiming::OneShot125Sync => (125.0, 250.0),
        }
    }
}

/// The output path's configuration.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EscConfig {
    /// Protocol and timing.
    pub timing: OutputTiming,
    /// From the gyro sample to the output being written (sensor read, estimation, control),
    /// µs. The seed's scope showed ≈ 300 µs from the MPU9250's interrupt to the end of a
    /// short OneShot125 pulse, so ≈ 175 µs before the pulse starts.
    pub compute_us: u64,
    /// Throttle the pulses carry at zero axis command (hover), 0…1.
    pub hover_throttle: f64,
    /// Share of an axis command in one motor's throttle (a quad X mixer gives each motor
    /// ± 0.5 of roll/pitch; with the attitude demand scaled into ±1, 0.25 keeps the pulses
    /// inside their range).
    pub axis_share: f64,
    /// The ESC averages the last this many pulses (1 = acts on each pulse as it comes; some
    /// ESC firmwares filter their input).
    pub filter_pulses: usize,
}

impl EscConfig {
    /// `timing` with 175 µs compute time, hover at 0.5, axis share 0.25, no input filter.
    #[must_use]
    pub fn new(timing: OutputTiming) -> Self {
        Self {
            timing,
            compute_us: 175,
            hover_throttle: 0.5,
            axis_share: 0.25,
            filter_pulses: 1,
        }
    }

    /// Pulse width for axis command `u` (±1), in ticks.
    fn width_ticks(&self, u: f64) -> u64 {
        let (lo, hi) = self.timing.pulse_range_us();
        let duty = (self.hover_throttle + self.axis_share * u).clamp(0.0, 1.0);
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let ticks = ((lo + duty * (hi - lo)) / TICK_US as f64).round() as u64;
        ticks
    }
}

/// One axis behind its ESC.
#[derive(Debug, Clone)]
struct EscAxis {
    m: LqrMatrices<f64>,
    /// Angle (deg), rate (deg/s), normalised torque.
    state: [f64; 3],
    /// The output the loop last wrote (what the timer's next pulse carries).
    register: f64,
    /// Falling edges still to come: (tick, command).
    pending: VecDeque<(u64, f64)>,
    /// The last pulses the ESC received (for its input filter).
    received: VecDeque<f64>,
    /// What the ESC drives the motor with.
    command: f64,
    /// The tick at which the command first left 0.
    first_drive_tick: Option<u64>,
}

/// The three axes of a frame behind one output timer.
#[derive(Debug, Clone)]
pub struct EscPlant {
    cfg: EscConfig,
    axes: Vec<EscAxis>,
    /// Loop period in ticks.
    loop_ticks: u64,
    /// Next timer period start (asynchronous PWM), tick.
    next_period: u64,
    /// Current tick.
    now: u64,
    /// Constant input disturbance of every axis (actuator units).
    disturbance: f64,
    gyro_noise_dps: f64,
    rng: SplitMix64,
}

impl EscPlant {
    /// Three axes with `models` at loop period `loop_us`, the timer's phase drawn from
    /// `seed` (with the gyro noise).
    #[must_use]
    pub fn new(
        cfg: EscConfig,
        models: [AxisModel; 3],
        loop_us: u64,
        gyro_noise_dps: f64,
        disturbance: f64,
        seed: u64,
    ) -> Self {
        #[allow(clippy::cast_precision_loss)]
        let tick_s = TICK_US as f64 * 1e-6;
        let axes = models
            .iter()
            .map(|model| EscAxis {
                m: LqrMatrices::new(model, tick_s),
                state: [0.0; 3],
                register: 0.0,
                pending: VecDeque::new(),
                received: VecDeque::new(),
                command: 0.0,
                first_drive_tick: None,
            })
            .collect();
        let mut rng = SplitMix64::new(seed ^ GOLDEN_GAMMA);
        let period = Self::period_ticks(cfg.timing);
        #[allow(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            clippy::cast_precision_loss
        )]
        let phase = (rng.open_unit() * period as f64) as u64 % period.max(1);
        Self {
            cfg,
            axes,
            loop_ticks: (loop_us / TICK_US).max(1),
            next_period: phase,
            now: 0,
            disturbance,
            gyro_noise_dps,
            rng,
        }
    }

    fn period_ticks(timing: OutputTiming) -> u64 {
        match timing {
            OutputTiming::PwmAsync { rate_hz } => {
                (1_000_000 / u64::from(rate_hz.max(1)) / TICK_US).max(1)
            }
            OutputTiming::OneShot125Sync => 1,
        }
    }

    /// Gyro samples of the three axes now (deg/s, with noise).
    pub fn gyro(&mut self) -> [f32; 3] {
        let mut g = [0.0f32; 3];
        for (out, axis) in g.iter_mut().zip(&self.axes) {
            #[allow(clippy::cast_possible_truncation)]
            let v = (axis.state[1] + self.gyro_noise_dps * self.rng.gaussian()) as f32;
            *out = v;
        }
        g
    }

    /// When the first axis's ESC first drove its motor, µs since the start.
    #[must_use]
    pub fn first_drive_us(&self) -> Option<u64> {
        self.axes.first()?.first_drive_tick.map(|t| t * TICK_US)
    }

    /// True angles, deg.
    #[must_use]
    pub fn angles_deg(&self) -> [f64; 3] {
        let mut a = [0.0; 3];
        for (out, axis) in a.iter_mut().zip(&self.axes) {
            *out = axis.state[0];
        }
        a
    }

    /// The loop computed `outputs` from the sample taken now: run one loop period (the
    /// write after the compute time, the pulses, the ESC edges) and return the next sample.
    pub fn step(&mut self, outputs: [f32; 3]) -> [f32; 3] {
        let start = self.now;
        let write_at = start + self.cfg.compute_us / TICK_US;
        let end = start + self.loop_ticks;
        let mut written = false;
        let sync = matches!(self.cfg.timing, OutputTiming::OneShot125Sync);
        let period = Self::period_ticks(self.cfg.timing);
        for t in start..end {
            if !written && t >= write_at {
                written = true;
                for (axis, u) in self.axes.iter_mut().zip(outputs) {
                    axis.register = f64::from(u).clamp(-1.0, 1.0);
                    if sync {
                        let fall = t + self.cfg.width_ticks(axis.register);
                        axis.pending.push_back((fall, axis.register));
                    }
                }
            }
            if !sync && t >= self.next_period {
                self.next_period += period;
                for axis in &mut self.axes {
                    let fall = t + self.cfg.width_ticks(axis.register);
                    axis.pending.push_back((fall, axis.register));
                }
            }
            let filter = self.cfg.filter_pulses.max(1);
            for axis in &mut self.axes {
                while let Some(&(fall, value)) = axis.pending.front() {
                    if fall > t {
                        break;
                    }
                    axis.pending.pop_front();
                    axis.received.push_back(value);
                    while axis.received.len() > filter {
                        axis.received.pop_front();
                    }
                    #[allow(clippy::cast_precision_loss)]
                    let n = axis.received.len().max(1) as f64;
                    axis.command = axis.received.iter().sum::<f64>() / n;
                    if axis.command != 0.0 && axis.first_drive_tick.is_none() {
                        axis.first_drive_tick = Some(t);
                    }
                }
                let drive = axis.command - self.disturbance;
                let [angle, rate, torque] = axis.state;
                let m = &axis.m;
                let [b0, b1, b2] = m.b;
                axis.state = [
                    angle + m.ts * rate + m.a_angle_torque * torque + b0 * drive,
                    rate + m.a_rate_torque * torque + b1 * drive,
                    m.e * torque + b2 * drive,
                ];
            }
        }
        self.now = end;
        self.gyro()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// When a 0.5 output written in the first loop (one 20 ms loop period, so nothing else
    /// is written) first reaches the motor, µs.
    fn first_response_us(cfg: EscConfig, seed: u64) -> u64 {
        let model = AxisModel::new(10.0, 0.01).unwrap();
        let mut p = EscPlant::new(cfg, [model; 3], 20_000, 0.0, 0.0, seed);
        p.step([0.5; 3]);
        p.first_drive_us().expect("acted within 20 ms")
    }

    #[test]
    fn oneshot_acts_at_the_end_of_a_pulse_right_after_the_loop() {
        let cfg = EscConfig::new(OutputTiming::OneShot125Sync);
        // Written at 175 µs, a 0.5 command: duty 0.625 → 203 µs pulse, on the 5 µs grid.
        let us = first_response_us(cfg, 1);
        assert!((370..=385).contains(&us), "{us} µs");
    }

    #[test]
    fn pwm_waits_for_the_next_period_then_the_whole_pulse() {
        let cfg = EscConfig::new(OutputTiming::PwmAsync { rate_hz: 400 });
        let mut seen = Vec::new();
        for seed in 0..40 {
            seen.push(first_response_us(cfg, seed));
        }
        // Written at 175 µs; the next period starts within 2.5 ms; the pulse is 1.625 ms.
        let (lo, hi) = (175 + 1625, 175 + 2500 + 1625 + 5);
        assert!(seen.iter().all(|us| (lo..=hi).contains(us)), "{seen:?}");
        let spread = seen.iter().max().unwrap() - seen.iter().min().unwrap();
        assert!(
            spread > 1500,
            "the timer phase varies with the seed: {seen:?}"
        );
    }

    #[test]
    fn the_input_filter_averages_the_last_pulses() {
        let mut cfg = EscConfig::new(OutputTiming::OneShot125Sync);
        cfg.filter_pulses = 4;
        let model = AxisModel::new(10.0, 0.01).unwrap();
        let mut p = EscPlant::new(cfg, [model; 3], 1000, 0.0, 0.0, 1);
        for _ in 0..2 {
            p.step([0.5; 3]);
        }
        // Two pulses of 0.5 received so far: the average of what it has is 0.5.
        assert!((p.axes[0].command - 0.5).abs() < 1e-12);
        p.step([0.0; 3]);
        // 0.5, 0.5, 0.0 → 1/3; after four more zeros only zeros are left.
        assert!((p.axes[0].command - 1.0 / 3.0).abs() < 1e-12);
        for _ in 0..4 {
            p.step([0.0; 3]);
        }
        assert_eq!(p.axes[0].command, 0.0);
    }
}
