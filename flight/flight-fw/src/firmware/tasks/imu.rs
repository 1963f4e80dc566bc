//! The flight loop, in its own interrupt executor above every thread-mode task: the
//! MPU9250's data-ready (EXTI5, PC5) → one burst read → `LoopSide::step` → the motor timers,
//! in one context, so the time from the edge to the motor pulse depends on no other task.
//! No edge within `POLL` or a failed read: `LoopSide::missing` (the app's fault policy
//! decides, a re-probe re-initialises the sensor).
//!
//! The loop's side of the application is this task's alone; it trades with the rest of the
//! app through the mailboxes of `shared` (inputs in, the report out, a designed setup to
//! install while disarmed) and never waits for a task. It counts what it misses
//! (`LoopSide::timing`: edges that came while a step still ran, steps that ran past the
//! next edge) and keeps the flight state a resume after a reset needs (`fault`).

use core::sync::atomic::Ordering;

use defmt::warn;
use embassy_futures::select::{Either, select};
use embassy_time::{Duration, Instant, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_app::app::{ImuFault, LoopInputs, LoopReport, LoopSide};
use flight_app::pipeline::ImuSample;
use mpu9250::{Config, Mpu9250, SampleRate};

use super::motors::Motors;
use crate::firmware::board::{Imu, imu_to_body};
use crate::firmware::fault::with_record;
use crate::firmware::imu_bus::{AliveDelay, IMU_SPI_FAST, ImuBus};
use crate::firmware::shared::{LOOP_INPUTS, LOOP_REPORT, REPORTED, SETUP, now_ms, take, with_slot};

/// How long to wait for a data-ready edge before telling the loop it is missing.
const POLL: Duration = Duration::from_millis(5);

/// `warm`: the first start is a resumed flight's (`Mpu9250::new_warm`: the chip kept its
/// power, the 100 ms device reset is skipped). `motors`: `None` if the outputs could not
/// start (the loop flies on without them, which the console shows).
#[embassy_executor::task]
pub async fn imu_task(
    imu: Imu,
    sample_rate: SampleRate,
    mut warm: bool,
    side: &'static mut LoopSide,
    mut motors: Option<Motors>,
) {
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
            let (reading, edge_us) = match &mut sensor {
                Ok(s) => match select(int.wait_for_high(), Timer::after(POLL)).await {
                    Either::First(()) => {
                        let edge_us = Instant::now().as_micros();
                        (
                            s.read().await.map_err(|_| ImuFault::ReadError),
                            Some(edge_us),
                        )
                    }
                    Either::Second(()) => (Err(ImuFault::Stalled), None),
                },
                // No sensor: INT may float high, so wait the poll period, never spin.
                Err(_) => {
                    Timer::after(POLL).await;
                    (Err(ImuFault::Stalled), None)
                }
            };
            let now = now_ms();
            let inputs = take_inputs(side);
            let (step, report) = match reading {
                Ok(s) => {
                    let sample = ImuSample {
                        gyro_radps: imu_to_body(s.gyro_radps),
                        accel_mps2: imu_to_body(s.accel_mps2),
                        mag: s.mag_ut.map(imu_to_body),
                    };
                    side.step(now, &sample, &inputs)
                }
                Err(cause) => side.missing(now, cause, &inputs),
            };
            if let Some(m) = motors.as_mut() {
                m.apply(&step.motors);
            }
            if let Some(edge_us) = edge_us {
                side.timing(edge_us, Instant::now().as_micros());
            }
            hand_over(report);
            if let Some(state) = side.resume_state_due(now) {
                with_record(|r| r.state = state);
            }
            if step.reprobe {
                break;
            }
        }
    }
}

/// This step's inputs from the mailbox, and a designed setup installed if one waits and the
/// motors are stopped.
fn take_inputs(side: &mut LoopSide) -> LoopInputs {
    let inputs = with_slot(&LOOP_INPUTS, |m| m.first_mut().map(LoopInputs::take));
    let inputs = inputs.flatten().unwrap_or_default();
    if inputs.setup_pending
        && !side.armed()
        && let Some((setup, controllers)) = take(&SETUP)
    {
        side.install(&setup, controllers);
    }
    inputs
}

/// The step's report to the report task (merged into one it has not taken yet).
fn hand_over(report: LoopReport) {
    with_slot(&LOOP_REPORT, |slot| match slot.first_mut() {
        Some(pending) => pending.merge(report),
        None => {
            let _ = slot.push(report);
        }
    });
    REPORTED.signal(());
}
