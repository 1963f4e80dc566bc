//! Samples the bind button every 10 ms through `module_core::button` (debounce, long press).

use embassy_nrf::gpio::Input;
use embassy_time::{Duration, Ticker};
use module_core::button::{Button, ButtonConfig};

use super::supervisor::{Watched, check_in};
use crate::firmware::shared::{carry_out, now_ms, with_app};

#[embassy_executor::task]
pub async fn button_task(pin: Input<'static>) {
    let mut button = Button::new(ButtonConfig::default(), now_ms());
    let mut ticker = Ticker::every(Duration::from_millis(10));
    loop {
        check_in(Watched::Button);
        // Wired to GND with a pull-up: low is pressed.
        if let Some(event) = button.on_sample(pin.is_low(), now_ms()) {
            defmt::info!("bind button: {}", event);
            carry_out(with_app(|app| app.on_button(event)).flatten());
        }
        ticker.next().await;
    }
}
