//! What `flight_app::app::FlightApp` adds around the flight loop, as the IMU task calls it:
//! one `on_imu_sample` (IMU fault checks, the loop step, alerts, identification hand-off)
//! next to one bare `FlightLoop::step` on the same kind of sample, both disarmed (arming
//! needs the link, which this bench does not run), and one `on_imu_missing` (ride-through).
//! The flight log's cost in the loop: ten `on_imu_sample`s with `log.profile off`, then ten
//! with `full` (every topic every loop: the ring is drained between the two, as the logging
//! task drains it, outside the regions).
//! m4count regions: 1 = `FlightApp::new` (setup and gain design), 3 = `on_imu_sample`
//! (factory settings: `log.profile flight`), 5 = `FlightLoop::step`, 7 = `on_imu_missing`,
//! 9 = ten `on_imu_sample` logging off, 11 = ten logging `full`; the even regions are setup.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use flight_app::app::{FlightApp, ImuFault};
    use flight_app::logging::Profile;
    use flight_app::pipeline::{FlightLoop, ImuSample, LinkInput, from_settings};
    use flight_app::settings::{Settings, handles};
    use m4_bench::{exit, m4count_marker};

    // Real sensors are noisy: bit-identical samples are the frozen-data fault.
    let sample = |t: u32| ImuSample {
        gyro_radps: [0.01 + (t % 7) as f32 * 1e-4, -0.02, 0.005],
        accel_mps2: [0.1, -0.2, -9.8],
        mag: None,
    };
    m4count_marker();
    let Some(mut app) = FlightApp::new(black_box(Settings::default()), 0) else {
        exit()
    };
    m4count_marker();
    let Ok(setup) = from_settings(&Settings::default()) else {
        exit()
    };
    let mut fl = FlightLoop::new(setup.loop_config, setup.mixer, None);
    let link = LinkInput::default();
    let mut t = 0u32;
    for _ in 0..100 {
        app.on_imu_sample(t, &sample(t));
        fl.step(t, &sample(t), &link, None);
        t += 1;
    }
    let s = black_box(sample(t));
    m4count_marker();
    let step = app.on_imu_sample(t, &s);
    m4count_marker();
    black_box(step);
    m4count_marker();
    let out = fl.step(t, &s, &link, None);
    m4count_marker();
    black_box(out);
    t += 1;
    m4count_marker();
    let step = app.on_imu_missing(t, black_box(ImuFault::Stalled));
    m4count_marker();
    black_box(step);
    let logging = |profile: Profile| {
        let mut s = Settings::default();
        s.put(handles::LOG_PROFILE, profile.index()).ok()?;
        FlightApp::new(black_box(s), 0)
    };
    let (Some(mut off), Some(mut full)) = (logging(Profile::Off), logging(Profile::Full)) else {
        exit()
    };
    for t in 0..100 {
        off.on_imu_sample(t, &sample(t));
        full.on_imu_sample(t, &sample(t));
        while full.take_log_entry().is_some() {}
    }
    m4count_marker();
    for t in 100..110 {
        black_box(off.on_imu_sample(t, &black_box(sample(t))));
    }
    m4count_marker();
    m4count_marker();
    for t in 100..110 {
        black_box(full.on_imu_sample(t, &black_box(sample(t))));
    }
    m4count_marker();
    black_box(full.take_log_entry());
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
