//! Owns the RFM22B: hard reset through SDN, probe, report; keeps retrying while no chip
//! answers.

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use radio_rfm22b::Rfm22b;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;

#[embassy_executor::task]
pub async fn radio_task(radio: Radio) {
    let Radio {
        spim,
        nsel,
        nirq,
        sdn,
    } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spim, nsel);
    let mut rfm = Rfm22b::new(device, nirq, sdn, Delay);
    loop {
        check_in(Watched::Radio);
        // `reset` holds SDN high for 15 ms (full power-down), waits out the
        // power-on reset, then software-resets and waits for chip-ready.
        match rfm.reset().await {
            Ok(chip) => info!("RFM22B found: Si4432 {}", chip.version),
            Err(e) => warn!("radio reset/probe failed: {}", e),
        }
        for _ in 0..10 {
            check_in(Watched::Radio);
            Timer::after(Duration::from_millis(100)).await;
        }
    }
}
