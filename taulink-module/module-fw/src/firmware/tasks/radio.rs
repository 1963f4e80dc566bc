//! Owns the RFM22B: hard reset through SDN, probe, report presence to the module core;
//! keeps retrying while no chip answers. The link itself comes with the link task
//! (see `seams`).

use defmt::{info, warn};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use radio_rfm22b::Bus;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;
use crate::firmware::shared::{carry_out, with_app};

#[embassy_executor::task]
pub async fn radio_task(radio: Radio) {
    let Radio {
        spim,
        nsel,
        nirq,
        mut sdn,
    } = radio;
    let _nirq = nirq; // interrupt-driven link comes with the link task
    let Ok(device) = ExclusiveDevice::new_no_delay(spim, nsel);
    let mut bus = Bus::new(device);
    loop {
        check_in(Watched::Radio);
        // SDN high for ≥ 10 ms powers the chip down completely (datasheet §3.5), then the
        // power-on reset takes up to 16.8 ms; software reset waits for chip-ready after that.
        sdn.set_high();
        Timer::after(Duration::from_millis(15)).await;
        sdn.set_low();
        Timer::after(Duration::from_millis(20)).await;
        let present = match radio_rfm22b::software_reset(&mut bus, &mut Delay, 50).await {
            Ok(()) => match radio_rfm22b::probe(&mut bus).await {
                Ok(chip) => {
                    info!("RFM22B found: Si4432 {}", chip.version);
                    true
                }
                Err(e) => {
                    warn!("radio probe failed: {}", e);
                    false
                }
            },
            Err(e) => {
                warn!("radio reset failed: {}", e);
                false
            }
        };
        carry_out(with_app(|app| app.on_radio_present(present)).flatten());
        for _ in 0..10 {
            check_in(Watched::Radio);
            Timer::after(Duration::from_millis(100)).await;
        }
    }
}
