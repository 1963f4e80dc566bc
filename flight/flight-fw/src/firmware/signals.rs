//! Every channel between tasks, in one place: this file is the firmware's data-flow diagram.
//!
//! ```text
//! imu (MPU9250 EXTI) ──MOTORS────▶ motors         battery ──ALERTS──▶ alerts (DAC tones)
//!     ▲    ▲         ──ALERTS────▶ alerts         battery ──BATTERY─▶ alerts, link
//!     │    └─CLIMB── baro (MS5611)
//!     └──LINK_INPUT── link (RFM22B follower) ◀──FLIGHT_STATE, SYSID── imu
//!                     link ──SETTINGS (shared)── console, storage
//! gains ──NEW_SETUP──▶ imu     (SETTINGS_CHANGED from link/console wakes gains)
//! ```

use core::cell::Cell;

use embassy_sync::blocking_mutex::Mutex as BlockingMutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::mutex::Mutex;
use embassy_sync::signal::Signal;
use embassy_sync::watch::Watch;
use flight_core::alerts::Alert;
use flight_core::battery::BatteryStatus;
use flight_core::outputs::Command;
use flight_core::pipeline::{Controllers, FlightSetup, LinkInput, LoopOutput};
use flight_core::settings::Settings;
use flight_core::sysid::ekf::Identification;

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

/// A setting changed (console or link): re-derive the setup and re-solve the gains.
pub static SETTINGS_CHANGED: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// Whether the motors are armed (the console refuses changes while they are).
pub static ARMED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// The sticks and switches the link delivers, read by the loop on every sample (latest value
/// wins; the loop never waits for the link).
pub static LINK_INPUT: BlockingMutex<CriticalSectionRawMutex, Cell<LinkInput>> =
    BlockingMutex::new(Cell::new(LinkInput {
        up: false,
        sticks: flight_core::supervisor::Sticks {
            throttle: 0.0,
            roll: 0.0,
            pitch: 0.0,
            yaw: 0.0,
        },
        arm_switch: None,
        mode_channel: -1.0,
    }));

/// Barometric climb rate (m/s, up), when the baro delivers.
pub static CLIMB: BlockingMutex<CriticalSectionRawMutex, Cell<Option<f32>>> =
    BlockingMutex::new(Cell::new(None));

/// The loop's latest output and arming blockers, for telemetry.
pub static FLIGHT_STATE: BlockingMutex<CriticalSectionRawMutex, Cell<Option<(LoopOutput, u16)>>> =
    BlockingMutex::new(Cell::new(None));

/// A finished identification (system-identification mode left), for the downlink.
pub static SYSID: Signal<CriticalSectionRawMutex, Identification> = Signal::new();

/// A new configuration with its solved gains, installed by the loop while disarmed.
pub static NEW_SETUP: Signal<CriticalSectionRawMutex, (FlightSetup, Controllers)> = Signal::new();
