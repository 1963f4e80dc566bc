//! Owns the watchdog handle. Tasks check in; the watchdog is fed only while every
//! registered task has checked in since the last feed, so a stuck task is a reset.

use core::sync::atomic::{AtomicU32, Ordering};

use embassy_nrf::wdt::WatchdogHandle;
use embassy_time::{Duration, Ticker};

/// One bit per supervised task.
#[derive(Clone, Copy, defmt::Format)]
#[repr(u32)]
pub enum Watched {
    /// The status LED task.
    StatusLed = 1 << 0,
    /// The radio task.
    Radio = 1 << 1,
    /// PPM capture (transmitter role, PPM input).
    PpmIn = 1 << 2,
    /// PPM output (receiver role).
    PpmOut = 1 << 3,
    /// JR pin 5 line (transmitter role).
    JrLine = 1 << 4,
    /// HM-10 UART.
    Hm10 = 1 << 5,
    /// Battery ADC.
    Battery = 1 << 6,
    /// Bind button.
    Button = 1 << 7,
    /// Settings storage.
    Settings = 1 << 8,
    /// The module core's periodic work.
    App = 1 << 9,
}

static EXPECTED: AtomicU32 = AtomicU32::new(0);
static CHECKED_IN: AtomicU32 = AtomicU32::new(0);

/// Registers a task before it starts: from then on it must check in.
pub fn expect(task: Watched) {
    EXPECTED.fetch_or(task as u32, Ordering::Relaxed);
}

/// Called by a task at least every 100 ms.
pub fn check_in(task: Watched) {
    CHECKED_IN.fetch_or(task as u32, Ordering::Relaxed);
}

/// For a task with nothing (left) to do: checks in forever.
pub async fn idle(task: Watched) -> ! {
    loop {
        check_in(task);
        embassy_time::Timer::after_millis(50).await;
    }
}

#[embassy_executor::task]
pub async fn supervisor_task(mut watchdog: WatchdogHandle) {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        ticker.next().await;
        let expected = EXPECTED.load(Ordering::Relaxed);
        if CHECKED_IN.load(Ordering::Relaxed) & expected == expected {
            CHECKED_IN.store(0, Ordering::Relaxed);
            watchdog.pet();
        }
    }
}
