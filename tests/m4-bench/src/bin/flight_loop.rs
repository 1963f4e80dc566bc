//! Instructions for one full flight-loop iteration, `FlightLoop::step`, exactly as the firmware
//! runs it after each gyro sample: complementary-filter attitude update (accelerometer
//! correction), the arming/failsafe supervisor, the mode switch, roll and pitch, the controller
//! of the active mode and the quad-X mixer. Configuration from the factory settings
//! (`pipeline::from_settings`, 1 kHz), gains designed before the first measured step, the loop
//! armed by the stick gesture (1.2 s of steps, not measured).
//! m4count regions: 1 = gain design, 3 = attitude mode (LQG angle law), 5 = rate PID,
//! 7 = rate LQG — each one step on which the accelerometer is skipped (armed, one sample in
//! 20 corrects the attitude) — and 9 = 20 attitude-mode steps, so one with the
//! accelerometer correction (divide by 20 for the mean), 11 = one step of the
//! system-identification mode (shake + 13-state EKF, switch high set to `sysid`); the even
//! regions are setup. Then 13–32: twenty consecutive attitude-mode steps, one region each
//! (markers back to back); the largest is the one on which the accelerometer corrects,
//! the loop's worst regular step.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use flight_app::pipeline::{
        Controllers, FlightLoop, ImuSample, LinkInput, Source, from_settings,
    };
    use flight_app::settings::Settings;
    use flight_app::supervisor::Sticks;
    use m4_bench::{exit, m4count_marker};

    let Ok(setup) = from_settings(&Settings::default()) else {
        exit()
    };
    m4count_marker();
    let controllers = Controllers::design(&setup.control).ok();
    m4count_marker();
    let mut fl = FlightLoop::new(setup.loop_config, setup.mixer, controllers);
    // A second loop whose switch-high position is the identification mode.
    let mut settings = Settings::default();
    if settings.set_text("mode.switch_high", "sysid").is_err() {
        exit()
    }
    let Ok(sysid_setup) = from_settings(&settings) else {
        exit()
    };
    let mut id_loop = FlightLoop::new(sysid_setup.loop_config, sysid_setup.mixer, controllers);
    let imu = ImuSample {
        gyro_radps: [0.01, -0.02, 0.005],
        accel_mps2: [0.1, -0.2, -9.8],
        mag: None,
    };
    let link = |throttle: f32, yaw: f32, mode_channel: f32| LinkInput {
        up: true,
        sticks: Sticks {
            throttle,
            roll: 0.1,
            pitch: -0.05,
            yaw,
        },
        arm_switch: None,
        mode_channel,
    };
    // Arm: throttle low, yaw right for 1.2 s.
    let mut t = 0u32;
    for _ in 0..1200 {
        fl.step(t, &imu, &link(0.0, 1.0, -1.0), None);
        t += 1;
    }
    // Fly a little so the hover estimate and controllers have state.
    for _ in 0..19 {
        fl.step(t, &imu, &link(0.4, 0.0, -1.0), Some(0.1));
        t += 1;
    }
    let flying = |mode: f32| black_box(link(0.4, 0.02, mode));
    let sample = black_box(imu);
    let attitude = flying(-1.0);
    m4count_marker();
    let out = fl.step(t, &sample, &attitude, Some(0.1));
    m4count_marker();
    black_box(out);
    t += 1;
    // Rate PID (switch middle). Mode change resets happen on the first step: take the second.
    let pid = flying(0.0);
    fl.step(t, &sample, &pid, Some(0.1));
    t += 1;
    m4count_marker();
    let out = fl.step(t, &sample, &pid, Some(0.1));
    m4count_marker();
    black_box(out);
    t += 1;
    let lqg = flying(1.0);
    fl.step(t, &sample, &lqg, Some(0.1));
    t += 1;
    m4count_marker();
    let out = fl.step(t, &sample, &lqg, Some(0.1));
    m4count_marker();
    black_box(out);
    t += 1;
    fl.step(t, &sample, &attitude, Some(0.1));
    t += 1;
    m4count_marker();
    let mut out = fl.step(t, &sample, &attitude, Some(0.1));
    for _ in 0..19 {
        t += 1;
        out = fl.step(t, &sample, &attitude, Some(0.1));
    }
    m4count_marker();
    black_box(out);
    // System identification: arm the second loop, hover, switch high, measure its 2nd step.
    let mut t_id = 0u32;
    for _ in 0..1200 {
        id_loop.step(t_id, &imu, &link(0.0, 1.0, -1.0), None);
        t_id += 1;
    }
    let shake = flying(1.0);
    for _ in 0..2 {
        id_loop.step(t_id, &sample, &shake, Some(0.1));
        t_id += 1;
    }
    m4count_marker();
    let out = id_loop.step(t_id, &sample, &shake, Some(0.1));
    m4count_marker();
    black_box(out);
    if id_loop.identification_in_progress().is_none() {
        exit()
    }
    // Back to the first loop: twenty single steps, so one has the accelerometer correction.
    m4count_marker();
    for _ in 0..20 {
        t += 1;
        let out = fl.step(t, &sample, &attitude, Some(0.1));
        m4count_marker();
        black_box(out);
    }
    // The indoor INS (`ins.mode ins_indoor`, the attitude mode): armed and flying for 2.2 s
    // so the INS has taken over (region 33, setup). Region 34: a regular step (INS predict);
    // 36: a step that fuses a baro reading; 38: 100 steps with the baro at 50 Hz and one
    // indoor pseudo-measurement (divide by 100 for the mean).
    let mut settings = Settings::default();
    if settings.set_text("ins.mode", "ins_indoor").is_err() {
        exit()
    }
    let Ok(ins_setup) = from_settings(&settings) else {
        exit()
    };
    let mut ins_loop = FlightLoop::new(ins_setup.loop_config, ins_setup.mixer, controllers);
    let mut t_ins = 0u32;
    for k in 0..2200u32 {
        if k % 20 == 0 {
            ins_loop.on_baro_altitude(black_box(0.0));
        }
        let input = if k < 1200 {
            link(0.0, 1.0, -1.0)
        } else {
            link(0.4, 0.0, -1.0)
        };
        ins_loop.step(t_ins, &imu, &input, None);
        t_ins += 1;
    }
    if ins_loop.estimator().source() != Source::Ins || !ins_loop.armed() {
        exit()
    }
    m4count_marker();
    let out = ins_loop.step(t_ins, &sample, &attitude, None);
    m4count_marker();
    black_box(out);
    t_ins += 1;
    ins_loop.on_baro_altitude(black_box(0.01));
    m4count_marker();
    let out = ins_loop.step(t_ins, &sample, &attitude, None);
    m4count_marker();
    black_box(out);
    m4count_marker();
    for k in 0..100u32 {
        t_ins += 1;
        if k % 20 == 0 {
            ins_loop.on_baro_altitude(black_box(0.02));
        }
        black_box(ins_loop.step(t_ins, &sample, &attitude, None));
    }
    m4count_marker();
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
