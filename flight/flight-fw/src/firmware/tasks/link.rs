//! Owns the RFM22B and runs the link task's body, `flight_app::app::link_task`, on it:
//! what `FlightApp::next_link_step` says (a bind window the console opened, the TauLink
//! follower or OpenLRSng receiver with the app as its hooks, or nothing until the owner
//! binds), the chip lent to OpenLRSng and back by `openlrs::dual::DualRadio`. This task
//! only builds the driver and logs what a step reports.
//!
//! The RFM22B's SPI transfers block (`BlockingAsync` over the polled SPI3) rather than
//! await DMA: a register access is 2–3 bytes, ≈ 5 µs at 5.25 MHz, while an awaited
//! transfer parks the task and comes back through the executor; the flight loop has its
//! own interrupt executor, so only the thread-mode tasks wait, at most a FIFO burst
//! (≈ 100 µs). The driver's futures then never pend inside a register access, and the
//! image carries no DMA transfer futures for the radio (issue 33).

use defmt::{info, warn};
use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_time::{Delay, Instant};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_app::app::FAILSAFE_US;
use flight_app::app::link_task::{LinkEvent, run_link_step};
use openlrs::dual::DualRadio;
use radio_rfm22b::{Rfm22b, TxPower};

use crate::firmware::board::Radio;
use crate::firmware::link_radio::EmbassyClock;
use crate::firmware::shared::SharedApp;

#[embassy_executor::task]
pub async fn link_task(radio: Radio) {
    let Radio { spi, nsel, nirq } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(BlockingAsync::new(spi), nsel);
    // SDN is tied low on these boards: software reset only. Bind mode drops to the lowest
    // power step by itself (`RadioConfig::reduced_power`).
    let driver = Rfm22b::new_without_sdn(device, nirq, Delay);
    let mut chip = DualRadio::new(driver, TxPower::MAX, || Instant::now().as_micros());
    let mut clock = EmbassyClock;
    loop {
        match run_link_step(&SharedApp, &mut chip, &mut clock, FAILSAFE_US).await {
            Some(LinkEvent::Bound {
                bind_id,
                authenticated,
            }) => info!(
                "bound to link {:08x} (authenticated: {})",
                bind_id, authenticated
            ),
            Some(LinkEvent::BindRefused(why)) => warn!("bind not made: {}", why.describe()),
            Some(LinkEvent::BoundOpenLrs { rf_magic }) => {
                info!("bound to OpenLRSng link {:08x}", rf_magic)
            }
            Some(LinkEvent::RadioFailed) => warn!("link stopped: radio error"),
            None => {}
        }
    }
}
