//! Owns the RFM22B and runs the module core's link task body on it,
//! `module_core::link_task::run_link_step`: the core's session steps (probe, the master or
//! follower loop, OpenLRSng's transmitter, the binds) on the chip, lent to OpenLRSng and
//! back by `openlrs::dual::DualRadio`. What to do next, when to stop and what a bind
//! means are the core's decisions; this task builds the driver, draws the hardware random
//! numbers and logs a radio failure.
//!
//! The RFM22B's SPI transfers block (SPIM2's own busy-wait, `BlockingAsync`) rather than
//! await the END interrupt: a register access is 2–3 bytes, 2–3 µs at 8 MHz, while an
//! awaited transfer parks the task and comes back through the executor, the link's nested
//! `select`s and the timer queue — about 2 000 instructions, ≈ 30 µs at 64 MHz, per
//! transfer, two transfers per register access. A master's `begin_transmit` (six accesses)
//! then took ≈ 480 µs against the slot's 100 µs SPI set-up: every uplink went on air ≈ 300 µs
//! late and the first after each downlink slot was skipped (measured in the PIL, issue 28).

use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_nrf::rng::Rng;
use embassy_time::{Delay, Instant};
use embedded_hal_bus::spi::ExclusiveDevice;
use module_core::link_task::run_link_step;
use module_core::settings::Settings;
use openlrs::dual::DualRadio;
use radio_rfm22b::{Rfm22b, TxPower};

use crate::firmware::board::Radio;
use crate::firmware::link_radio::{EmbassyClock, Ports};
use crate::firmware::shared::with_app;

#[embassy_executor::task]
pub async fn link_task(radio: Radio, boot_settings: Settings) {
    let Ok(device) = ExclusiveDevice::new_no_delay(BlockingAsync::new(radio.spim), radio.nsel);
    let mut rng = Rng::new_blocking(radio.rng);
    let driver = Rfm22b::new(device, radio.nirq, radio.sdn, Delay);
    let power = TxPower::from_step(boot_settings.tx_power);
    let mut chip = DualRadio::new(driver, power, || Instant::now().as_micros());
    // The module's secrets every boot (spec §12): the epoch nonces' seed, the CPace
    // randomness of binds and phone exchanges, new module keys, the phrase salt.
    let mut seed = [0u8; 32];
    rng.blocking_fill_bytes(&mut seed);
    with_app(|app| app.seed_random(&seed));
    let mut clock = EmbassyClock;
    loop {
        let random = rng.blocking_next_u32();
        if let Some(event) = run_link_step(&Ports, &mut chip, &mut clock, random).await {
            defmt::warn!("link: {}", event);
        }
    }
}
