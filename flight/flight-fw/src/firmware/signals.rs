//! Every channel between tasks, in one place: this file is the firmware's data-flow diagram.
//!
//! ```text
//! control ──MOTORS──▶ motors        battery ──ALERTS──▶ alerts (DAC tones)
//!         ──ALERTS──▶ alerts        battery ──BATTERY─▶ control, telemetry
//! console ──SETTINGS (shared)──── storage
//! ```

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::mutex::Mutex;
use embassy_sync::signal::Signal;
use embassy_sync::watch::Watch;
use flight_core::alerts::Alert;
use flight_core::battery::BatteryStatus;
use flight_core::outputs::Command;
use flight_core::settings::Settings;

/// Motor commands for outputs 1–4, published once per control loop; the motor task applies
/// them right away so the outputs stay synchronous with the gyro sample.
pub static MOTORS: Signal<CriticalSectionRawMutex, [Command; 4]> = Signal::new();

/// Alerts to sound. Bounded: a burst beyond 8 drops the newest, the state is in telemetry.
pub static ALERTS: Channel<CriticalSectionRawMutex, Alert, 8> = Channel::new();

/// The latest battery reading.
pub static BATTERY: Watch<CriticalSectionRawMutex, BatteryStatus, 2> = Watch::new();

/// The live settings, and what flash holds (to save only the changes).
pub static SETTINGS: Mutex<CriticalSectionRawMutex, Option<(Settings, Settings)>> =
    Mutex::new(None);

/// The console asks the storage task to persist the settings.
pub static SAVE_REQUEST: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// Whether the motors are armed (the console refuses changes while they are).
pub static ARMED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);
