//! The flight controller board: boots `flight_core::app::FlightApp` from its simulated
//! settings flash and runs the firmware's task adapters around it — link (the firmware's
//! own task body, `flight_core::app::link_task::run_link_step`: the TauLink follower or,
//! with `link.protocol` OpenLRSng, the OpenLRSng receiver — a bind only in a window the
//! console opens — on the real rfm22b driver over the virtual Si4432), supervisor (polls the
//! app's check-in policy every `FEED_PERIOD_MS` and feeds the IWDG), storage, gains and
//! heartbeat — until its independent watchdog expires or its power goes; then it boots
//! again. The IMU, baro, battery and alert adapters run in the world's physics task at the
//! same instants as the sensors (see `world`), on the app this board publishes.

use std::cell::RefCell;
use std::rc::Rc;

use embassy_futures::join::join5;
use embassy_futures::select::{Either, select};
use flight_core::app::link_task::run_link_step;
use flight_core::app::{FEED_PERIOD_MS, FlightApp, Task};
use flight_core::pipeline::{Controllers, from_settings};
use openlrs::dual::DualRadio;
use openlrs::radio::Clock;
use radio_rfm22b::{NoPin, Rfm22b, TxPower};
use si4432_sim::{ChipHandle, Fault, Medium, SimDelay, SimIrq, SimSpi};

use crate::clock::sleep_ms;
use crate::flash::SettingsFlash;
use crate::scenario::{End, RadioInjection};
use crate::world::{BootCause, Shared};
use si4432_sim::{SimClock, VirtualTime};

/// Power-on to the first loop, ms, modelled as the firmware's boot at 168 MHz: clocks and
/// PLL lock ≈ 2 ms, settings load ≈ 3 ms (two records read and CRC-checked), MPU-9250
/// start-up ≈ 100 ms (its datasheet's start-up time after power-on; the driver waits for
/// it), gain design ≈ 40 ms (≈ 5.5 M instructions of f64 Riccati solves).
pub const FLIGHT_BOOT_MS: u64 = 145;
/// The flight board's crystal error, ppm (the module's runs 40 ppm apart).
const FLIGHT_DRIFT_PPM: f64 = -20.0;
/// How often the stop watcher looks at power and the IWDG, ms.
const WATCH_MS: u64 = 5;

/// The flight board's RFM22B as the firmware wires it: SDN tied low, software reset only.
pub(crate) type FlightDriver = Rfm22b<SimSpi, SimIrq, NoPin, SimDelay>;

/// The flight board's radio and how to break it. Each boot's link task runs it as the
/// firmware's does (`openlrs::dual::DualRadio` on that boot's clock); the slot is
/// empty only while a boot runs.
pub(crate) struct FlightChip {
    pub(crate) radio: Option<FlightDriver>,
    pub(crate) chip: ChipHandle,
}

impl FlightChip {
    pub(crate) fn new(handle: si4432_sim::RadioHandle) -> Self {
        Self {
            radio: Some(Rfm22b::new_without_sdn(
                handle.spi,
                handle.nirq,
                handle.delay,
            )),
            chip: handle.chip,
        }
    }
}

/// Why a boot's tasks stopped.
enum Stop {
    Watchdog,
    PowerOff,
}

/// The firmware's link task: `flight_core::app::link_task::run_link_step` in a loop, on
/// the board's driver lent to a `DualRadio` for this boot (given back when the boot ends).
async fn link_task(
    app: Rc<RefCell<FlightApp>>,
    slot: &RefCell<Option<FlightDriver>>,
    mut clock: SimClock,
    failsafe_us: u64,
) {
    let Some(driver) = slot.borrow_mut().take() else {
        return;
    };
    let now = clock.clone();
    let chip = DualRadio::new(driver, TxPower::MAX, move || now.now_us());
    // The driver goes back to the board when this task is dropped (a reset, a power cut).
    let mut chip = GiveBack(Some(chip), slot);
    loop {
        let Some(chip) = chip.0.as_mut() else {
            return;
        };
        run_link_step(&*app, chip, &mut clock, failsafe_us).await;
    }
}

/// Puts the driver back in the board's slot when the boot's link task ends.
struct GiveBack<'a, C: Clock>(
    Option<DualRadio<SimSpi, SimIrq, NoPin, SimDelay, C>>,
    &'a RefCell<Option<FlightDriver>>,
);

impl<C: Clock> Drop for GiveBack<'_, C> {
    fn drop(&mut self) {
        if let Some((driver, _)) = self.0.take().and_then(|chip| chip.release()) {
            *self.1.borrow_mut() = Some(driver);
        }
    }
}

/// The gain design's time on the F405, µs: the `flight_loop` bench's three-axis design
/// (`cargo xtask figures`: `loop.design`, 5 519 425 instructions when this was set) at 1.3
/// cycles per instruction and 168 MHz.
pub const DESIGN_US: u64 = 42_700;

/// Holds the flight board for `us`: every flight task runs on one thread-mode executor, so
/// a blocking job (a gain design; a flash operation, which on the single-bank F405 also
/// stalls code fetch) keeps the others — the IMU adapter, the supervisor — from running.
/// The radio link's timing is not held (a simplification: its slots run on).
async fn occupy(shared: &Shared, time: &VirtualTime, us: u64) {
    {
        let mut s = shared.borrow_mut();
        s.flight_busy_until_ns = s.now_ns() + us * 1000;
    }
    time.sleep_ns(us * 1000).await;
}

/// Waits while the board is held by a blocking job.
async fn wait_while_busy(shared: &Shared, time: &VirtualTime) {
    loop {
        let left = {
            let s = shared.borrow();
            s.flight_busy_until_ns.saturating_sub(s.now_ns())
        };
        if left == 0 {
            return;
        }
        time.sleep_ns(left).await;
    }
}

/// The supervisor task: polls the check-in policy every `FEED_PERIOD_MS`; the IWDG is fed
/// inside the app's model (`Watchdog::poll`), which the stop watcher reads.
async fn supervisor_task(app: Rc<RefCell<FlightApp>>, clock: SimClock, shared: &Shared) {
    loop {
        sleep_ms(clock.time(), u64::from(FEED_PERIOD_MS)).await;
        wait_while_busy(shared, clock.time()).await;
        let _fed = app.borrow_mut().on_watchdog_poll(clock.now_ms());
    }
}

/// The heartbeat LED task (50 ms ticker) and the motor task's check-in (it wakes at least
/// every 100 ms; the commands themselves go to the quad in the physics task).
async fn heartbeat_and_motors_task(
    app: Rc<RefCell<FlightApp>>,
    time: VirtualTime,
    shared: &Shared,
) {
    loop {
        sleep_ms(&time, 50).await;
        wait_while_busy(shared, &time).await;
        let mut a = app.borrow_mut();
        a.check_in(Task::Heartbeat);
        a.check_in(Task::Motors);
    }
}

/// The storage task: every 100 ms, a save job the app hands out goes to the flash, with
/// the watchdog stretched to the job's period (unless the world turned that off), holding
/// the board for the flash's time (sectors erased and words programmed, `FlashWork::f405_us`).
async fn storage_task(
    app: Rc<RefCell<FlightApp>>,
    flash: &RefCell<SettingsFlash>,
    clock: SimClock,
    shared: &Shared,
) {
    let time = clock.time().clone();
    loop {
        sleep_ms(&time, 100).await;
        let Some(job) = app.borrow_mut().take_save_job() else {
            continue;
        };
        if shared.borrow().save_stretch {
            app.borrow_mut()
                .on_watchdog_stretched(clock.now_ms(), job.watchdog_ms);
        }
        let (saved, work) = flash.borrow_mut().save(&job);
        occupy(shared, &time, work.f405_us()).await;
        let saved = saved.then(|| job.live.clone());
        app.borrow_mut().on_save_done(clock.now_ms(), saved);
    }
}

/// The gains task: every 100 ms, a design request is solved (holding the board for
/// [`DESIGN_US`]) and handed back.
async fn gains_task(app: Rc<RefCell<FlightApp>>, time: VirtualTime, shared: &Shared) {
    loop {
        sleep_ms(&time, 100).await;
        let Some(settings) = app.borrow_mut().take_design_request() else {
            continue;
        };
        let Ok(setup) = from_settings(&settings) else {
            continue;
        };
        let designed = Controllers::design(&setup.control);
        occupy(shared, &time, DESIGN_US).await;
        if let Ok(c) = designed {
            app.borrow_mut().on_designed(setup, c);
        }
    }
}

/// Ends a boot: the IWDG expired (no feed for `WATCHDOG_TIMEOUT_MS`) or the power went.
async fn stop_watcher(app: &Rc<RefCell<FlightApp>>, shared: &Shared, clock: &SimClock) -> Stop {
    loop {
        sleep_ms(clock.time(), WATCH_MS).await;
        if !shared.borrow().input.flight_powered {
            return Stop::PowerOff;
        }
        if app.borrow().watchdog().expired(clock.now_ms()) {
            return Stop::Watchdog;
        }
    }
}

/// The flight board, forever: power, boot, run, reset.
pub(crate) async fn flight_board(
    shared: Shared,
    medium: Medium,
    time: VirtualTime,
    chip: FlightChip,
    flash: SettingsFlash,
    failsafe_us: u64,
) {
    let flash = RefCell::new(flash);
    let radio = RefCell::new(chip.radio);
    let chip = chip.chip;
    let mut cause = BootCause::PowerOn;
    loop {
        while !shared.borrow().input.flight_powered {
            sleep_ms(&time, WATCH_MS).await;
        }
        if cause == BootCause::PowerOn {
            // The RFM22B is powered with the board.
            chip.power_on_reset();
        }
        sleep_ms(&time, FLIGHT_BOOT_MS).await;
        if !shared.borrow().input.flight_powered {
            continue;
        }
        let clock = SimClock::booting_now(medium.time(), FLIGHT_DRIFT_PPM);
        let (settings, problem) = flash.borrow_mut().load();
        let Some(mut app) = FlightApp::new(settings, clock.now_ms()) else {
            return;
        };
        if let Some(p) = problem {
            app.on_settings_problem(p);
        }
        // The firmware's RNG at boot: the link's secrets, a fresh session for the phone's
        // changes every boot (the virtual time of the boot stands in for the hardware's
        // entropy).
        let boot_us = crate::clock::virtual_us(&medium);
        let mut boot_rng = telemetry::mock::SplitMix64::new(boot_us);
        let mut random = [0u8; 32];
        for chunk in random.chunks_exact_mut(8) {
            chunk.copy_from_slice(&boot_rng.next_u64().to_le_bytes());
        }
        app.seed_random(&random);
        {
            let mut s = shared.borrow_mut();
            s.record_boot(End::Flight, cause, problem.is_some());
            s.flight_logs.push(crate::flight_log::LogFile::new(
                u64::from(clock.now_ms()) * 1000,
            ));
        }
        let app = Rc::new(RefCell::new(app));
        shared.borrow_mut().flight = Some((app.clone(), clock.clone()));
        let tasks = join5(
            link_task(app.clone(), &radio, clock.clone(), failsafe_us),
            supervisor_task(app.clone(), clock.clone(), &shared),
            heartbeat_and_motors_task(app.clone(), time.clone(), &shared),
            storage_task(app.clone(), &flash, clock.clone(), &shared),
            gains_task(app.clone(), time.clone(), &shared),
        );
        let stop = match select(tasks, stop_watcher(&app, &shared, &clock)).await {
            Either::First(_) => Stop::PowerOff,
            Either::Second(stop) => stop,
        };
        let mut s = shared.borrow_mut();
        s.flight = None;
        s.flight_settings = app.borrow().settings().clone();
        cause = match stop {
            Stop::Watchdog => {
                s.watchdog_resets.flight += 1;
                BootCause::Watchdog
            }
            Stop::PowerOff => BootCause::PowerOn,
        };
    }
}

/// Applies a radio injection to a chip (called when it changes).
pub fn inject_radio(chip: &ChipHandle, from: RadioInjection, to: RadioInjection) {
    if from == RadioInjection::BrownOut {
        // Power back: a power-on reset, registers lost.
        chip.set_fault(Fault::None);
        chip.power_on_reset();
    }
    match to {
        RadioInjection::Healthy | RadioInjection::SpiErrors => chip.set_fault(Fault::None),
        RadioInjection::IrqStuckLow => chip.set_fault(Fault::NirqStuckLow),
        RadioInjection::IrqStuckHigh => chip.set_fault(Fault::NirqStuckHigh),
        // Held in reset: SPI reads nothing, nIRQ never asserts.
        RadioInjection::BrownOut => chip.set_fault(Fault::Unplugged { miso: 0x00 }),
    }
    chip.set_spi_error_rate(if to == RadioInjection::SpiErrors {
        1.0
    } else {
        0.0
    });
}
