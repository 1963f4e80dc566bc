//! The flight controller board: boots `flight_core::app::FlightApp` from its simulated
//! settings flash and runs the firmware's task adapters around it — link (the TauLink
//! follower or, with `link.protocol` OpenLRSng, `flight_core::app::run_openlrs_receiver` —
//! a bind only in a window the console opens — on the real rfm22b driver over the virtual
//! Si4432), supervisor (polls the
//! app's check-in policy every `FEED_PERIOD_MS` and feeds the IWDG), storage, gains and
//! heartbeat — until its independent watchdog expires or its power goes; then it boots
//! again. The IMU, baro, battery and alert adapters run in the world's physics task at the
//! same instants as the sensors (see `world`), on the app this board publishes.

use std::cell::RefCell;
use std::rc::Rc;

use embassy_futures::join::join5;
use embassy_futures::select::{Either, select};
use flight_core::app::{
    FEED_PERIOD_MS, FlightApp, LinkStep, Task, openlrs_bind_window, run_openlrs_receiver,
};
use flight_core::pipeline::{Controllers, from_settings};
use openlrs::radio::Radio as OpenLrsRadio;
use openlrs::rx::{Config as OpenLrsConfig, Receiver};
use radio_rfm22b::link::LinkRadio;
use radio_rfm22b::{NoPin, Rfm22b, TxPower};
use si4432_sim::{ChipHandle, Fault, Medium, SimDelay, SimIrq, SimSpi};
use telemetry::link::core::Follower;
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};

use crate::clock::sleep_ms;
use crate::flash::SettingsFlash;
use crate::scenario::{End, RadioInjection};
use crate::world::{BootCause, Shared};
use si4432_sim::SimClock;

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
pub(crate) type FlightRadio = LinkRadio<SimSpi, SimIrq, NoPin, SimDelay>;

/// The flight board's radio and how to break it. The link task lends the driver's parts
/// to the OpenLRSng roles while they run (the firmware's `link_task` does the same), so the
/// slot is empty only inside such a step.
pub(crate) struct FlightChip {
    pub(crate) radio: Option<FlightRadio>,
    pub(crate) chip: ChipHandle,
}

impl FlightChip {
    pub(crate) fn new(handle: si4432_sim::RadioHandle) -> Self {
        let radio = LinkRadio::new(
            Rfm22b::new_without_sdn(handle.spi, handle.nirq, handle.delay),
            TxPower::MAX,
        );
        Self {
            radio: Some(radio),
            chip: handle.chip,
        }
    }
}

/// Why a boot's tasks stopped.
enum Stop {
    Watchdog,
    PowerOff,
}

/// The follower's hooks: straight into the app (the firmware's `AppHooks`).
struct AppHooks(Rc<RefCell<FlightApp>>);

impl FollowerHooks for AppHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.0.borrow_mut().on_link_step(now_us, follower);
    }
}

/// Checks the link task in every 50 ms while it waits (the firmware's `keep_alive`).
async fn keep_alive(app: &Rc<RefCell<FlightApp>>, delay: &SimDelay) -> core::convert::Infallible {
    loop {
        app.borrow_mut().on_link_idle();
        sleep_ms(delay, 50).await;
    }
}

async fn idle(app: &Rc<RefCell<FlightApp>>, delay: &SimDelay, ms: u64) {
    let _ = select(sleep_ms(delay, ms), keep_alive(app, delay)).await;
}

/// Resolves when the link must restart (a bind asked for, the binding phrase changed),
/// checking in every 50 ms (the firmware's `restart_due`).
async fn restart_due(app: &Rc<RefCell<FlightApp>>, delay: &SimDelay) {
    loop {
        if app.borrow().link_restart_due() {
            return;
        }
        app.borrow_mut().on_link_idle();
        sleep_ms(delay, 50).await;
    }
}

/// The OpenLRSng steps (the firmware's `openlrs_step`): the driver's parts become an
/// OpenLRSng radio for the step, and go back after it.
async fn openlrs_step(
    app: &Rc<RefCell<FlightApp>>,
    slot: &mut Option<FlightRadio>,
    clock: &SimClock,
    config: OpenLrsConfig,
    step: LinkStep,
) {
    let delay = clock.delay().clone();
    let Some(link) = slot.take() else {
        return;
    };
    let (spi, irq, _, chip_delay) = link.release().release();
    let now = clock.clone();
    let mut radio = OpenLrsRadio::new(
        spi,
        irq,
        chip_delay,
        move || now.now_us(),
        config.version,
        config.band,
    );
    let failed = match step {
        LinkStep::BindOpenLrs { window_us, .. } => {
            let bind = openlrs_bind_window(&mut radio, config, window_us);
            let Either::First(result) = select(bind, keep_alive(app, &delay)).await;
            let bound = result.as_ref().ok().copied().flatten();
            app.borrow_mut().on_openlrs_bind_result(bound.as_ref());
            result.is_err()
        }
        LinkStep::FollowOpenLrs { data, .. } => {
            let mut rx = Receiver::new(config, Some(data));
            let on_step = |now_us: u64, rx: &mut Receiver, events: &[_]| {
                app.borrow_mut().on_openlrs_step(now_us, rx, events);
            };
            let run = run_openlrs_receiver(&mut radio, &mut rx, on_step);
            // Racing the check-in too: a slow profile's lost-link dwell outlasts the IWDG.
            let waits = select(restart_due(app, &delay), keep_alive(app, &delay));
            let failed = matches!(select(run, waits).await, Either::First(_));
            app.borrow_mut().on_link_down();
            failed
        }
        _ => false,
    };
    let (spi, irq, chip_delay, _) = radio.release();
    *slot = Some(LinkRadio::new(
        Rfm22b::new_without_sdn(spi, irq, chip_delay),
        TxPower::MAX,
    ));
    if failed {
        idle(app, &delay, 1000).await;
    }
}

/// The firmware's link task: runs what `FlightApp::next_link_step` says (a bind window the
/// console opened, the follower on the stored link, or nothing until a bind is asked for).
async fn link_task(
    app: Rc<RefCell<FlightApp>>,
    slot: &mut Option<FlightRadio>,
    mut clock: SimClock,
    failsafe_us: u64,
) {
    let delay = clock.delay().clone();
    loop {
        let step = app.borrow_mut().next_link_step();
        if let LinkStep::BindOpenLrs { config, .. } | LinkStep::FollowOpenLrs { config, .. } = step
        {
            openlrs_step(&app, slot, &clock, config, step).await;
            continue;
        }
        let Some(radio) = slot.as_mut() else {
            return;
        };
        match step {
            LinkStep::Bind { band, window_us } => {
                let bind = bind_follower(radio, &mut clock, band, window_us);
                let Either::First(result) = select(bind, keep_alive(&app, &delay)).await;
                let offered = result.as_ref().ok().copied().flatten();
                app.borrow_mut().on_bind_result(offered.as_ref());
                if result.is_err() {
                    idle(&app, &delay, 1000).await;
                }
            }
            LinkStep::WaitForBind => restart_due(&app, &delay).await,
            LinkStep::Follow(params) => {
                let mut follower = app.borrow().follower(params, failsafe_us);
                let mut hooks = AppHooks(app.clone());
                let run = run_follower(radio, &mut clock, &mut follower, &mut hooks);
                let failed = matches!(
                    select(run, restart_due(&app, &delay)).await,
                    Either::First(Err(_))
                );
                app.borrow_mut().on_link_down();
                if failed {
                    idle(&app, &delay, 1000).await;
                }
            }
            LinkStep::BindOpenLrs { .. } | LinkStep::FollowOpenLrs { .. } => {}
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
async fn occupy(shared: &Shared, delay: &SimDelay, us: u64) {
    {
        let mut s = shared.borrow_mut();
        s.flight_busy_until_ns = s.now_ns() + us * 1000;
    }
    delay.sleep_ns(us * 1000).await;
}

/// Waits while the board is held by a blocking job.
async fn wait_while_busy(shared: &Shared, delay: &SimDelay) {
    loop {
        let left = {
            let s = shared.borrow();
            s.flight_busy_until_ns.saturating_sub(s.now_ns())
        };
        if left == 0 {
            return;
        }
        delay.sleep_ns(left).await;
    }
}

/// The supervisor task: polls the check-in policy every `FEED_PERIOD_MS`; the IWDG is fed
/// inside the app's model (`Watchdog::poll`), which the stop watcher reads.
async fn supervisor_task(app: Rc<RefCell<FlightApp>>, clock: SimClock, shared: &Shared) {
    loop {
        sleep_ms(clock.delay(), u64::from(FEED_PERIOD_MS)).await;
        wait_while_busy(shared, clock.delay()).await;
        let _fed = app.borrow_mut().on_watchdog_poll(clock.now_ms());
    }
}

/// The heartbeat LED task (50 ms ticker) and the motor task's check-in (it wakes at least
/// every 100 ms; the commands themselves go to the quad in the physics task).
async fn heartbeat_and_motors_task(app: Rc<RefCell<FlightApp>>, delay: SimDelay, shared: &Shared) {
    loop {
        sleep_ms(&delay, 50).await;
        wait_while_busy(shared, &delay).await;
        let mut a = app.borrow_mut();
        a.check_in(Task::Heartbeat);
        a.check_in(Task::Motors);
    }
}

/// The storage task: every 100 ms, a save the app hands out goes to the flash, holding the
/// board for the flash's time (sectors erased and words programmed, `FlashWork::f405_us`).
async fn storage_task(
    app: Rc<RefCell<FlightApp>>,
    flash: &RefCell<SettingsFlash>,
    delay: SimDelay,
    shared: &Shared,
) {
    loop {
        sleep_ms(&delay, 100).await;
        let request = {
            let mut a = app.borrow_mut();
            a.take_save().map(|(l, s)| (l, s, a.save_whole()))
        };
        let Some((live, stored, whole)) = request else {
            continue;
        };
        let (saved, work) = flash.borrow_mut().save(&live, &stored, whole);
        occupy(shared, &delay, work.f405_us()).await;
        if saved {
            app.borrow_mut().on_saved(live);
        }
    }
}

/// The gains task: every 100 ms, a design request is solved (holding the board for
/// [`DESIGN_US`]) and handed back.
async fn gains_task(app: Rc<RefCell<FlightApp>>, delay: SimDelay, shared: &Shared) {
    loop {
        sleep_ms(&delay, 100).await;
        let Some(settings) = app.borrow_mut().take_design_request() else {
            continue;
        };
        let Ok(setup) = from_settings(&settings) else {
            continue;
        };
        let designed = Controllers::design(&setup.control);
        occupy(shared, &delay, DESIGN_US).await;
        if let Ok(c) = designed {
            app.borrow_mut().on_designed(setup, c);
        }
    }
}

/// Ends a boot: the IWDG expired (no feed for `WATCHDOG_TIMEOUT_MS`) or the power went.
async fn stop_watcher(app: &Rc<RefCell<FlightApp>>, shared: &Shared, clock: &SimClock) -> Stop {
    loop {
        sleep_ms(clock.delay(), WATCH_MS).await;
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
    delay: SimDelay,
    mut chip: FlightChip,
    flash: SettingsFlash,
    failsafe_us: u64,
) {
    let flash = RefCell::new(flash);
    let mut cause = BootCause::PowerOn;
    loop {
        while !shared.borrow().input.flight_powered {
            sleep_ms(&delay, WATCH_MS).await;
        }
        if cause == BootCause::PowerOn {
            // The RFM22B is powered with the board.
            chip.chip.power_on_reset();
        }
        sleep_ms(&delay, FLIGHT_BOOT_MS).await;
        if !shared.borrow().input.flight_powered {
            continue;
        }
        let clock = SimClock::booting_now(medium.clone(), delay.clone(), FLIGHT_DRIFT_PPM);
        let (settings, problem) = flash.borrow_mut().load();
        let Some(mut app) = FlightApp::new(settings, clock.now_ms()) else {
            return;
        };
        if let Some(p) = problem {
            app.on_settings_problem(p);
        }
        // The firmware's RNG at boot: a fresh session nonce for the phone's changes every
        // boot (the virtual time of the boot stands in for the hardware's entropy).
        let boot_us = crate::clock::virtual_us(&medium);
        let mut boot_rng = telemetry::mock::SplitMix64::new(boot_us);
        app.seed_change_session(boot_rng.next_u64() as u32);
        app.seed_link_nonces(boot_rng.next_u64());
        shared
            .borrow_mut()
            .record_boot(End::Flight, cause, problem.is_some());
        let app = Rc::new(RefCell::new(app));
        shared.borrow_mut().flight = Some((app.clone(), clock.clone()));
        let tasks = join5(
            link_task(app.clone(), &mut chip.radio, clock.clone(), failsafe_us),
            supervisor_task(app.clone(), clock.clone(), &shared),
            heartbeat_and_motors_task(app.clone(), delay.clone(), &shared),
            storage_task(app.clone(), &flash, delay.clone(), &shared),
            gains_task(app.clone(), delay.clone(), &shared),
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
pub(crate) fn inject_radio(chip: &ChipHandle, from: RadioInjection, to: RadioInjection) {
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
