//! Shows the link state on the status LED with the patterns of `module_core::status`.

use embassy_nrf::gpio::Output;
use embassy_time::{Duration, Timer};
use module_core::status::LinkState;

use super::supervisor::{Watched, check_in};

#[embassy_executor::task]
pub async fn status_led_task(mut led: Output<'static>) {
    // Until the link task publishes its state, show "searching".
    let state = LinkState::Searching;
    loop {
        let (on_ms, off_ms) = state.blink();
        led.set_high();
        wait_checking_in(on_ms).await;
        if off_ms > 0 {
            led.set_low();
            wait_checking_in(off_ms).await;
        }
    }
}

/// Sleeps in 50 ms steps so the supervisor keeps hearing from us.
async fn wait_checking_in(ms: u32) {
    let mut left = ms;
    while left > 0 {
        check_in(Watched::StatusLed);
        let step = left.min(50);
        Timer::after(Duration::from_millis(u64::from(step))).await;
        left -= step;
    }
}
