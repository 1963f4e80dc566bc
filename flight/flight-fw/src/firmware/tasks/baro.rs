//! The MS5611 on I2C1 (address 0x77, OSR 1024: two 2.3 ms conversions per reading) at 50 Hz:
//! pressure → altitude → climb rate for the loop's failsafe descent. An absent or failing
//! baro leaves the climb rate unknown; the loop then descends on throttle alone.

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Instant, Ticker, Timer};
use flight_core::pipeline::ClimbRate;
use flight_core::sensors::ms5611::{Ms5611, Oversampling};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{BARO_ADDRESS, Baro};
use crate::firmware::signals::CLIMB;

#[embassy_executor::task]
pub async fn baro_task(baro: Baro) {
    let mut delay = Delay;
    check_in(Watched::Baro);
    let mut sensor =
        match Ms5611::new(baro.i2c, BARO_ADDRESS, Oversampling::Osr1024, &mut delay).await {
            Ok(s) => s,
            Err(e) => {
                warn!("MS5611 unavailable: {}", defmt::Debug2Format(&e));
                loop {
                    check_in(Watched::Baro);
                    Timer::after(Duration::from_millis(100)).await;
                }
            }
        };
    info!("MS5611 up");
    let mut climb = ClimbRate::new();
    let mut ticker = Ticker::every(Duration::from_millis(20));
    loop {
        ticker.next().await;
        check_in(Watched::Baro);
        match sensor.measure(&mut delay).await {
            Ok(m) => {
                let now_ms = Instant::now().as_millis() as u32;
                let rate = climb.update(now_ms, m.altitude_m);
                CLIMB.lock(|c| c.set(rate));
            }
            Err(e) => {
                warn!("MS5611 read: {}", defmt::Debug2Format(&e));
                CLIMB.lock(|c| c.set(None));
            }
        }
    }
}
