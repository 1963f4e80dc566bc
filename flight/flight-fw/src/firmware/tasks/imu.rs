//! The flight loop's clock: the MPU9250's data-ready interrupt (EXTI5, PC5) at the configured
//! gyro rate. Each edge: one burst read (accel, gyro and — at the AK8963's own 100 Hz — the
//! magnetometer), the board rotation, `FlightLoop::step` with the link's latest sticks and
//! the baro climb rate, and the motor commands handed to the motor task at once (synchronous
//! outputs). Alerts and the arming state go out as the loop reports them; a new setup with
//! solved gains is installed only while disarmed.

use core::sync::atomic::Ordering;

use defmt::{error, info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration, Instant, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::outputs::Command;
use flight_core::pipeline::{Controllers, FlightLoop, FlightSetup, ImuSample, loop_alerts};
use flight_core::report::blocker_bit;
use flight_core::sensors::mpu9250::{Config, Mpu9250, SampleRate};
use flight_core::supervisor::Decision;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{Imu, imu_to_body};
use crate::firmware::imu_bus::{IMU_SPI_FAST, ImuBus};
use crate::firmware::signals::{
    ALERTS, ARMED, CLIMB, FLIGHT_STATE, LINK_INPUT, MOTORS, NEW_SETUP, SYSID,
};

/// A data-ready edge later than this (several periods) means the sensor stalled.
const SAMPLE_TIMEOUT: Duration = Duration::from_millis(20);

fn sensor_config(setup: &FlightSetup) -> Config {
    Config {
        sample_rate: if setup.loop_rate_hz >= 1000 {
            SampleRate::Hz1000
        } else {
            SampleRate::Hz500
        },
        ..Config::default()
    }
}

#[embassy_executor::task]
pub async fn imu_task(imu: Imu, setup: FlightSetup, controllers: Option<Controllers>) {
    let Imu { spi, cs, mut int } = imu;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, cs);
    let mut delay = Delay;
    check_in(Watched::Imu);
    IMU_SPI_FAST.store(false, Ordering::Relaxed);
    let bus = ImuBus::new(device);
    let mut sensor = match Mpu9250::new(bus, sensor_config(&setup), &mut delay).await {
        Ok(s) => {
            // Configured: the sample reads may run at the fast clock.
            IMU_SPI_FAST.store(true, Ordering::Relaxed);
            s
        }
        Err(e) => {
            // Without the IMU nothing may arm. The motors task holds every output stopped;
            // keep checking in so the console stays up to diagnose, and say why each second.
            loop {
                error!("MPU9250 unavailable: {}", defmt::Debug2Format(&e));
                for _ in 0..10 {
                    check_in(Watched::Imu);
                    MOTORS.signal([Command::Stopped; 4]);
                    Timer::after(Duration::from_millis(100)).await;
                }
            }
        }
    };
    info!("MPU9250 up at {} Hz", setup.loop_rate_hz);
    let mut fl = FlightLoop::new(setup.loop_config, setup.mixer, controllers);
    let mut blockers = 0u16;
    loop {
        check_in(Watched::Imu);
        if !ARMED.load(Ordering::Relaxed)
            && let Some((new_setup, gains)) = NEW_SETUP.try_take()
        {
            // Same sensor rate only: a rate change needs the chip reconfigured (next boot).
            fl = FlightLoop::new(new_setup.loop_config, new_setup.mixer, Some(gains));
            info!("new gains installed");
        }
        // INT is latched until any register is read: waiting for the level (not the edge)
        // cannot miss a sample whose edge came while the previous step was still running.
        match select(int.wait_for_high(), Timer::after(SAMPLE_TIMEOUT)).await {
            Either::First(()) => {}
            Either::Second(()) => {
                warn!("IMU data-ready missing");
                // Stop the motors now; the loop's sensor check keeps them stopped.
                MOTORS.signal([Command::Stopped; 4]);
                continue;
            }
        }
        let sample = match sensor.read().await {
            Ok(s) => s,
            Err(e) => {
                warn!("IMU read: {}", defmt::Debug2Format(&e));
                continue;
            }
        };
        let imu = ImuSample {
            gyro_radps: imu_to_body(sample.gyro_radps),
            accel_mps2: imu_to_body(sample.accel_mps2),
            mag: sample.mag_ut.map(imu_to_body),
        };
        let link = LINK_INPUT.lock(|c| c.get());
        let climb = CLIMB.lock(|c| c.get());
        let now_ms = Instant::now().as_millis() as u32;
        let out = fl.step(now_ms, &imu, &link, climb);
        MOTORS.signal(out.motors);
        ARMED.store(out.armed, Ordering::Relaxed);
        if let Decision::ArmRefused(b) = out.decision {
            blockers = blocker_bit(b);
        } else if out.decision == Decision::Armed {
            blockers = 0;
        }
        for alert in loop_alerts(&out).into_iter().flatten() {
            // A full queue already holds more important alerts; the state is in telemetry.
            let _ = ALERTS.try_send(alert);
        }
        FLIGHT_STATE.lock(|c| c.set(Some((out, blockers))));
        if let Some(id) = fl.take_identification() {
            info!("identified: ln β {} τ {} s", id.ln_beta, id.tau_s);
            SYSID.signal(id);
        }
    }
}
