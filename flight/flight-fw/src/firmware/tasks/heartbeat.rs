//! The three status LEDs (active low): the blue heartbeat blinks at 1 Hz so a running
//! scheduler is visible; the orange alarm and the blue link show what the app says
//! (`FlightApp::leds`: a standing fault or the failsafe; the link delivering). The
//! BrushedSparky's ERR and RF LEDs (PB4, PB6; the Sparky2's ALARM and LINK) were never driven.

use embassy_stm32::gpio::Output;
use embassy_time::{Duration, Ticker};

use flight_app::app::Task;

use crate::firmware::shared::with_app;

#[embassy_executor::task]
pub async fn heartbeat_task(
    mut heartbeat: Output<'static>,
    mut alarm: Output<'static>,
    mut link: Output<'static>,
) {
    let mut ticker = Ticker::every(Duration::from_millis(50));
    let mut tick = 0u32;
    loop {
        ticker.next().await;
        let Some(leds) = with_app(|a| {
            a.check_in(Task::Heartbeat);
            a.leds()
        }) else {
            continue;
        };
        tick = tick.wrapping_add(1);
        // 100 ms on, 900 ms off.
        set(&mut heartbeat, tick % 20 < 2);
        set(&mut alarm, leds.alarm);
        set(&mut link, leds.link);
    }
}

/// An active-low LED on or off.
fn set(led: &mut Output<'static>, on: bool) {
    if on {
        led.set_low();
    } else {
        led.set_high();
    }
}
