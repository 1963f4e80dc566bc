//! The identification EKF (Korken's / Tau Labs' autotune filter, `control/LQG.md` §5), with the
//! exact ZOH model of the LQG branch and causal pairing.
//!
//! State (13): per axis roll, pitch, yaw: ω (deg/s), ν, input bias b, ln β; then one ln τ
//! shared by all axes. Prediction uses the cancellation-free ZOH of `model::discrete`:
//! ω⁺ = ω + β·τ·φ1·ν + β·τ·φ2·(u − b), ν⁺ = e·ν + φ1·(u − b); the parameters are random walks.
//! Jacobian entries w.r.t. ln β and ln τ use d(τφ1)/d ln τ = τ·g, d(τφ2)/d ln τ = −τ·g and
//! de/d ln τ = x·e (x = Ts/τ, g = 1 − (1 + x)e).
//!
//! Timing: Tau Labs predicted with the output computed *in the same loop* as the gyro it
//! corrects with, which biases τ up by about one sample (+11 % at 2.5 ms / 30 ms). Here the
//! filter keeps the outputs it was told about and predicts with the one that actually acted
//! on the airframe during the last period: the previous loop's output, or older when the
//! output path has extra transport delay (`output_delay_samples`).

use crate::model::Phi;
use nalgebra::{SMatrix, SVector};

/// Number of EKF states.
pub const STATES: usize = 13;
const LN_TAU: usize = 12;
type Mat = SMatrix<f32, STATES, STATES>;
type Vector = SVector<f32, STATES>;

/// Filter settings (noises are per loop step).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SysidConfig {
    /// Loop period, s.
    pub ts_s: f32,
    /// Whole loop periods between an output being computed and it starting to act, beyond
    /// the normal one-period hold (0 when the output is written right after the gyro read).
    pub output_delay_samples: u8,
    /// Gyro variance R, (deg/s)²: about 10× the real gyro variance. The joint state/parameter
    /// EKF ignores how its gain depends on β and τ and that the stabilising controller feeds
    /// gyro noise back into u; with R at the true variance ln β of stiff frames (ln β 11)
    /// came out 0.2 low and τ 10–25 % low in simulation, with 10× both are within 0.02 / 2 %.
    /// (Tau Labs used R = 1000 for the raw gyro for the same reason.)
    pub gyro_variance: f32,
    /// Process noise of ω, (deg/s)².
    pub q_rate: f32,
    /// Process noise of ν.
    pub q_torque: f32,
    /// Random walk of the input bias.
    pub q_bias: f32,
    /// Random walk of each ln β.
    pub q_ln_beta: f32,
    /// Random walk of ln τ.
    pub q_ln_tau: f32,
    /// Initial ln β (roll, pitch, yaw): Tau Labs 10, 10, 7.
    pub initial_ln_beta: [f32; 3],
    /// Initial ln τ: −4 (18.3 ms).
    pub initial_ln_tau: f32,
    /// Each parameter's covariance is restarted once, the first time its 1σ falls below
    /// this (0: never). 0.15 (ln units). Tau Labs' initial yaw 7 on a yaw-5 frame (6-DoF,
    /// 5 deg/s noise, 60 s, 0.7 yaw shake cap, 3 τ): +0.035…+0.049 without, +0.015…+0.022
    /// with (with the 0.45 cap: +0.06…+0.14 without).
    pub restart_below_sigma: f32,
}

impl SysidConfig {
    /// Defaults for a loop period, tuned in simulation (tests/quad-sim) for 60 s shakes.
    pub fn new(ts_s: f32) -> Self {
        Self {
            ts_s,
            output_delay_samples: 0,
            gyro_variance: 250.0,
            q_rate: 0.01,
            q_torque: 1e-7,
            q_bias: 1e-10,
            q_ln_beta: 1e-10,
            q_ln_tau: 1e-10,
            initial_ln_beta: [10.0, 10.0, 7.0],
            initial_ln_tau: -4.0,
            restart_below_sigma: 0.15,
        }
    }
}

/// The identification result with its confidence.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Identification {
    /// ln β (roll, pitch, yaw).
    pub ln_beta: [f32; 3],
    /// Shared motor time constant τ, s.
    pub tau_s: f32,
    /// Input bias per axis (actuator units).
    pub bias: [f32; 3],
    /// 1σ of each ln β from the EKF covariance.
    pub sigma_ln_beta: [f32; 3],
    /// 1σ of ln τ (≈ relative σ of τ).
    pub sigma_ln_tau: f32,
    /// RMS gyro innovation per axis (tracked noise, EMA α = 0.9997), deg/s.
    pub gyro_noise_dps: [f32; 3],
    /// Samples processed.
    pub samples: u32,
}

/// The 13-state identification EKF.
#[derive(Debug, Clone, PartialEq)]
pub struct SystemIdentifier {
    cfg: SysidConfig,
    x: Vector,
    p: Mat,
    outputs: [[f32; 3]; 4],
    noise_var: [f32; 3],
    samples: u32,
    /// Whether each parameter's covariance has been restarted.
    restarted: [bool; 4],
}

/// Initial variances of each ln β and of ln τ.
const P0_LN_BETA: f32 = 1.0;
const P0_LN_TAU: f32 = 0.5;
/// State indices of the parameters (ln β roll, pitch, yaw; ln τ) and their initial variances.
const PARAMETERS: [(usize, f32); 4] = [
    (3, P0_LN_BETA),
    (7, P0_LN_BETA),
    (11, P0_LN_BETA),
    (LN_TAU, P0_LN_TAU),
];

fn get(v: &Vector, i: usize) -> f32 {
    v.get(i).copied().unwrap_or(0.0)
}

/// ln β and ln τ are kept inside physically possible ranges so a bad transient cannot
/// overflow exp().
const LN_BETA_RANGE: (f32, f32) = (4.0, 15.0);
const LN_TAU_RANGE: (f32, f32) = (-6.5, -0.7);

impl SystemIdentifier {
    /// A filter at its initial guess.
    pub fn new(cfg: SysidConfig) -> Self {
        let mut x = Vector::zeros();
        let mut p0 = Vector::zeros();
        for (axis, lb) in cfg.initial_ln_beta.iter().enumerate() {
            let base = 4 * axis;
            for (k, (xv, pv)) in [(0.0, 1.0), (0.0, 1.0), (0.0, 0.05), (*lb, P0_LN_BETA)]
                .into_iter()
                .enumerate()
            {
                if let (Some(xe), Some(pe)) = (x.get_mut(base + k), p0.get_mut(base + k)) {
                    *xe = xv;
                    *pe = pv;
                }
            }
        }
        if let (Some(xe), Some(pe)) = (x.get_mut(LN_TAU), p0.get_mut(LN_TAU)) {
            *xe = cfg.initial_ln_tau;
            *pe = P0_LN_TAU;
        }
        Self {
            cfg,
            x,
            p: Mat::from_diagonal(&p0),
            outputs: [[0.0; 3]; 4],
            noise_var: [cfg.gyro_variance; 3],
            samples: 0,
            restarted: [false; 4],
        }
    }

    /// Records the output that will act on the airframe (call once per loop, after
    /// [`Self::update`]): the attitude part the mixer actually realised
    /// (`Mixer::mix_with_applied`), not the controller's request. When the mixer has to
    /// scale the attitude demand down (span > 1, e.g. a noisy yaw PID at the ±1 clamp plus
    /// the shake), telling the filter the request makes every ln β come out low: measured on
    /// the 6-DoF quad at 5 deg/s gyro noise with I_yaw ≈ 3.6·I_roll, −0.03…−0.11 on all
    /// axes (the demand was scaled in 20–40 % of the samples), and ±0.01 once it is told
    /// the realised output.
    pub fn record_output(&mut self, output: [f32; 3]) {
        self.outputs.rotate_right(1);
        if let Some(first) = self.outputs.first_mut() {
            *first = output;
        }
    }

    /// The current ln β estimates (what the shake scales its amplitude by).
    pub fn ln_beta(&self) -> [f32; 3] {
        [get(&self.x, 3), get(&self.x, 7), get(&self.x, 11)]
    }

    /// One loop: predict over the last period with the output that acted during it, then
    /// correct with this gyro sample (deg/s, roll/pitch/yaw).
    pub fn update(&mut self, gyro_dps: [f32; 3]) {
        let applied = self
            .outputs
            .get(usize::from(self.cfg.output_delay_samples))
            .copied()
            .unwrap_or([0.0; 3]);
        self.predict(applied);
        for (axis, y) in gyro_dps.iter().enumerate() {
            self.correct(axis, *y);
        }
        // Round-off makes P drift from symmetric; once per step is enough.
        self.p = (self.p + self.p.transpose()) * 0.5;
        self.samples = self.samples.saturating_add(1);
        self.restart_converged();
    }

    /// Restarts a parameter's covariance (once) when it first converges.
    ///
    /// Why: the information the EKF books for ln β is the squared Jacobian ∂ω/∂ln β, which
    /// is proportional to β̂. Starting above the truth (Tau Labs' yaw 7 on a yaw-5 frame)
    /// books e^{2·2} ≈ 55× too much information in the first second; σ collapses while
    /// the estimate is still far off, and it then creeps towards the truth for minutes
    /// (measured with the 0.45 yaw shake cap: +0.06…+0.14 after 60 s, +0.05…+0.08 after
    /// 120 s). Restarting the covariance once the estimate has arrived near the truth
    /// (estimate kept, cross terms cleared, which keeps P positive semi-definite) rebuilds
    /// it on a good linearisation point.
    fn restart_converged(&mut self) {
        let threshold = self.cfg.restart_below_sigma;
        for ((index, p0), done) in PARAMETERS.iter().zip(self.restarted.iter_mut()) {
            let variance = self.p.get((*index, *index)).copied().unwrap_or(0.0);
            if !*done && variance < threshold * threshold {
                *done = true;
                self.p.row_mut(*index).fill(0.0);
                self.p.column_mut(*index).fill(0.0);
                if let Some(e) = self.p.get_mut((*index, *index)) {
                    *e = *p0;
                }
            }
        }
    }

    fn predict(&mut self, u: [f32; 3]) {
        let ts = self.cfg.ts_s;
        let tau = libm::expf(get(&self.x, LN_TAU));
        let x = ts / tau;
        let phi = Phi::new(x);
        // F = I + E; E has two non-zero rows per axis (ω and ν), each listed as
        // (row, [(column, value); 4]) with unused slots pointing at column 0 with value 0.
        let mut rows = [(0usize, [(0usize, 0.0f32); 4]); 6];
        let mut next = self.x;
        for ((axis, u), pair) in u.iter().enumerate().zip(rows.chunks_exact_mut(2)) {
            let base = 4 * axis;
            let (w, nu, b, lb) = (
                get(&self.x, base),
                get(&self.x, base + 1),
                get(&self.x, base + 2),
                get(&self.x, base + 3),
            );
            let beta = libm::expf(lb);
            let drive = u - b;
            let dw = beta * tau * phi.phi1 * nu + beta * tau * phi.phi2 * drive;
            if let Some(e) = next.get_mut(base) {
                *e = w + dw;
            }
            if let Some(e) = next.get_mut(base + 1) {
                *e = phi.e * nu + phi.phi1 * drive;
            }
            let rate_row = [
                (base + 1, beta * tau * phi.phi1),
                (base + 2, -beta * tau * phi.phi2),
                (base + 3, dw),
                (LN_TAU, beta * tau * phi.g * (nu - drive)),
            ];
            let torque_row = [
                (base + 1, phi.e - 1.0),
                (base + 2, -phi.phi1),
                (LN_TAU, x * phi.e * (nu - drive)),
                (0, 0.0),
            ];
            if let [r0, r1] = pair {
                *r0 = (base, rate_row);
                *r1 = (base + 1, torque_row);
            }
        }
        self.x = next;
        // P' = F·P·Fᵀ exploiting the sparsity of E: rows of F·P first (from the old P),
        // then columns of (F·P)·Fᵀ (from F·P): ≈ 600 multiply-adds instead of 2·13³.
        // (Every index is below STATES by construction; the checks make that visible to the
        // compiler, so nalgebra's view asserts are no panic path.)
        let old = self.p;
        let mut fp = old;
        for (r, entries) in rows.iter().filter(|(r, _)| *r < STATES) {
            let mut row = old.row(*r).into_owned();
            for (c, v) in entries.iter().filter(|(c, _)| *c < STATES) {
                row += old.row(*c) * *v;
            }
            fp.set_row(*r, &row);
        }
        let mut p = fp;
        for (r, entries) in rows.iter().filter(|(r, _)| *r < STATES) {
            let mut col = fp.column(*r).into_owned();
            for (c, v) in entries.iter().filter(|(c, _)| *c < STATES) {
                col += fp.column(*c) * *v;
            }
            p.set_column(*r, &col);
        }
        let c = &self.cfg;
        let q_axis = [c.q_rate, c.q_torque, c.q_bias, c.q_ln_beta];
        let q = Vector::from_fn(|i, _| {
            if i == LN_TAU {
                c.q_ln_tau
            } else {
                q_axis.get(i % 4).copied().unwrap_or(0.0)
            }
        });
        p.set_diagonal(&(p.diagonal() + q));
        self.p = p;
    }

    fn correct(&mut self, axis: usize, gyro_dps: f32) {
        let idx = 4 * axis;
        // `column` asserts its index: out of range is no measurement (never: axis < 3).
        if idx >= STATES {
            return;
        }
        let innovation = gyro_dps - get(&self.x, idx);
        if let Some(v) = self.noise_var.get_mut(axis) {
            *v = 0.9997 * *v + 0.0003 * innovation * innovation;
        }
        let col: Vector = self.p.column(idx).into_owned();
        let s = get(&col, idx) + self.cfg.gyro_variance;
        if !(s.is_finite() && s > 0.0 && innovation.is_finite()) {
            return;
        }
        let k = col / s;
        self.x += k * innovation;
        self.p -= k * col.transpose();
        for a in 0..3 {
            if let Some(lb) = self.x.get_mut(4 * a + 3) {
                *lb = lb.clamp(LN_BETA_RANGE.0, LN_BETA_RANGE.1);
            }
        }
        if let Some(lt) = self.x.get_mut(LN_TAU) {
            *lt = lt.clamp(LN_TAU_RANGE.0, LN_TAU_RANGE.1);
        }
    }

    /// The current result with 1σ confidences.
    pub fn result(&self) -> Identification {
        let d = self.p.diagonal();
        let sigma = |i: usize| libm::sqrtf(get(&d, i).max(0.0));
        Identification {
            ln_beta: self.ln_beta(),
            tau_s: libm::expf(get(&self.x, LN_TAU)),
            bias: [get(&self.x, 2), get(&self.x, 6), get(&self.x, 10)],
            sigma_ln_beta: [sigma(3), sigma(7), sigma(11)],
            sigma_ln_tau: sigma(LN_TAU),
            gyro_noise_dps: self.noise_var.map(libm::sqrtf),
            samples: self.samples,
        }
    }
}
