//! The controller bank the loop switches between: three LQG axes, three rate PIDs and two
//! attitude PIDs, designed together before take-off (the Riccati solves run in f64 and take
//! milliseconds, so arming waits for them, never the loop).

use crate::control::design::{AxisDesign, DesignError, KfNoise, LqrCosts, design_axis};
use crate::control::lqr::{AxisSetpoint, LqgAxis};
use crate::control::pid::{AttitudePid, Pid, PidGains};
use crate::model::AxisModel;

/// Everything the design needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlParams {
    /// Loop period, s.
    pub ts_s: f32,
    /// Roll, pitch, yaw models.
    pub models: [AxisModel; 3],
    /// LQR costs in rate mode (roll, pitch, yaw): per axis, because frame-invariant costs
    /// scale with each axis' β.
    pub rate_costs: [LqrCosts; 3],
    /// LQR costs in attitude mode (roll, pitch, yaw).
    pub attitude_costs: [LqrCosts; 3],
    /// RTKF noise model.
    pub noise: KfNoise,
    /// Rate PID gains (roll, pitch, yaw), output per deg/s.
    pub pid_rate: [PidGains; 3],
    /// Attitude PID outer gain, deg/s per deg.
    pub attitude_kp: f32,
    /// Largest rate the attitude PID may ask for, deg/s.
    pub attitude_max_rate_dps: f32,
    /// Extra whole loop periods between an output and the motors acting on it.
    pub output_delay_samples: u8,
}

/// The designed controllers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controllers {
    lqg: [LqgAxis; 3],
    pid: [Pid; 3],
    attitude_pid: [AttitudePid; 2],
    /// The Riccati solutions they were built from: with the parameters, all that rebuilds
    /// them without solving again ([`Controllers::from_designs`]).
    designs: [AxisDesign; 3],
}

/// |bias state| limit of the RTKF (actuator units): the integral action's authority.
const BIAS_LIMIT: f32 = 0.3;

impl Controllers {
    /// Solves the three axes' LQG gains and builds the PIDs.
    #[inline] // see `from_designs`
    pub fn design(p: &ControlParams) -> Result<Self, DesignError> {
        Ok(Self::from_designs(p, Self::solve(p)?))
    }

    /// The three axes' Riccati solutions (roll, pitch, yaw) for `p`.
    pub fn solve(p: &ControlParams) -> Result<[AxisDesign; 3], DesignError> {
        let ts = f64::from(p.ts_s);
        let mut designs = [None; 3];
        for (((slot, model), rate), attitude) in designs
            .iter_mut()
            .zip(p.models.iter())
            .zip(&p.rate_costs)
            .zip(&p.attitude_costs)
        {
            *slot = Some(design_axis(model, ts, rate, attitude, &p.noise)?);
        }
        let [Some(roll), Some(pitch), Some(yaw)] = designs else {
            return Err(DesignError::BadCost);
        };
        Ok([roll, pitch, yaw])
    }

    /// The controllers `p` and the axes' Riccati solutions `designs` make (as
    /// [`Controllers::design`] found them): no solve, a few thousand instructions. A
    /// resumed flight rebuilds its gains this way (`app::resume`).
    ///
    /// Run once per design, never in the loop: `#[inline]` (with the LQG axes'
    /// constructors) so it is compiled in the crate that calls it — the application's
    /// `flight_app::gains`, built for size — rather than in this crate, built for speed.
    #[inline]
    pub fn from_designs(p: &ControlParams, designs: [AxisDesign; 3]) -> Self {
        let [mr, mp, my] = p.models;
        let [dr, dp, dy] = designs;
        let lqg = [(mr, dr), (mp, dp), (my, dy)].map(|(model, design)| {
            LqgAxis::new(&model, p.ts_s, &design, BIAS_LIMIT)
                .with_output_delay(p.output_delay_samples)
        });
        let pid = p.pid_rate.map(|g| Pid::new(g, p.ts_s));
        let [roll_pid, pitch_pid, _] = pid;
        let attitude_pid = [roll_pid, pitch_pid].map(|rate| {
            AttitudePid::new(p.attitude_kp, 0.0, p.attitude_max_rate_dps, rate, p.ts_s)
        });
        Self {
            lqg,
            pid,
            attitude_pid,
            designs,
        }
    }

    /// The axes' Riccati solutions (roll, pitch, yaw).
    pub fn designs(&self) -> &[AxisDesign; 3] {
        &self.designs
    }

    /// Restarts every controller (arming, taking control back): no stale integrals.
    pub fn reset(&mut self, gyro_dps: [f32; 3]) {
        for (c, g) in self.lqg.iter_mut().zip(gyro_dps) {
            c.reset(g);
        }
        for c in &mut self.pid {
            c.reset();
        }
        for c in &mut self.attitude_pid {
            c.reset();
        }
    }

    /// Tells the three LQG axes what the mixer realised of their last outputs.
    pub fn lqg_realised(&mut self, applied: [f32; 3]) {
        for (c, a) in self.lqg.iter_mut().zip(applied) {
            c.set_realised_output(a);
        }
    }

    /// LQG on all three axes.
    pub fn lqg(&mut self, gyro_dps: [f32; 3], setpoints: [AxisSetpoint; 3]) -> [f32; 3] {
        let mut out = [0.0; 3];
        for ((o, c), (g, s)) in out
            .iter_mut()
            .zip(&mut self.lqg)
            .zip(gyro_dps.into_iter().zip(setpoints))
        {
            *o = c.update(g, s);
        }
        out
    }

    /// Rate PID on all three axes.
    pub fn pid_rate(&mut self, gyro_dps: [f32; 3], rates_dps: [f32; 3]) -> [f32; 3] {
        let mut out = [0.0; 3];
        for ((o, c), (g, r)) in out
            .iter_mut()
            .zip(&mut self.pid)
            .zip(gyro_dps.into_iter().zip(rates_dps))
        {
            *o = c.update(r, g);
        }
        out
    }

    /// Attitude PID on roll and pitch, rate PID on yaw.
    pub fn pid_attitude(
        &mut self,
        gyro_dps: [f32; 3],
        angle_errors_deg: [f32; 2],
        yaw_rate_dps: f32,
    ) -> [f32; 3] {
        let [gr, gp, gy] = gyro_dps;
        let [er, ep] = angle_errors_deg;
        let [ar, ap] = &mut self.attitude_pid;
        let [_, _, yaw] = &mut self.pid;
        [
            ar.update(er, gr),
            ap.update(ep, gp),
            yaw.update(yaw_rate_dps, gy),
        ]
    }
}
