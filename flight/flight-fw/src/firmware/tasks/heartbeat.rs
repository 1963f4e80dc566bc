//! Blinks the blue heartbeat LED at 1 Hz so a running scheduler is visible.

use embassy_stm32::gpio::Output;
use embassy_time::{Duration, Ticker};

use flight_core::app::Task;

use crate::firmware::shared::check_in;

#[embassy_executor::task]
pub async fn heartbeat_task(mut led: Output<'static>) {
    let mut ticker = Ticker::every(Duration::from_millis(50));
    let mut tick = 0u32;
    loop {
        ticker.next().await;
        check_in(Task::Heartbeat);
        tick = tick.wrapping_add(1);
        // Active low: 100 ms on, 900 ms off.
        if tick % 20 < 2 {
            led.set_low();
        } else {
            led.set_high();
        }
    }
}
