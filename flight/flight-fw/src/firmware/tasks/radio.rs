//! Owns the RFM22B: resets and probes it, reports what it found, and keeps retrying while
//! no chip answers (an unplugged radio must not stop the flight controller).

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use radio_rfm22b::Rfm22b;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;

#[embassy_executor::task]
pub async fn radio_task(radio: Radio) {
    let Radio { spi, nsel, nirq } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, nsel);
    // SDN is tied low on these boards: software reset only.
    let mut rfm = Rfm22b::new_without_sdn(device, nirq, Delay);
    loop {
        check_in(Watched::Radio);
        match rfm.reset().await {
            Ok(chip) => info!("RFM22B found: Si4432 {}", chip.version),
            Err(e) => warn!("radio reset/probe failed: {}", e),
        }
        // Re-check once a second; the watchdog wants to hear from us more often than that.
        for _ in 0..10 {
            check_in(Watched::Radio);
            Timer::after(Duration::from_millis(100)).await;
        }
    }
}
