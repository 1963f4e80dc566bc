//! The TauLink module board: boots `module_core::App` with its stored settings and runs the
//! module firmware's task adapters around it — the link task carrying out the core's
//! session steps (`next_link_step`, master loop on the real rfm22b driver over the virtual
//! Si4432, `poll_session`, `on_session_end`, binds), the PPM capture task feeding the
//! handset's frames as edges (`on_ppm_edge` / `on_ppm_tick`), the 10 Hz app task, the HM-10
//! task relaying records to a connected phone (what the module received: `Sitl.module_rx`)
//! and the phone's setting changes up, and the supervisor feeding the nRF52840 WDT (250 ms)
//! only while every modelled task checked in. An expired WDT reboots the module.

use std::cell::{Cell, RefCell};

use embassy_futures::join::join5;
use embassy_futures::select::{Either, select};
use module_core::air::AirLink;
use module_core::app::{Action, App};
use module_core::channels::value_to_us;
use module_core::handset::Handset;
use module_core::session::{BindOutcome, LinkStep, POLL_MS, SessionEnd};
use module_core::settings::Settings as ModuleSettings;
use radio_rfm22b::link::LinkRadio;
use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{Medium, SimDelay, SimIrq, SimSdn, SimSpi};
use telemetry::change_auth::Signer;
use telemetry::link::LinkClock;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};
use telemetry::link::master::{MasterHooks, bind_master, run_master};
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SettingChange, encode_message,
};
use telemetry::mock::SplitMix64;

use crate::clock::{BoardClock, sleep_ms};
use crate::scenario::End;
use crate::world::{BootCause, Shared, transmitter};

/// Power-on to the first task, ms: nRF52840 start-up and HFXO ≈ 1 ms, settings load from
/// the NVMC ≈ 1 ms, the RFM22B probe is the link task's first step (its own POR time is
/// in the chip model).
pub const MODULE_BOOT_MS: u64 = 5;
/// The nRF52840 WDT timeout the firmware programs (32 768 / 4 ticks), ms.
pub const MODULE_WATCHDOG_MS: u64 = 250;
/// The module's crystal error, ppm.
const MODULE_DRIFT_PPM: f64 = 20.0;
/// PPM frame period of the handset, µs (8 channels, the usual 22.5 ms).
const PPM_FRAME_US: u64 = 22_500;
/// PPM channels the handset sends.
const PPM_CHANNELS: usize = 8;
/// The PPM task's idle tick without edges, ms (the firmware's `IDLE_TICK`).
const PPM_IDLE_MS: u64 = 50;
/// How often the HM-10 task moves bytes, ms.
const HM10_POLL_MS: u64 = 10;

/// The module's RFM22B: SDN wired (the nRF52840 drives it).
pub(crate) type ModuleRadio = LinkRadio<SimSpi, SimIrq, SimSdn, SimDelay>;

/// The module's radio (its faults are injected through the world's chip handle).
pub(crate) struct ModuleChip {
    pub(crate) radio: ModuleRadio,
}

impl ModuleChip {
    pub(crate) fn new(handle: si4432_sim::RadioHandle, tx_power: u8) -> Self {
        let radio = LinkRadio::new(
            Rfm22b::new(handle.spi, handle.nirq, handle.sdn, handle.delay),
            TxPower::from_step(tx_power),
        );
        Self { radio }
    }
}

type ModuleApp = App<AirLink, Handset>;

/// The tasks the module's supervisor expects (the firmware's `Watched` bits of the tasks
/// modelled here; the LED, button, battery, settings and JR-line tasks only idle and
/// check in, so they are left out).
#[derive(Clone, Copy)]
enum Watched {
    Radio = 1 << 1,
    PpmIn = 1 << 2,
    Hm10 = 1 << 5,
    App = 1 << 9,
}

const EXPECTED: u32 =
    Watched::Radio as u32 | Watched::PpmIn as u32 | Watched::Hm10 as u32 | Watched::App as u32;

/// One boot's context.
struct Board {
    app: RefCell<ModuleApp>,
    clock: BoardClock,
    checked_in: Cell<u32>,
    last_feed_ms: Cell<u32>,
}

impl Board {
    fn check_in(&self, t: Watched) {
        self.checked_in.set(self.checked_in.get() | t as u32);
    }

    fn now_ms(&self) -> u32 {
        self.clock.now_ms()
    }

    fn delay(&self) -> &SimDelay {
        self.clock.delay()
    }
}

/// The loops' hook into the core (the firmware's `Hooks`).
struct Hooks<'a>(&'a Board);

impl MasterHooks for Hooks<'_> {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let now_ms = self.0.now_ms();
        self.0
            .app
            .borrow_mut()
            .on_master_slot(now_us, now_ms, master);
    }
}

impl FollowerHooks for Hooks<'_> {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let now_ms = self.0.now_ms();
        self.0
            .app
            .borrow_mut()
            .on_follower_step(now_us, now_ms, follower);
    }
}

async fn poll_session(b: &Board) -> SessionEnd {
    loop {
        b.check_in(Watched::Radio);
        if let Some(end) = b.app.borrow_mut().poll_session(b.now_ms()) {
            return end;
        }
        sleep_ms(b.delay(), POLL_MS.into()).await;
    }
}

async fn keep_alive<T>(b: &Board, step: impl Future<Output = T>) -> T {
    let ticking = async {
        loop {
            b.check_in(Watched::Radio);
            sleep_ms(b.delay(), POLL_MS.into()).await;
        }
    };
    match select(step, ticking).await {
        Either::First(v) => v,
        Either::Second(never) => never,
    }
}

async fn run<E>(
    b: &Board,
    link: impl Future<Output = Result<core::convert::Infallible, E>>,
) -> SessionEnd {
    match select(link, poll_session(b)).await {
        Either::First(Err(_)) => SessionEnd::RadioFailed,
        Either::First(Ok(never)) => match never {},
        Either::Second(end) => end,
    }
}

/// The firmware's link task.
async fn link_task(b: &Board, radio: &mut ModuleRadio, shared: &Shared, seed: u64) {
    let mut rng = SplitMix64::new(seed ^ 0x4D0D);
    let mut clock = b.clock.clone();
    loop {
        b.check_in(Watched::Radio);
        let random = rng.next_u64() as u32;
        let step = b.app.borrow_mut().next_link_step(b.now_ms(), random);
        let action = match step {
            LinkStep::Probe => {
                let present = radio.driver().reset().await.is_ok();
                b.app.borrow_mut().on_radio_present(present)
            }
            LinkStep::Wait { ms } => {
                keep_alive(b, sleep_ms(b.delay(), ms.into())).await;
                None
            }
            LinkStep::WaitForBind => {
                let end = poll_session(b).await;
                b.app.borrow_mut().on_session_end(end)
            }
            LinkStep::RunMaster(params) => {
                let mut master = b.app.borrow().master(params);
                let end = run(b, run_master(radio, &mut clock, &mut master, &mut Hooks(b))).await;
                b.app.borrow_mut().on_session_end(end)
            }
            LinkStep::RunFollower {
                params,
                failsafe,
                failsafe_us,
            } => {
                let mut follower = b.app.borrow().follower(params, failsafe, failsafe_us);
                let end = run(
                    b,
                    run_follower(radio, &mut clock, &mut follower, &mut Hooks(b)),
                )
                .await;
                b.app.borrow_mut().on_session_end(end)
            }
            LinkStep::BindMaster { params, timeout_us } => {
                let accepted =
                    keep_alive(b, bind_master(radio, &mut clock, &params, timeout_us)).await;
                let outcome = BindOutcome::offered(accepted);
                b.app.borrow_mut().on_bind_outcome(outcome)
            }
            LinkStep::BindFollower { band, timeout_us } => {
                let offer = keep_alive(b, bind_follower(radio, &mut clock, band, timeout_us)).await;
                let outcome = BindOutcome::listened(offer);
                b.app.borrow_mut().on_bind_outcome(outcome)
            }
        };
        carry_out(shared, action);
    }
}

/// The firmware's `carry_out`: a save goes to the module's settings flash (kept by the
/// world across resets); the LED is not modelled.
fn carry_out(shared: &Shared, action: Option<Action>) {
    if let Some(Action::Save(settings)) = action {
        shared.borrow_mut().module_flash = settings;
    }
}

/// The PPM capture task: the handset's frame as falling edges, each stamped (by the
/// capture timer, exact to 1 µs) and handed to the core; without edges, the idle tick.
async fn ppm_in_task(b: &Board, shared: &Shared) {
    let mut clock = b.clock.clone();
    let mut frame_start = clock.now_us();
    loop {
        b.check_in(Watched::PpmIn);
        let input = shared.borrow().input;
        if !input.handset_connected {
            sleep_ms(b.delay(), PPM_IDLE_MS).await;
            let now = clock.now_us() as u32;
            b.app.borrow_mut().on_ppm_tick(now);
            frame_start = clock.now_us();
            continue;
        }
        let ch = transmitter(&input);
        let mut edge = frame_start;
        for i in 0..=PPM_CHANNELS {
            clock.sleep_until_us(edge).await;
            let t = edge as u32;
            {
                let mut app = b.app.borrow_mut();
                app.on_ppm_edge(t);
                app.on_ppm_tick(t);
            }
            b.check_in(Watched::PpmIn);
            if let Some(v) = ch.get(i) {
                edge += u64::from(value_to_us(*v));
            }
        }
        frame_start += PPM_FRAME_US;
    }
}

/// The 10 Hz app task.
async fn app_task(b: &Board, shared: &Shared) {
    loop {
        b.check_in(Watched::App);
        let action = b.app.borrow_mut().on_tick();
        carry_out(shared, action);
        sleep_ms(b.delay(), 100).await;
    }
}

/// A message from the phone, as the HM-10 hands its bytes to the module.
fn send_to_flight(b: &Board, message: &Message) {
    let mut buf = [0u8; FRAMED_MAX_BYTES];
    if let Ok(n) = encode_message(message, &mut buf) {
        b.app
            .borrow_mut()
            .on_phone_bytes(buf.get(..n).unwrap_or(&[]));
    }
}

/// The HM-10 task with a phone connected: records to the phone (decoded: what the module
/// received), the scenario's setting changes from the phone.
async fn hm10_task(b: &Board, shared: &Shared) {
    let mut reader = MessageReader::new();
    let mut phone = shared.borrow().phone_key.map(|k| Signer::new(&k));
    let mut pending: Option<SettingChange> = None;
    let mut frame = [0u8; module_core::hm10::relay::MAX_FRAME_LEN];
    loop {
        b.check_in(Watched::Hm10);
        let change = {
            let mut s = shared.borrow_mut();
            (!s.uplink.is_empty()).then(|| s.uplink.remove(0))
        };
        if let Some(change) = change {
            // The pilot typed the same phrase into the phone (the ground station signs in
            // WASM with `change_auth::Signer`); without a phrase the change goes unsigned
            // and the flight side refuses it.
            let message = match phone.as_mut() {
                Some(signer) => Message::SignedChange(signer.sign(change)),
                None => Message::SettingChange(change),
            };
            pending = Some(change);
            send_to_flight(b, &message);
        }
        loop {
            let Some(n) = b.app.borrow_mut().next_phone_frame(&mut frame) else {
                break;
            };
            for &byte in frame.get(..n).unwrap_or(&[]) {
                if let Some(Decoded::Message(m)) = reader.push(byte) {
                    // A refusal for want of the session: sign the change again, once.
                    if let (Message::ChangeRefused(r), Some(signer), Some(change)) =
                        (&m, phone.as_mut(), pending)
                        && signer.on_refused(r)
                    {
                        send_to_flight(b, &Message::SignedChange(signer.sign(change)));
                    }
                    let mut s = shared.borrow_mut();
                    let t = s.scenario_s();
                    s.module_rx.push((t, m));
                }
            }
        }
        sleep_ms(b.delay(), HM10_POLL_MS).await;
    }
}

/// The supervisor: every 100 ms, fed if every expected task checked in.
async fn supervisor_task(b: &Board) {
    loop {
        sleep_ms(b.delay(), 100).await;
        if b.checked_in.get() & EXPECTED == EXPECTED {
            b.checked_in.set(0);
            b.last_feed_ms.set(b.now_ms());
        }
    }
}

/// The WDT: returns when it expires.
async fn watchdog(b: &Board) {
    loop {
        sleep_ms(b.delay(), 5).await;
        if u64::from(b.now_ms().wrapping_sub(b.last_feed_ms.get())) >= MODULE_WATCHDOG_MS {
            return;
        }
    }
}

/// The module board, forever: boot, run, reset on the WDT.
pub(crate) async fn module_board(
    shared: Shared,
    medium: Medium,
    delay: SimDelay,
    mut chip: ModuleChip,
    seed: u64,
) {
    let mut cause = BootCause::PowerOn;
    loop {
        sleep_ms(&delay, MODULE_BOOT_MS).await;
        let settings: ModuleSettings = shared.borrow().module_flash;
        let Ok(app) = App::new(settings, AirLink::new(), Handset::new(&settings), true) else {
            return;
        };
        shared.borrow_mut().record_boot(End::Module, cause, false);
        let clock = BoardClock::booting_now(medium.clone(), delay.clone(), MODULE_DRIFT_PPM);
        let board = Board {
            app: RefCell::new(app),
            last_feed_ms: Cell::new(clock.now_ms()),
            clock,
            checked_in: Cell::new(0),
        };
        let tasks = join5(
            link_task(&board, &mut chip.radio, &shared, seed),
            ppm_in_task(&board, &shared),
            app_task(&board, &shared),
            hm10_task(&board, &shared),
            supervisor_task(&board),
        );
        let _ = select(tasks, watchdog(&board)).await;
        shared.borrow_mut().watchdog_resets.module += 1;
        cause = BootCause::Watchdog;
    }
}
