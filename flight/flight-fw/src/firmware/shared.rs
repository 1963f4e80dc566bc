//! State shared between the tasks, and between them and the flight loop.
//!
//! ```text
//!   thread-mode tasks ── with_app ──▶ FlightApp (ThreadModeRawMutex: never masks an interrupt)
//!          │ after each call: FlightApp::loop_inputs_into ──▶ LOOP_INPUTS ─┐
//!          │                                                              ▼ (take)
//!   loop_report task ◀── REPORTED ── LOOP_REPORT (merged) ◀── imu task: LoopSide::step ─▶ motors
//!          │ on_loop_report, a designed setup ──▶ SETUP ──▶ (installed while disarmed)
//! ```
//!
//! The application is reached only from thread mode, under a mutex that does not mask
//! interrupts: the flight loop, in its interrupt executor, preempts any task's call, however
//! long (a console `status`, a link step). The loop never takes that lock; it trades with the
//! app through three mailboxes under critical sections a few hundred cycles long, each a
//! copy: the inputs (`flight_core::app::LoopInputs`), its report (`LoopReport`, merged while
//! the report task has not taken it), and a newly designed setup.

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, Ordering};

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::{CriticalSectionRawMutex, ThreadModeRawMutex};
use embassy_sync::signal::Signal;
use embassy_time::Instant;
use flight_core::app::link_task::AppAccess;
use flight_core::app::{FlightApp, LoopInputs, LoopReport};
use flight_core::pipeline::{Controllers, FlightSetup};
use heapless::Vec;
use static_cell::StaticCell;

/// The application's storage: uninitialised RAM (.bss), not an initialiser in flash.
static APP_STORAGE: StaticCell<FlightApp> = StaticCell::new();
static APP: Mutex<ThreadModeRawMutex, RefCell<Option<&'static mut FlightApp>>> =
    Mutex::new(RefCell::new(None));

/// A mailbox of one: empty, or the one value put last. (A `heapless::Vec` rather than an
/// `Option`: its empty state is all zeros, so the static lives in .bss, not as an initial
/// value in flash.)
pub type Slot<T> = Mutex<CriticalSectionRawMutex, RefCell<Vec<T, 1>>>;

/// What the loop takes before each step (empty until the app is installed).
pub static LOOP_INPUTS: Slot<LoopInputs> = Mutex::new(RefCell::new(Vec::new()));
/// The loop's reports the report task has not taken yet, merged.
pub static LOOP_REPORT: Slot<LoopReport> = Mutex::new(RefCell::new(Vec::new()));
/// A report waits.
pub static REPORTED: Signal<CriticalSectionRawMutex, ()> = Signal::new();
/// A designed setup for the loop to install while disarmed.
pub static SETUP: Slot<(FlightSetup, Controllers)> = Mutex::new(RefCell::new(Vec::new()));

/// Takes the value out of `slot`.
pub fn take<T>(slot: &Slot<T>) -> Option<T> {
    slot.lock(|s| s.borrow_mut().pop())
}

/// Puts `value` in `slot`, replacing what it held.
pub fn put<T>(slot: &Slot<T>, value: T) {
    slot.lock(|s| {
        let mut s = s.borrow_mut();
        s.clear();
        let _ = s.push(value);
    });
}
/// The loop is alive while it cannot report (re-probing its sensor); the supervisor checks it
/// in for it.
pub static LOOP_ALIVE: AtomicBool = AtomicBool::new(false);

/// Installs the application (once, before the tasks start; a second call is refused) and
/// fills the loop's mailbox from it.
pub fn install(app: FlightApp) {
    let Some(app) = APP_STORAGE.try_init(app) else {
        return;
    };
    put(&LOOP_INPUTS, app.loop_inputs());
    APP.lock(|cell| {
        if let Ok(mut slot) = cell.try_borrow_mut() {
            *slot = Some(app);
        }
    });
}

/// Runs `f` on the application (thread mode only); `None` before it is installed. The
/// loop's mailbox follows whatever `f` changed.
pub fn with_app<R>(f: impl FnOnce(&mut FlightApp) -> R) -> Option<R> {
    APP.lock(|cell| {
        let mut slot = cell.try_borrow_mut().ok()?;
        let app = slot.as_deref_mut()?;
        let result = f(app);
        publish(app);
        Some(result)
    })
}

/// The loop's mailbox brought up to date with `app` (one copy of this code, not one per
/// `with_app` caller).
#[inline(never)]
fn publish(app: &mut FlightApp) {
    LOOP_INPUTS.lock(|m| {
        if let Some(mailbox) = m.borrow_mut().first_mut() {
            app.loop_inputs_into(mailbox);
        }
    });
}

/// The installed application, as the shared task bodies (`flight_core::app::link_task`)
/// reach it.
pub struct SharedApp;

impl AppAccess for SharedApp {
    fn with_app<R>(&self, f: impl FnOnce(&mut FlightApp) -> R) -> Option<R> {
        with_app(f)
    }
}

/// The loop's check-in while it cannot report (its sensor re-probing): the supervisor passes
/// it on.
pub fn loop_alive() {
    LOOP_ALIVE.store(true, Ordering::Relaxed);
}

/// Milliseconds since boot (wrapping), the application's clock.
pub fn now_ms() -> u32 {
    Instant::now().as_millis() as u32
}
