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
//! copy: the inputs (`flight_app::app::LoopInputs`), its report (`LoopReport`, merged while
//! the report task has not taken it), and a newly designed setup.

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, Ordering};

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::{CriticalSectionRawMutex, ThreadModeRawMutex};
use embassy_sync::signal::Signal;
use embassy_time::Instant;
use flight_app::app::link_task::AppAccess;
use flight_app::app::{FlightApp, LoopInputs, LoopReport, LoopSide};
use flight_app::pipeline::{Controllers, FlightSetup};
use heapless::Vec;
use static_cell::StaticCell;

/// The application's storage: uninitialised RAM (.bss), not an initialiser in flash.
static APP_STORAGE: StaticCell<Option<FlightApp>> = StaticCell::new();
/// The flight loop's side, once the IMU task's.
static LOOP_SIDE_STORAGE: StaticCell<Option<LoopSide>> = StaticCell::new();
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

/// Runs `f` on what `slot` holds (the critical section makes the borrow the only one;
/// `try_borrow_mut` keeps the impossible double borrow from being a panic path).
pub fn with_slot<T, R>(slot: &Slot<T>, f: impl FnOnce(&mut Vec<T, 1>) -> R) -> Option<R> {
    slot.lock(|s| s.try_borrow_mut().ok().map(|mut v| f(&mut v)))
}

/// Takes the value out of `slot`.
pub fn take<T>(slot: &Slot<T>) -> Option<T> {
    with_slot(slot, Vec::pop).flatten()
}

/// Puts `value` in `slot`, replacing what it held.
pub fn put<T>(slot: &Slot<T>, value: T) {
    with_slot(slot, |v| {
        v.clear();
        let _ = v.push(value);
    });
}
/// The loop is alive while it cannot report (re-probing its sensor); the supervisor checks it
/// in for it.
pub static LOOP_ALIVE: AtomicBool = AtomicBool::new(false);

/// Builds the application in its static storage (once): `make` runs with its result
/// written in place, not moved through the stack (the app is ≈ 16 KiB; the boot's frame held
/// several copies when it was returned and moved).
pub fn create(make: impl FnOnce() -> Option<FlightApp>) -> Option<&'static mut FlightApp> {
    APP_STORAGE.try_init_with(make)?.as_mut()
}

/// Moves the loop's side to its static storage, for the IMU task.
pub fn loop_side(app: &mut FlightApp) -> Option<&'static mut LoopSide> {
    LOOP_SIDE_STORAGE
        .try_init_with(|| app.take_loop_side())?
        .as_mut()
}

/// Installs the application (once, before the tasks start; a second call is refused) and
/// fills the loop's mailbox from it.
pub fn install(app: &'static mut FlightApp) {
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
    let mut f = Some(f);
    let mut result = None;
    locked(&mut |app| result = f.take().map(|f| f(app)));
    result
}

/// The lock, the call and the mailbox update, once in the image rather than once per
/// `with_app` caller.
#[inline(never)]
fn locked(f: &mut dyn FnMut(&mut FlightApp)) {
    APP.lock(|cell| {
        let Ok(mut slot) = cell.try_borrow_mut() else {
            return;
        };
        let Some(app) = slot.as_deref_mut() else {
            return;
        };
        f(app);
        with_slot(&LOOP_INPUTS, |m| {
            if let Some(mailbox) = m.first_mut() {
                app.loop_inputs_into(mailbox);
            }
        });
    });
}

/// The installed application, as the shared task bodies (`flight_app::app::link_task`)
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
