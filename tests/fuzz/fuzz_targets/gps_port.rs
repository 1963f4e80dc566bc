//! The flight controller's GPS port (`FlightApp::on_gps_bytes`): fuzzed UART bytes, in
//! fuzzed chunk sizes, through the UBX parser into the boot configuration, the estimator
//! (the full INS flying, `ins.mode ins`) and the telemetry `Gps` message.
//!
//! Invariants: nothing panics; the configuration only ever hands out whole UBX frames; the
//! attitude estimate stays finite and normalised whatever the receiver claims.
#![no_main]

use flight_app::app::FlightApp;
use flight_app::pipeline::ImuSample;
use flight_app::settings::Settings;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut settings = Settings::default();
    settings
        .set_text("ins.mode", "ins")
        .expect("a factory choice");
    let Some(mut app) = FlightApp::new(settings, 0) else {
        return;
    };
    let level = |i: u32| ImuSample {
        gyro_radps: [(i % 7) as f32 * 1e-4, 0.0, 0.0],
        accel_mps2: [0.0, 0.0, -9.805],
        mag: None,
    };
    // 2.5 s of samples: the INS takes over from the complementary filter.
    let mut t = 0u32;
    for _ in 0..2500 {
        app.on_imu_sample(t, &level(t));
        t += 1;
    }
    let (sizes, bytes) = data.split_at(data.len().min(8));
    let mut rest = bytes;
    let mut k = 0usize;
    while !rest.is_empty() {
        let n = usize::from(sizes.get(k % sizes.len().max(1)).copied().unwrap_or(16)).max(1);
        let (chunk, tail) = rest.split_at(n.min(rest.len()));
        app.on_gps_bytes(t, chunk);
        if let Some(frame) = app.gps_to_send(t) {
            assert!(
                frame.len() >= 8 && frame[0] == 0xB5 && frame[1] == 0x62,
                "{frame:?}"
            );
        }
        for _ in 0..5 {
            app.on_imu_sample(t, &level(t));
            t += 1;
        }
        rest = tail;
        k += 1;
    }
    let Some(side) = app.loop_side() else {
        return;
    };
    let q = side.flight_loop().attitude();
    let norm = q.iter().map(|x| x * x).sum::<f32>();
    assert!((norm - 1.0).abs() < 1e-3, "{q:?}");
});
