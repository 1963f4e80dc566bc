//! Owns the independent watchdog: programs it as `flight_app::app::IWDG` (200 ms at the
//! fastest LSI the datasheet allows, 47 kHz; 552 ms at the slowest, 17 kHz) and feeds it at
//! each of the app's polls that says every supervised task is alive
//! (`flight_app::app::Watchdog`: the rule and its margin are there), so a stuck task is a
//! reset, not a runaway motor. Register-level rather than embassy's `IndependentWatchdog`,
//! which computes its reload for a 32 kHz LSI.
//!
//! A flash sector erase stalls the CPU for up to 0.5 s (16 KiB sector at ×32, DS8626
//! "Flash memory programming"), longer than the timeout. Settings are only written while
//! disarmed, inside [`with_long_timeout`], which stretches the watchdog to at least the
//! period the app's save job asks for (`flight_app::app::SAVE_WATCHDOG_MS`) at the fastest
//! LSI and restores it afterwards, telling the app's watchdog model both times.

use core::sync::atomic::Ordering;

use embassy_stm32::Peri;
use embassy_stm32::pac;
use embassy_stm32::pac::iwdg::vals::{Key, Pr};
use embassy_stm32::peripherals::IWDG;
use embassy_time::{Duration, Ticker};
use flight_app::app::{FEED_PERIOD_MS, IWDG as SETTING, IwdgSetting, Task};

use crate::firmware::fault::keep_feed;
use crate::firmware::shared::{LOOP_ALIVE, now_ms, with_app};

/// How long a new prescaler and reload take to reach the LSI domain at most: 5 LSI periods
/// at 17 kHz (RM0090 IWDG_SR: PVU/RVU stay set while an update is in progress), µs.
const UPDATE_US: u32 = 300;

/// The setting flown: the app's, or — the PIL's `iwdg-half` test variant (build.rs, never
/// built by dist) — one of half the feed period, which no feeding meets.
const FLOWN: IwdgSetting = if cfg!(pil_iwdg_half) {
    IwdgSetting::at_least(FEED_PERIOD_MS / 2)
} else {
    SETTING
};

/// Programs `setting` and reloads the counter with it: feed first (the old period starts
/// full while the update crosses into the LSI domain), unlock, write, wait for the update
/// (bounded: a stopped LSI must not hang the board), reload.
fn program(setting: IwdgSetting) {
    let iwdg = pac::IWDG;
    iwdg.kr().write(|w| w.set_key(Key::RESET));
    iwdg.kr().write(|w| w.set_key(Key::ENABLE));
    iwdg.pr()
        .write(|w| w.set_pr(Pr::from_bits(setting.prescaler)));
    iwdg.rlr().write(|w| w.set_rl(setting.reload));
    for _ in 0..UPDATE_US / 10 {
        let sr = iwdg.sr().read();
        if !sr.pvu() && !sr.rvu() {
            break;
        }
        // 10 µs at 168 MHz.
        cortex_m::asm::delay(1_680);
    }
    iwdg.kr().write(|w| w.set_key(Key::RESET));
}

fn feed() {
    pac::IWDG.kr().write(|w| w.set_key(Key::RESET));
}

/// Runs `f` (a flash write) with the watchdog at least `timeout_ms` at the fastest LSI, then
/// restores [`FLOWN`] (the app's model restores with `on_save_done`).
pub async fn with_long_timeout<R>(timeout_ms: u32, f: impl core::future::Future<Output = R>) -> R {
    program(IwdgSetting::at_least(timeout_ms));
    with_app(|a| a.on_watchdog_stretched(now_ms(), timeout_ms));
    let result = f.await;
    program(FLOWN);
    result
}

#[embassy_executor::task]
pub async fn supervisor_task(_iwdg: Peri<'static, IWDG>) {
    // Started, it cannot be stopped until the next reset.
    pac::IWDG.kr().write(|w| w.set_key(Key::START));
    program(FLOWN);
    let mut ticker = Ticker::every(Duration::from_millis(u64::from(FEED_PERIOD_MS)));
    loop {
        ticker.next().await;
        let now = now_ms();
        let loop_alive = LOOP_ALIVE.swap(false, Ordering::Relaxed);
        let fed = with_app(|a| {
            if loop_alive {
                a.check_in(Task::Imu);
            }
            a.on_watchdog_poll(now)
        });
        if fed == Some(true) {
            feed();
            // A resume after a watchdog reset bounds the reset's time with it.
            keep_feed(now);
        }
    }
}
