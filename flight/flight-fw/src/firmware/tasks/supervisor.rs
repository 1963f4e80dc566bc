//! Owns the independent watchdog. Tasks check in; the watchdog is fed only while every
//! registered task has checked in since the last feed, so a stuck task is a reset, not a
//! runaway motor.
//!
//! A flash sector erase stalls the CPU for up to 0.8 s (16 KiB sector, RM0090 / datasheet
//! "sector erase time"), longer than the 250 ms timeout. Settings are only written while
//! disarmed, inside [`with_long_timeout`], which stretches the watchdog to 4 s for the write
//! and restores it afterwards.

use core::sync::atomic::{AtomicU32, Ordering};

use embassy_stm32::pac;
use embassy_stm32::pac::iwdg::vals::{Key, Pr};
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_time::{Duration, Ticker};

/// One bit per supervised task.
#[derive(Clone, Copy)]
#[repr(u32)]
pub enum Watched {
    /// The heartbeat task.
    Heartbeat = 1 << 0,
    /// The link (radio) task.
    Link = 1 << 1,
    /// The motor output task.
    Motors = 1 << 2,
    /// The battery task.
    Battery = 1 << 3,
    /// The alert (tone) task.
    Alerts = 1 << 4,
    /// The IMU / flight-loop task.
    Imu = 1 << 5,
    /// The baro task.
    Baro = 1 << 6,
    /// The gain-design task.
    Gains = 1 << 7,
}

const ALL: u32 = Watched::Heartbeat as u32
    | Watched::Link as u32
    | Watched::Motors as u32
    | Watched::Battery as u32
    | Watched::Alerts as u32
    | Watched::Imu as u32
    | Watched::Baro as u32
    | Watched::Gains as u32;
static CHECKED_IN: AtomicU32 = AtomicU32::new(0);

/// Called by a task at least every 100 ms.
pub fn check_in(task: Watched) {
    CHECKED_IN.fetch_or(task as u32, Ordering::Relaxed);
}

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
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        ticker.next().await;
        if CHECKED_IN.load(Ordering::Relaxed) & ALL == ALL {
            CHECKED_IN.store(0, Ordering::Relaxed);
            watchdog.pet();
        }
    }
}
