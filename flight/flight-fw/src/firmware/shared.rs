//! State shared between tasks: the flight application behind a critical-section mutex
//! (every call is short and never awaits), and the one signal that carries its motor
//! commands to the motor task.
//!
//! ```text
//! imu (MPU9250 EXTI) ─on_imu_sample─▶ FlightApp ─MOTORS─▶ motors
//! link (RFM22B follower) ─on_link_step─▶ FlightApp ◀─on_baro/on_battery── baro, battery
//! console ─on_console_line─▶ FlightApp ─take_save/take_design_request─▶ storage, gains
//! alerts ◀─on_alert_tick── FlightApp ─on_watchdog_poll─▶ supervisor (IWDG)
//! ```

use core::cell::RefCell;

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::Instant;
use flight_core::app::link_task::AppAccess;
use flight_core::app::{FlightApp, Task};
use flight_core::outputs::Command;
use static_cell::StaticCell;

/// Motor commands for outputs 1–4, published once per control loop; the motor task applies
/// them right away so the outputs stay synchronous with the gyro sample.
pub static MOTORS: Signal<CriticalSectionRawMutex, [Command; 4]> = Signal::new();

/// The application's storage: uninitialised RAM (.bss), not an initialiser in flash.
static APP_STORAGE: StaticCell<FlightApp> = StaticCell::new();
static APP: Mutex<CriticalSectionRawMutex, RefCell<Option<&'static mut FlightApp>>> =
    Mutex::new(RefCell::new(None));

/// Installs the application (once, before the tasks start; a second call is refused).
pub fn install(app: FlightApp) {
    let Some(app) = APP_STORAGE.try_init(app) else {
        return;
    };
    APP.lock(|cell| {
        if let Ok(mut slot) = cell.try_borrow_mut() {
            *slot = Some(app);
        }
    });
}

/// Runs `f` on the application; `None` before it is installed.
pub fn with_app<R>(f: impl FnOnce(&mut FlightApp) -> R) -> Option<R> {
    APP.lock(|cell| cell.try_borrow_mut().ok()?.as_deref_mut().map(f))
}

/// The installed application, as the shared task bodies (`flight_core::app::link_task`)
/// reach it.
pub struct SharedApp;

impl AppAccess for SharedApp {
    fn with_app<R>(&self, f: impl FnOnce(&mut FlightApp) -> R) -> Option<R> {
        with_app(f)
    }
}

/// A task that hands the application nothing else checks in with the watchdog policy.
pub fn check_in(task: Task) {
    with_app(|a| a.check_in(task));
}

/// Milliseconds since boot (wrapping), the application's clock.
pub fn now_ms() -> u32 {
    Instant::now().as_millis() as u32
}
