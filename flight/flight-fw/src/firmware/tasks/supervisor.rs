//! Owns the independent watchdog: fed every `FEED_PERIOD_MS` only when the app's check-in
//! policy (`flight_core::app::Watchdog`) says every supervised task checked in, so a stuck
//! task is a reset, not a runaway motor.
//!
//! A flash sector erase stalls the CPU for up to 0.8 s (16 KiB sector, RM0090 / datasheet
//! "sector erase time"), longer than the 250 ms timeout. Settings are only written while
//! disarmed, inside [`with_long_timeout`], which stretches the watchdog to 4 s for the write
//! and restores it afterwards.

use embassy_stm32::pac;
use embassy_stm32::pac::iwdg::vals::{Key, Pr};
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_time::{Duration, Ticker};
use flight_core::app::FEED_PERIOD_MS;

use crate::firmware::shared::{now_ms, with_app};

/// Sets the IWDG period: LSI 32 kHz / prescaler, 12-bit reload.
fn set_timeout(prescaler: Pr, reload: u16) {
    let iwdg = pac::IWDG;
    iwdg.kr().write(|w| w.set_key(Key::RESET)); // feed first: the new period starts full
    iwdg.kr().write(|w| w.set_key(Key::ENABLE)); // unlock PR/RLR
    iwdg.pr().write(|w| w.set_pr(prescaler));
    iwdg.rlr().write(|w| w.set_rl(reload));
    iwdg.kr().write(|w| w.set_key(Key::RESET));
}

/// Runs `f` (a flash write) with a 4 s watchdog, then restores 250 ms.
pub async fn with_long_timeout<R>(f: impl core::future::Future<Output = R>) -> R {
    // 32 kHz / 64 = 500 Hz, 2000 ticks = 4 s.
    set_timeout(Pr::DIVIDE_BY64, 2000);
    let result = f.await;
    // 32 kHz / 32 = 1 kHz, 250 ticks = 250 ms (what IndependentWatchdog::new chose).
    set_timeout(Pr::DIVIDE_BY32, 249);
    result
}

#[embassy_executor::task]
pub async fn supervisor_task(mut watchdog: IndependentWatchdog<'static, IWDG>) {
    watchdog.unleash();
    let mut ticker = Ticker::every(Duration::from_millis(u64::from(FEED_PERIOD_MS)));
    loop {
        ticker.next().await;
        if with_app(|a| a.on_watchdog_poll(now_ms())) == Some(true) {
            watchdog.pet();
        }
    }
}
