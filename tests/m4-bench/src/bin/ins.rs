//! Instruction counts of the 14-state INS (issue 7): one predict (state + covariance), and
//! the corrections — GPS position (3 rows), GPS velocity (3), baro (1), mag (2 heading rows)
//! and all four together ("full", the reference's 10-row 0x3FF correction). Regions:
//! 1 predict, 2 GPS position, 3 GPS velocity, 4 baro, 5 mag, 6 full correction.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use flight_app::estimation::ins::{Config, Filter};
    use m4_bench::{exit, m4count_marker};

    let mut f = Filter::new(Config::default());
    let gyro = [0.001_f32, -0.002, 0.003];
    let accel = [0.01_f32, -0.02, -9.80];
    let mag = [399.0_f32, 3.0, 1601.0];
    // Warm up as in the static scenario so P has its usual fill-in and nothing is gated.
    for k in 0..2000u32 {
        let _ = f.predict(black_box(gyro), black_box(accel), 0.002);
        if k % 50 == 49 {
            let _ = f.fuse_gps_position(black_box([0.0; 3]), true);
            let _ = f.fuse_gps_velocity(black_box([0.0; 3]));
        }
        if k % 10 == 3 {
            let _ = f.fuse_baro(black_box(0.0));
        }
        if k % 10 == 7 {
            let _ = f.fuse_mag(black_box(mag));
        }
    }
    m4count_marker();
    let _ = black_box(f.predict(black_box(gyro), black_box(accel), black_box(0.002)));
    m4count_marker();
    let _ = black_box(f.fuse_gps_position(black_box([0.01, -0.01, 0.02]), true));
    m4count_marker();
    let _ = black_box(f.fuse_gps_velocity(black_box([0.001, -0.001, 0.002])));
    m4count_marker();
    let _ = black_box(f.fuse_baro(black_box(-0.01)));
    m4count_marker();
    let _ = black_box(f.fuse_mag(black_box(mag)));
    m4count_marker();
    let _ = black_box(f.fuse_gps_position(black_box([0.01, -0.01, 0.02]), true));
    let _ = black_box(f.fuse_gps_velocity(black_box([0.001, -0.001, 0.002])));
    let _ = black_box(f.fuse_baro(black_box(-0.01)));
    let _ = black_box(f.fuse_mag(black_box(mag)));
    m4count_marker();
    black_box(&f);
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
