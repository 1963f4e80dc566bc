//! Owns the independent watchdog. Tasks check in; the watchdog is fed only while every
//! registered task has checked in since the last feed, so a stuck task is a reset, not a
//! runaway motor.

use core::sync::atomic::{AtomicU32, Ordering};

use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_time::{Duration, Ticker};

/// One bit per supervised task.
#[derive(Clone, Copy)]
#[repr(u32)]
pub enum Watched {
    /// The heartbeat task.
    Heartbeat = 1 << 0,
    /// The radio task.
    Radio = 1 << 1,
}

const ALL: u32 = Watched::Heartbeat as u32 | Watched::Radio as u32;
static CHECKED_IN: AtomicU32 = AtomicU32::new(0);

/// Called by a task at least every 100 ms.
pub fn check_in(task: Watched) {
    CHECKED_IN.fetch_or(task as u32, Ordering::Relaxed);
}

#[embassy_executor::task]
pub async fn supervisor_task(mut watchdog: IndependentWatchdog<'static, IWDG>) {
    watchdog.unleash();
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        ticker.next().await;
        if CHECKED_IN.load(Ordering::Relaxed) & ALL == ALL {
            CHECKED_IN.store(0, Ordering::Relaxed);
            watchdog.pet();
        }
    }
}
