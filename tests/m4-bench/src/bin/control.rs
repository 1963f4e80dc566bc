//! Instructions for one flight-control cycle on the Cortex-M4F: (a) 3-axis LQG (RTKF update +
//! LQR law, rate mode on roll/pitch/yaw) plus the quad-X mixer; (b) 3-axis PID rate loops plus
//! the same mixer. Gains are designed (f64 DARE) before the first marker, as before take-off;
//! the LQG compensates one sample of output delay (one look-ahead prediction per axis).
//! (c) one step of the identification EKF, for the autotune flight's CPU budget.
//! m4count regions: 1 = gain design (3 axes × Kalman/rate/attitude DARE), 3 = (a), 5 = (b),
//! 7 = (c); the even regions are setup between them.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use flight_app::control::design::{FrameInvariantCosts, KfNoise, design_axis};
    use flight_app::control::lqr::{AxisSetpoint, LqgAxis};
    use flight_app::control::mixer::{Mixer, QUAD_X, ThrustCurve};
    use flight_app::control::pid::{Pid, PidGains};
    use flight_app::model::AxisModel;
    use m4_bench::{exit, m4count_marker};

    let ts = 1.0 / 8000.0;
    let models =
        [(10.0, None), (10.0, None), (7.0, Some(5.0))].map(|(lb, l2): (f32, Option<f32>)| {
            let m = AxisModel::new(lb, 0.03).unwrap_or(AxisModel {
                ln_beta1: 10.0,
                ln_beta2: None,
                tau_s: 0.03,
            });
            match l2 {
                Some(l) => m.with_beta2(l).unwrap_or(m),
                None => m,
            }
        });
    // (0) The f64 gain design for three axes (soft double on the M4F), before take-off.
    m4count_marker();
    let mut lqg = models.map(|m| {
        let costs = FrameInvariantCosts::default().for_beta(m.beta1());
        match design_axis(&m, ts, &costs, &costs, &KfNoise::default()) {
            Ok(d) => LqgAxis::new(&m, ts as f32, &d, 0.3).with_output_delay(1),
            Err(_) => exit(),
        }
    });
    m4count_marker();
    let mixer = Mixer::new(QUAD_X, ThrustCurve::Linear);
    let gyro: [f32; 3] = black_box([12.5, -3.0, 40.0]);
    let setpoint: [f32; 3] = black_box([100.0, 0.0, 30.0]);
    let throttle: f32 = black_box(0.4);

    // (a) LQG cycle.
    m4count_marker();
    let mut u = [0.0f32; 3];
    for ((axis, out), (g, sp)) in lqg
        .iter_mut()
        .zip(u.iter_mut())
        .zip(gyro.iter().zip(setpoint))
    {
        *out = axis.update(*g, AxisSetpoint::Rate { rate_dps: sp });
    }
    let motors = mixer.mix(throttle, u);
    m4count_marker();
    black_box(motors);

    // (b) PID cycle.
    let gains = PidGains::new(2.22e-3, 8.81e-3, 4.84e-5, 5.75e-3);
    let mut pids = [Pid::new(gains, ts as f32); 3];
    m4count_marker();
    let mut v = [0.0f32; 3];
    for ((pid, out), (g, sp)) in pids
        .iter_mut()
        .zip(v.iter_mut())
        .zip(gyro.iter().zip(setpoint))
    {
        *out = pid.update(sp, *g);
    }
    let motors = mixer.mix(throttle, v);
    m4count_marker();
    black_box(motors);

    // (c) One step of the 13-state identification EKF (autotune, not in the normal loop).
    let mut ekf =
        flight_app::sysid::SystemIdentifier::new(flight_app::sysid::SysidConfig::new(ts as f32));
    ekf.record_output(black_box([0.05, -0.02, 0.1]));
    m4count_marker();
    ekf.update(gyro);
    m4count_marker();
    black_box(ekf.result());
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
