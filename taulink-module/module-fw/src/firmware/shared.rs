//! State shared between tasks: the module core behind a critical-section mutex (every call
//! is short and never awaits), and the signals that carry its actions to the tasks that
//! carry them out.

use core::cell::RefCell;

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::Instant;
use module_core::app::{Action, App};
use module_core::settings::Settings;
use module_core::status::LinkState;
use static_cell::StaticCell;

use module_core::air::AirLink;
use module_core::handset::Handset;

/// The module core as the firmware instantiates it.
pub type FirmwareApp = App<AirLink, Handset>;

/// The core's storage: uninitialised RAM (.bss), not a 4 KiB initialiser in flash.
static APP_STORAGE: StaticCell<FirmwareApp> = StaticCell::new();
static APP: Mutex<CriticalSectionRawMutex, RefCell<Option<&'static mut FirmwareApp>>> =
    Mutex::new(RefCell::new(None));

/// The state the LED shows.
pub static LED: Signal<CriticalSectionRawMutex, LinkState> = Signal::new();
/// Settings to persist.
pub static SAVE: Signal<CriticalSectionRawMutex, Settings> = Signal::new();

/// Installs the core (once, before the tasks start; a second call is refused).
pub fn install(app: FirmwareApp) {
    let Some(app) = APP_STORAGE.try_init(app) else {
        return;
    };
    APP.lock(|cell| {
        if let Ok(mut slot) = cell.try_borrow_mut() {
            *slot = Some(app);
        }
    });
}

/// Runs `f` on the core; `None` before it is installed.
pub fn with_app<R>(f: impl FnOnce(&mut FirmwareApp) -> R) -> Option<R> {
    APP.lock(|cell| cell.try_borrow_mut().ok()?.as_deref_mut().map(f))
}

/// Hands an action of the core to the task that carries it out.
pub fn carry_out(action: Option<Action>) {
    match action {
        Some(Action::Led(state)) => LED.signal(state),
        Some(Action::Save(settings)) => SAVE.signal(settings),
        None => {}
    }
}

/// Microseconds since boot: the link's clock, and the CRSF frames' time stamps.
pub fn now_us() -> u64 {
    Instant::now().as_micros()
}

/// Milliseconds since boot, wrapping (the core works on wrapping differences).
pub fn now_ms() -> u32 {
    Instant::now().as_millis() as u32
}
