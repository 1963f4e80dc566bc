//! The MS5611 on I2C1 (address 0x77, OSR 1024: two 2.3 ms conversions per reading) at 50 Hz:
//! each altitude, or `None` for a failed reading, goes to `FlightApp::on_baro` (climb rate for
//! the failsafe descent; the baro's health, `flight_app::app::BaroHealth`: a failing baro is
//! declared failed there, never a reset). The task cannot hang: every transaction is under a
//! timeout (`i2c_bus::TimedI2c`), and the bus is cleared (`i2c_bus::recover`) and the driver
//! and sensor initialised afresh at boot and after every failure, at the pace the app asks
//! (`FlightApp::baro_retry_ms`).

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Ticker, Timer};
use ms5611::{Ms5611, Oversampling};

use crate::firmware::board::{BARO_ADDRESS, Baro};
use crate::firmware::i2c_bus::TimedI2c;
use crate::firmware::shared::{now_ms, with_app};

/// The reading period, ms (50 Hz).
const PERIOD_MS: u64 = 20;

#[embassy_executor::task]
pub async fn baro_task(mut baro: Baro) {
    let mut delay = Delay;
    loop {
        if !baro.recover_bus() {
            warn!("I2C1: SDA still held low after the bus clear");
        }
        let bus = TimedI2c(baro.driver());
        match Ms5611::new(bus, BARO_ADDRESS, Oversampling::Osr1024, &mut delay).await {
            Ok(mut sensor) => {
                info!("MS5611 up");
                let mut ticker = Ticker::every(Duration::from_millis(PERIOD_MS));
                loop {
                    ticker.next().await;
                    match sensor.measure(&mut delay).await {
                        Ok(m) => with_app(|a| a.on_baro(now_ms(), Some(m.altitude_m))),
                        Err(e) => {
                            warn!("MS5611 read: {}", defmt::Debug2Format(&e));
                            break;
                        }
                    };
                }
            }
            Err(e) => warn!("MS5611 unavailable: {}", defmt::Debug2Format(&e)),
        }
        let retry_ms = with_app(|a| {
            a.on_baro(now_ms(), None);
            a.baro_retry_ms()
        })
        .unwrap_or(1_000);
        Timer::after(Duration::from_millis(u64::from(retry_ms))).await;
    }
}
