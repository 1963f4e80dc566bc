//! Owns the watchdog handle and feeds it by module-core's check-in policy
//! (`module_core::watchdog`): fed only while every registered task has checked in since the
//! last feed, so a stuck task is a reset.

use embassy_nrf::wdt::WatchdogHandle;
use embassy_time::{Duration, Ticker};
pub use module_core::watchdog::Watched;
use module_core::watchdog::{CheckIns, FEED_PERIOD_MS};

static CHECK_INS: CheckIns = CheckIns::new();

/// Registers a task before it starts: from then on it must check in.
pub fn expect(task: Watched) {
    CHECK_INS.expect(task);
}

/// Called by a task at least every 100 ms.
pub fn check_in(task: Watched) {
    CHECK_INS.check_in(task);
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
    let mut ticker = Ticker::every(Duration::from_millis(u64::from(FEED_PERIOD_MS)));
    loop {
        ticker.next().await;
        if CHECK_INS.poll() {
            watchdog.pet();
        }
    }
}
