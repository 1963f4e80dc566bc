//! Owns the independent watchdog: fed every `FEED_PERIOD_MS` only when the app's check-in
//! policy (`flight_core::app::Watchdog`) says every supervised task checked in, so a stuck
//! task is a reset, not a runaway motor.
//!
//! A flash sector erase stalls the CPU for up to 0.5 s (16 KiB sector at ×32, DS8626
//! "Flash memory programming"), longer than the 250 ms timeout. Settings are only written
//! while disarmed, inside [`with_long_timeout`], which stretches the watchdog to the period
//! the app's save job asks for (`flight_core::app::SAVE_WATCHDOG_MS`) and restores it
//! afterwards, telling the app's watchdog model both times.

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

/// Runs `f` (a flash write) with a watchdog of `timeout_ms` (at most 8 s: 32 kHz / 64,
/// 12-bit reload), then restores 250 ms (the app's model restores with `on_save_done`).
pub async fn with_long_timeout<R>(timeout_ms: u32, f: impl core::future::Future<Output = R>) -> R {
    // 32 kHz / 64 = 500 Hz: one tick per 2 ms (4 s = 2000 ticks).
    let reload = u16::try_from((timeout_ms / 2).min(0xFFF)).unwrap_or(0xFFF);
    set_timeout(Pr::DIVIDE_BY64, reload);
    with_app(|a| a.on_watchdog_stretched(now_ms(), u32::from(reload) * 2));
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
