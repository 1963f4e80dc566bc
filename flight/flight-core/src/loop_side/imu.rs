//! The IMU fault policy. The loop rides through a short gap in usable samples (data-ready
//! missing, read errors, frozen or all-zero data) by holding the last motor command for at
//! most [`STALL_RIDE_THROUGH_MS`]; beyond that the frame can no longer sense its attitude:
//! disarm with [`ImuFault`] as the reason (telemetry's "sensors unhealthy" blocker, the
//! console's status, a distinct alert tone) and ask the adapter to re-probe the sensor
//! every [`REPROBE_PERIOD_MS`]. The fault clears after [`CLEAR_SAMPLES`] good samples in a
//! row; the motors restart only with a fresh arm.
//!
//! Frozen data: a MEMS IMU's six axes carry noise, so [`FROZEN_SAMPLES`] bit-identical
//! samples in a row (20 ms at 1 kHz) mean a stuck sensor or bus, not a still frame. All six
//! axes exactly zero is never a real reading (the accelerometer feels gravity or thrust).

use crate::pipeline::ImuSample;

/// How long the last motor command is held without a usable sample, ms. At hover a
/// 50 ms open-loop hold tilts a typical frame by a few degrees; longer is a gamble.
pub const STALL_RIDE_THROUGH_MS: u32 = 50;
/// Bit-identical samples in a row that make the data "frozen".
pub const FROZEN_SAMPLES: u16 = 20;
/// Good samples in a row that clear a fault.
pub const CLEAR_SAMPLES: u16 = 100;
/// How often a faulted sensor is re-probed, ms.
pub const REPROBE_PERIOD_MS: u32 = 500;

/// What is wrong with the IMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ImuFault {
    /// No data-ready edge.
    Stalled,
    /// Bus reads failed.
    ReadError,
    /// Bit-identical samples.
    Frozen,
    /// All-zero samples.
    AllZero,
}

impl ImuFault {
    /// A short name for the console.
    pub const fn name(self) -> &'static str {
        match self {
            ImuFault::Stalled => "stalled",
            ImuFault::ReadError => "read errors",
            ImuFault::Frozen => "frozen data",
            ImuFault::AllZero => "all-zero data",
        }
    }
}

/// The policy's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuHealth {
    last_good_ms: u32,
    last_problem: ImuFault,
    previous: Option<[u32; 6]>,
    identical: u16,
    good_run: u16,
    fault: Option<ImuFault>,
    last_reprobe_ms: Option<u32>,
}

impl ImuHealth {
    /// Healthy as of `now_ms` (boot).
    pub fn new(now_ms: u32) -> Self {
        Self {
            last_good_ms: now_ms,
            last_problem: ImuFault::Stalled,
            previous: None,
            identical: 0,
            good_run: 0,
            fault: None,
            last_reprobe_ms: None,
        }
    }

    /// The standing fault (set once the ride-through ran out, cleared by good data).
    pub fn fault(&self) -> Option<ImuFault> {
        self.fault
    }

    /// Classifies a sample: `None` if the loop may use it, else what is wrong with it.
    pub fn check_sample(&mut self, now_ms: u32, sample: &ImuSample) -> Option<ImuFault> {
        let [gx, gy, gz] = sample.gyro_radps;
        let [ax, ay, az] = sample.accel_mps2;
        let raw = [gx, gy, gz, ax, ay, az].map(f32::to_bits);
        let problem = if raw.iter().all(|b| *b & 0x7FFF_FFFF == 0) {
            Some(ImuFault::AllZero)
        } else if self.previous == Some(raw) {
            self.identical = self.identical.saturating_add(1);
            (self.identical + 1 >= FROZEN_SAMPLES).then_some(ImuFault::Frozen)
        } else {
            self.identical = 0;
            None
        };
        self.previous = Some(raw);
        match problem {
            Some(p) => self.problem(p),
            None => {
                self.last_good_ms = now_ms;
                self.good_run = self.good_run.saturating_add(1);
                if self.good_run >= CLEAR_SAMPLES {
                    self.fault = None;
                    self.last_reprobe_ms = None;
                }
            }
        }
        problem
    }

    /// No sample this time (timeout or read error).
    pub fn problem(&mut self, fault: ImuFault) {
        self.last_problem = fault;
        self.good_run = 0;
    }

    /// The fault that ends the ride-through at `now_ms`, once (`None` while riding through,
    /// healthy, or already faulted).
    pub fn expire(&mut self, now_ms: u32) -> Option<ImuFault> {
        if self.fault.is_some() || self.good_run > 0 {
            return None;
        }
        if now_ms.wrapping_sub(self.last_good_ms) < STALL_RIDE_THROUGH_MS {
            return None;
        }
        self.fault = Some(self.last_problem);
        self.fault
    }

    /// Whether the adapter should re-initialise the sensor now.
    pub fn reprobe_due(&mut self, now_ms: u32) -> bool {
        if self.fault.is_none() {
            return false;
        }
        let due = self
            .last_reprobe_ms
            .is_none_or(|t| now_ms.wrapping_sub(t) >= REPROBE_PERIOD_MS);
        if due {
            self.last_reprobe_ms = Some(now_ms);
        }
        due
    }
}
