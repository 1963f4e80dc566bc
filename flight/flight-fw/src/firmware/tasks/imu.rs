//! The flight loop's clock: the MPU9250's data-ready interrupt (EXTI5, PC5). Each edge: one
//! burst read, the board rotation, `FlightApp::on_imu_sample`; no edge within `POLL` or a
//! failed read: `on_imu_missing` (the app's fault policy decides). The motor commands go
//! to the motor task at once (synchronous outputs); a re-probe request re-initialises the
//! sensor. After each step the flight state and gains go to the record a resume after a
//! reset reads (`fault`).

use core::sync::atomic::Ordering;

use defmt::warn;
use embassy_futures::select::{Either, select};
use embassy_time::{Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::app::{FlightApp, ImuFault};
use flight_core::pipeline::ImuSample;
use mpu9250::{Config, Mpu9250, SampleRate};

use crate::firmware::board::{Imu, imu_to_body};
use crate::firmware::fault::with_record;
use crate::firmware::imu_bus::{AliveDelay, IMU_SPI_FAST, ImuBus};
use crate::firmware::shared::{MOTORS, now_ms, with_app};

/// How long to wait for a data-ready edge before telling the app it is missing.
const POLL: Duration = Duration::from_millis(5);

/// `warm`: the first start is a resumed flight's (`Mpu9250::new_warm`: the chip kept its
/// power, the 100 ms device reset is skipped).
#[embassy_executor::task]
pub async fn imu_task(imu: Imu, sample_rate: SampleRate, mut warm: bool) {
    let Imu { spi, cs, mut int } = imu;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, cs);
    let mut bus = ImuBus::new(device);
    let config = Config {
        sample_rate,
        ..Config::default()
    };
    loop {
        IMU_SPI_FAST.store(false, Ordering::Relaxed);
        let mut sensor = if core::mem::take(&mut warm) {
            Mpu9250::new_warm(&mut bus, config, &mut AliveDelay).await
        } else {
            Mpu9250::new(&mut bus, config, &mut AliveDelay).await
        };
        match &sensor {
            // Configured: the sample reads may run at the fast clock.
            Ok(_) => IMU_SPI_FAST.store(true, Ordering::Relaxed),
            Err(e) => warn!("MPU9250: {}", defmt::Debug2Format(e)),
        }
        loop {
            let sample = match &mut sensor {
                Ok(s) => match select(int.wait_for_high(), Timer::after(POLL)).await {
                    Either::First(()) => s.read().await.map_err(|_| ImuFault::ReadError),
                    Either::Second(()) => Err(ImuFault::Stalled),
                },
                // No sensor: INT may float high, so wait the poll period, never spin.
                Err(_) => {
                    Timer::after(POLL).await;
                    Err(ImuFault::Stalled)
                }
            };
            let step = with_app(|a| {
                let now = now_ms();
                let step = match sample {
                    Ok(s) => a.on_imu_sample(
                        now,
                        &ImuSample {
                            gyro_radps: imu_to_body(s.gyro_radps),
                            accel_mps2: imu_to_body(s.accel_mps2),
                            mag: s.mag_ut.map(imu_to_body),
                        },
                    ),
                    Err(cause) => a.on_imu_missing(now, cause),
                };
                keep_for_resume(a, now);
                step
            });
            let Some(step) = step else { continue };
            MOTORS.signal(step.motors);
            if step.reprobe {
                break;
            }
        }
    }
}

/// The flight state and gains a resume after a reset needs, into the no-init record when
/// due (`flight_core::app::resume`).
fn keep_for_resume(app: &mut FlightApp, now_ms: u32) {
    let state = app.resume_state_due(now_ms);
    with_record(|r| {
        if let Some(state) = state {
            r.state = state;
        }
        app.keep_resume_gains(&mut r.gains);
    });
}
