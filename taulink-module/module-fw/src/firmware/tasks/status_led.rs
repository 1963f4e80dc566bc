//! Plays the LED pattern of the state the module core last reported
//! (`module_core::status`).

use embassy_nrf::gpio::Output;
use embassy_time::{Duration, Instant, Timer};
use module_core::status::LinkState;

use super::supervisor::{Watched, check_in};
use crate::firmware::shared::LED;

/// LED update step; also the check-in period.
const STEP_MS: u64 = 25;

#[embassy_executor::task]
pub async fn status_led_task(mut led: Output<'static>) {
    let mut state = LinkState::NoRadio;
    let mut started = Instant::now();
    loop {
        check_in(Watched::StatusLed);
        if let Some(next) = LED.try_take() {
            state = next;
            started = Instant::now();
        }
        let elapsed_ms = started.elapsed().as_millis() as u32;
        if state.level_at(elapsed_ms) {
            led.set_high();
        } else {
            led.set_low();
        }
        Timer::after(Duration::from_millis(STEP_MS)).await;
    }
}
