//! The MS5611 on I2C1 (address 0x77, OSR 1024: two 2.3 ms conversions per reading) at 50 Hz:
//! each altitude goes to `FlightApp::on_baro` (climb rate for the failsafe descent). An
//! absent or failing baro reports `None`; the loop then descends on throttle alone.

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Ticker, Timer};
use ms5611::{Ms5611, Oversampling};

use crate::firmware::board::{BARO_ADDRESS, Baro};
use crate::firmware::shared::{now_ms, with_app};

#[embassy_executor::task]
pub async fn baro_task(baro: Baro) {
    let mut delay = Delay;
    with_app(|a| a.on_baro(now_ms(), None));
    let mut sensor =
        match Ms5611::new(baro.i2c, BARO_ADDRESS, Oversampling::Osr1024, &mut delay).await {
            Ok(s) => s,
            Err(e) => {
                warn!("MS5611 unavailable: {}", defmt::Debug2Format(&e));
                loop {
                    with_app(|a| a.on_baro(now_ms(), None));
                    Timer::after(Duration::from_millis(100)).await;
                }
            }
        };
    info!("MS5611 up");
    let mut ticker = Ticker::every(Duration::from_millis(20));
    loop {
        ticker.next().await;
        let altitude = match sensor.measure(&mut delay).await {
            Ok(m) => Some(m.altitude_m),
            Err(e) => {
                warn!("MS5611 read: {}", defmt::Debug2Format(&e));
                None
            }
        };
        with_app(|a| a.on_baro(now_ms(), altitude));
    }
}
