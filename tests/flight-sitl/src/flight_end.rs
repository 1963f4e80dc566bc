//! The flight controller board: boots `flight_app::app::FlightApp` from its simulated
//! settings flash and runs the firmware's task adapters around it — link (the firmware's
//! own task body, `flight_app::app::link_task::run_link_step`: the TauLink follower or,
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
use flight_app::app::link_task::run_link_step;
use flight_app::app::resume::{
    self, FAULT_WORDS, FEED_WORDS, FaultReason, GAINS_WORDS, Kept, ResetCause, Resume, STATE_WORDS,
};
use flight_app::app::{FEED_PERIOD_MS, FlightApp, ImuFault, ImuStep, LoopSide, Task};
use flight_app::gains;
use flight_app::pipeline::ImuSample;
use flight_app::pipeline::from_settings;
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
/// Reset to the first loop of a resumed flight, ms, the firmware's resume path at 168 MHz:
/// clocks ≈ 2 ms, settings load ≈ 3 ms, the record decoded and the controllers rebuilt from
/// its Riccati solutions (no design) < 1 ms, the MPU-9250's warm start without its 100 ms
/// reset (`Mpu9250::new_warm`) ≈ 1 ms and the AK8963's set-up (seven 10 ms I²C transfers
/// through the MPU's master) 70 ms: 76 ms.
pub const FLIGHT_RESUME_BOOT_MS: u64 = 76;
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
    Panic,
}

/// The flight board's no-init RAM as the firmware keeps it (`flight-fw` `fault::Record`):
/// the blocks `flight_app::app::resume` encodes.
#[derive(Debug, Clone)]
pub(crate) struct KeptRecord {
    state: [u32; STATE_WORDS],
    gains: [u32; GAINS_WORDS],
    fault: [u32; FAULT_WORDS],
    feed: [u32; FEED_WORDS],
}

impl Default for KeptRecord {
    /// Power-up RAM: nothing any block accepts.
    fn default() -> Self {
        Self {
            state: [0; STATE_WORDS],
            gains: [0; GAINS_WORDS],
            fault: [0; FAULT_WORDS],
            feed: [0; FEED_WORDS],
        }
    }
}

impl KeptRecord {
    /// The IMU task's part, after each loop (`flight-fw` `imu::keep_for_resume`).
    pub(crate) fn keep(&mut self, app: &mut FlightApp, side: &mut LoopSide, now_ms: u32) {
        if let Some(state) = side.resume_state_due(now_ms) {
            self.state = state;
        }
        app.keep_resume_gains(&mut self.gains);
    }

    /// Boot: the decision on what the last boot left, and the record invalidated.
    fn take_plan(&mut self, cause: ResetCause) -> Option<Resume> {
        let kept = Kept {
            state: &self.state,
            gains: &self.gains,
            fault: &self.fault,
            feed: &self.feed,
        };
        let plan = resume::plan(cause, &kept).ok();
        self.state = [0; STATE_WORDS];
        self.fault = [0; FAULT_WORDS];
        self.feed = [0; FEED_WORDS];
        plan
    }
}

/// The firmware's link task: `flight_app::app::link_task::run_link_step` in a loop, on
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

/// What holds the flight board during a blocking job.
#[derive(Clone, Copy)]
enum Holds {
    /// The thread-mode executor (a gain design): the other thread tasks wait — the
    /// supervisor, storage, gains, heartbeat, baro, battery, alerts and GPS adapters — while
    /// the flight loop, in its interrupt executor, flies on.
    Thread,
    /// The whole CPU (a flash operation: on the single-bank F405 code fetch stalls, the
    /// loop's interrupt too): no IMU sample either.
    Cpu,
}

/// Holds the flight board for `us`. The radio link's timing is not held (a
/// simplification: its slots run on).
async fn occupy(shared: &Shared, time: &VirtualTime, us: u64, holds: Holds) {
    {
        let mut s = shared.borrow_mut();
        let until = s.now_ns() + us * 1000;
        match holds {
            Holds::Thread => s.flight_thread_busy_until_ns = until,
            Holds::Cpu => s.flight_busy_until_ns = until,
        }
    }
    time.sleep_ns(us * 1000).await;
}

/// Waits while the thread-mode executor is held.
async fn wait_while_busy(shared: &Shared, time: &VirtualTime) {
    loop {
        let left = {
            let s = shared.borrow();
            let until = s.flight_busy_until_ns.max(s.flight_thread_busy_until_ns);
            until.saturating_sub(s.now_ns())
        };
        if left == 0 {
            return;
        }
        time.sleep_ns(left).await;
    }
}

/// The firmware's IMU task for one sample (`flight-fw` `tasks::imu`): the loop's inputs
/// taken from the app, a designed setup installed while disarmed, the step on the loop's
/// side, its report handed back.
pub(crate) fn imu_task_step(
    app: &mut FlightApp,
    side: &mut LoopSide,
    now_ms: u32,
    reading: Result<ImuSample, ImuFault>,
) -> ImuStep {
    let inputs = app.loop_inputs();
    if inputs.setup_pending
        && !side.armed()
        && let Some((setup, controllers)) = app.take_pending_setup()
    {
        side.install(&setup, controllers);
    }
    let (step, report) = match reading {
        Ok(sample) => side.step(now_ms, &sample, &inputs),
        Err(cause) => side.missing(now_ms, cause, &inputs),
    };
    app.on_loop_report(now_ms, &report);
    step
}

/// The supervisor task: polls the check-in policy every `FEED_PERIOD_MS`; the IWDG is fed
/// inside the app's model (`Watchdog::poll`), which the stop watcher reads.
async fn supervisor_task(app: Rc<RefCell<FlightApp>>, clock: SimClock, shared: &Shared) {
    loop {
        sleep_ms(clock.time(), u64::from(FEED_PERIOD_MS)).await;
        wait_while_busy(shared, clock.time()).await;
        let now = clock.now_ms();
        if app.borrow_mut().on_watchdog_poll(now) {
            shared.borrow_mut().flight_record.feed = resume::encode_feed(now);
        }
    }
}

/// The heartbeat LED task (50 ms ticker; the motor commands go to the quad from the IMU
/// adapter in the physics task, as the firmware's loop drives the outputs itself).
async fn heartbeat_task(app: Rc<RefCell<FlightApp>>, time: VirtualTime, shared: &Shared) {
    loop {
        sleep_ms(&time, 50).await;
        wait_while_busy(shared, &time).await;
        let mut a = app.borrow_mut();
        a.check_in(Task::Heartbeat);
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
        occupy(shared, &time, work.f405_us(), Holds::Cpu).await;
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
        let designed = gains::design(&setup.control);
        occupy(shared, &time, DESIGN_US, Holds::Thread).await;
        if let Ok(c) = designed {
            app.borrow_mut().on_designed(setup, c);
        }
    }
}

/// Ends a boot: the IWDG expired (no feed for its timeout), the power went, or the firmware
/// panicked (the handler's reset, with the fault recorded). A hang holds the board (no task
/// runs, no feed) until the IWDG ends it. The injections act on their change to true.
async fn stop_watcher(app: &Rc<RefCell<FlightApp>>, shared: &Shared, clock: &SimClock) -> Stop {
    let (mut panicked, mut hung) = {
        let input = shared.borrow().input;
        (input.flight_panic, input.flight_hang)
    };
    loop {
        sleep_ms(clock.time(), WATCH_MS).await;
        let input = shared.borrow().input;
        if !input.flight_powered {
            return Stop::PowerOff;
        }
        if input.flight_panic && !panicked {
            let fault = resume::Fault {
                reason: FaultReason::Panic,
                at_ms: clock.now_ms(),
                address: 0,
            };
            shared.borrow_mut().flight_record.fault = fault.encode();
            return Stop::Panic;
        }
        panicked = input.flight_panic;
        if input.flight_hang && !hung {
            shared.borrow_mut().flight_thread_busy_until_ns = u64::MAX;
        }
        hung = input.flight_hang;
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
            // The RFM22B is powered with the board, the RAM is not kept.
            chip.power_on_reset();
            shared.borrow_mut().flight_record = KeptRecord::default();
        }
        // A reset ends whatever held the board.
        {
            let mut s = shared.borrow_mut();
            s.flight_busy_until_ns = 0;
            s.flight_thread_busy_until_ns = 0;
        }
        let reset = match cause {
            BootCause::PowerOn => ResetCause::PowerOn,
            BootCause::Watchdog => ResetCause::Watchdog,
            BootCause::Panic | BootCause::Resumed => ResetCause::Software,
        };
        let resume = shared.borrow_mut().flight_record.take_plan(reset);
        let boot_ms = if resume.is_some() {
            FLIGHT_RESUME_BOOT_MS
        } else {
            FLIGHT_BOOT_MS
        };
        sleep_ms(&time, boot_ms).await;
        if !shared.borrow().input.flight_powered {
            continue;
        }
        let clock = SimClock::booting_now(medium.time(), FLIGHT_DRIFT_PPM);
        let (settings, problem) = flash.borrow_mut().load();
        let resumed = resume
            .as_ref()
            .and_then(|r| FlightApp::resume(settings.clone(), r, clock.now_ms()));
        if resumed.is_some() {
            cause = BootCause::Resumed;
        }
        let Some(mut app) = resumed.or_else(|| FlightApp::new(settings, clock.now_ms())) else {
            return;
        };
        if let Some(p) = problem {
            app.on_settings_problem(p);
        }
        app.model_watchdog_lsi_hz(shared.borrow().flight_lsi_hz);
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
        // The IMU task owns the loop's side, apart from the app.
        let side = app.take_loop_side();
        let app = Rc::new(RefCell::new(app));
        {
            let mut s = shared.borrow_mut();
            s.flight = Some((app.clone(), clock.clone()));
            s.flight_loop = side;
        }
        let tasks = join5(
            link_task(app.clone(), &radio, clock.clone(), failsafe_us),
            supervisor_task(app.clone(), clock.clone(), &shared),
            heartbeat_task(app.clone(), time.clone(), &shared),
            storage_task(app.clone(), &flash, clock.clone(), &shared),
            gains_task(app.clone(), time.clone(), &shared),
        );
        let stop = match select(tasks, stop_watcher(&app, &shared, &clock)).await {
            Either::First(_) => Stop::PowerOff,
            Either::Second(stop) => stop,
        };
        let mut s = shared.borrow_mut();
        s.flight = None;
        s.flight_loop = None;
        s.flight_settings = app.borrow().settings().clone();
        cause = match stop {
            Stop::Watchdog => {
                s.watchdog_resets.flight += 1;
                BootCause::Watchdog
            }
            Stop::PowerOff => BootCause::PowerOn,
            Stop::Panic => BootCause::Panic,
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
