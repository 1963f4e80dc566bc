//! The TauLink module board: boots `module_core::App` with its stored settings and runs the
//! module firmware's task adapters around it — the link task (the firmware's own body,
//! `module_core::link_task::run_link_step`: the core's session steps, the master loop — or,
//! with the OpenLRSng protocol, OpenLRSng's transmitter — and the binds on the real rfm22b
//! driver over the virtual Si4432), the PPM capture task feeding the
//! handset's frames as edges (`on_ppm_edge` / `on_ppm_tick`), the JR-line task with the
//! radio at its other end (CRSF: the radio's channel frame every [`CRSF_PERIOD_US`], the
//! module's reply after it; S.Port / FrSky D: the pushed frames; what the module sent:
//! `Sitl.handset_tx`), the 10 Hz app task, the HM-10 task relaying records to a connected
//! phone (what the module received: `Sitl.module_rx`; the raw frames too when a page is
//! attached) and the phone's bytes up (the scenario's setting changes, an attached page's
//! writes), and the supervisor feeding the nRF52840 WDT (250 ms) only while every modelled
//! task checked in. An expired WDT reboots the module.

use std::cell::{Cell, RefCell};

use embassy_futures::join::{join, join5};
use embassy_futures::select::select;
use module_core::air::AirLink;
use module_core::app::{Action, App};
use module_core::channels::ticks_to_us;
use module_core::handset::{Handset, LineMode, MAX_LINE_BURST};
use module_core::link_task::{LinkPorts, run_link_step};
use module_core::settings::Settings as ModuleSettings;
use module_core::watchdog::{CheckIns, FEED_PERIOD_MS, WATCHDOG_TIMEOUT_MS, Watched};
use openlrs::dual::DualRadio;
use openlrs::radio::Clock;
use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{Medium, SimDelay, SimIrq, SimSdn, SimSpi};
use taulink_handset::crsf::channels::RcChannels;
use taulink_handset::crsf::frame::{Frame, frame_type};
use taulink_handset::crsf::{ModelSelect, address};
use telemetry::change_auth::Signer;
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SettingChange, encode_message,
};
use telemetry::mock::SplitMix64;

use crate::clock::sleep_ms;
use crate::scenario::End;
use crate::world::{BootCause, Shared, TO_PHONE_MAX, transmitter};
use si4432_sim::{SimClock, VirtualTime};

/// Power-on to the first task, ms: nRF52840 start-up and HFXO ≈ 1 ms, settings load from
/// the NVMC ≈ 1 ms, the RFM22B probe is the link task's first step (its own POR time is
/// in the chip model).
pub const MODULE_BOOT_MS: u64 = 5;
/// The nRF52840 WDT timeout the firmware programs (module-core's `WATCHDOG_TIMEOUT_MS`), ms.
pub const MODULE_WATCHDOG_MS: u64 = WATCHDOG_TIMEOUT_MS as u64;
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
/// The radio's CRSF channel-frame period, µs (EdgeTX's 250 Hz; this radio model does not
/// follow the module's timing frames).
pub const CRSF_PERIOD_US: u64 = 4_000;
/// How often the push modes ask the scheduler, ms (the firmware's `PUSH_POLL`).
const PUSH_POLL_MS: u64 = 2;
/// Bytes of the phone's writes the HM-10 task takes per poll (the firmware's UART read
/// buffer).
const HM10_READ_BYTES: usize = 64;

/// The module's RFM22B: SDN wired (the nRF52840 drives it).
pub(crate) type ModuleDriver = Rfm22b<SimSpi, SimIrq, SimSdn, SimDelay>;

/// The module's radio (its faults are injected through the world's chip handle). Each
/// boot's link task runs it as the firmware's does (`openlrs::dual::DualRadio` on that
/// boot's clock); the slot is empty only while a boot runs.
pub(crate) struct ModuleChip {
    pub(crate) radio: Option<ModuleDriver>,
    power: TxPower,
}

impl ModuleChip {
    pub(crate) fn new(handle: si4432_sim::RadioHandle, tx_power: u8) -> Self {
        Self {
            radio: Some(Rfm22b::new(
                handle.spi,
                handle.nirq,
                handle.sdn,
                handle.delay,
            )),
            power: TxPower::from_step(tx_power),
        }
    }
}

type ModuleApp = App<AirLink, Handset>;

/// The tasks the module's supervisor expects here (the firmware registers these; the LED,
/// button, battery, settings and JR-line tasks only idle and check in, so they are left out).
const EXPECTED: [Watched; 4] = [Watched::Radio, Watched::PpmIn, Watched::Hm10, Watched::App];

/// One boot's context.
struct Board {
    app: RefCell<ModuleApp>,
    clock: SimClock,
    /// module-core's check-in policy, as the firmware's supervisor runs it.
    check_ins: CheckIns,
    last_feed_ms: Cell<u32>,
}

impl Board {
    fn check_in(&self, t: Watched) {
        self.check_ins.check_in(t);
    }

    fn now_ms(&self) -> u32 {
        self.clock.now_ms()
    }

    fn time(&self) -> &VirtualTime {
        self.clock.time()
    }
}

/// The board as the link task's body sees it (the firmware's `Ports`).
struct Ports<'a> {
    b: &'a Board,
    shared: &'a Shared,
}

impl LinkPorts for Ports<'_> {
    type Handset = Handset;

    fn with_app<R>(&self, f: impl FnOnce(&mut ModuleApp) -> R) -> Option<R> {
        self.b.app.try_borrow_mut().ok().map(|mut app| f(&mut app))
    }

    fn check_in(&self) {
        self.b.check_in(Watched::Radio);
    }

    fn now_ms(&self) -> u32 {
        self.b.now_ms()
    }

    fn carry_out(&self, action: Action) {
        carry_out(self.shared, Some(action));
    }
}

/// The firmware's link task: `module_core::link_task::run_link_step` in a loop, on the
/// board's driver lent to a `DualRadio` for this boot (given back when the boot ends).
async fn link_task(b: &Board, chip: &RefCell<ModuleChip>, shared: &Shared, seed: u64) {
    let mut rng = SplitMix64::new(seed ^ 0x4D0D);
    let mut clock = b.clock.clone();
    let (driver, power) = {
        let mut c = chip.borrow_mut();
        (c.radio.take(), c.power)
    };
    let Some(driver) = driver else {
        return;
    };
    let now = clock.clone();
    let radio = DualRadio::new(driver, power, move || now.now_us());
    let mut radio = GiveBack(Some(radio), chip);
    let ports = Ports { b, shared };
    loop {
        let Some(radio) = radio.0.as_mut() else {
            return;
        };
        let random = rng.next_u64() as u32;
        run_link_step(&ports, radio, &mut clock, random).await;
    }
}

/// Puts the driver back in the board's slot when the boot's link task ends.
struct GiveBack<'a, C: Clock>(
    Option<DualRadio<SimSpi, SimIrq, SimSdn, SimDelay, C>>,
    &'a RefCell<ModuleChip>,
);

impl<C: Clock> Drop for GiveBack<'_, C> {
    fn drop(&mut self) {
        if let Some((driver, _)) = self.0.take().and_then(|radio| radio.release()) {
            self.1.borrow_mut().radio = Some(driver);
        }
    }
}

/// The firmware's `carry_out`: a save goes to the settings task (the firmware's `SAVE`
/// signal: the newest wins); the LED is not modelled.
fn carry_out(shared: &Shared, action: Option<Action>) {
    if let Some(Action::Save(settings)) = action {
        shared.borrow_mut().module_save = Some(settings);
    }
}

/// The settings task (the firmware's `settings_task`): every 50 ms, a pending save goes
/// through module-core's `SettingsStore` to the module's flash, halting the board for the
/// NVMC's time (`module_flash::nrf52840_us`: pages erased, words written).
async fn settings_task(b: &Board, shared: &Shared) {
    loop {
        sleep_ms(b.time(), 50).await;
        let pending = shared.borrow_mut().module_save.take();
        let Some(settings) = pending else {
            continue;
        };
        let (_saved, us) = shared.borrow_mut().module_flash.save(&settings);
        {
            let mut s = shared.borrow_mut();
            s.module_busy_until_ns = s.now_ns() + us * 1000;
        }
        b.time().sleep_ns(us * 1000).await;
    }
}

/// Waits while the module's CPU is halted by its NVMC.
async fn wait_while_halted(shared: &Shared, time: &VirtualTime) {
    loop {
        let left = {
            let s = shared.borrow();
            s.module_busy_until_ns.saturating_sub(s.now_ns())
        };
        if left == 0 {
            return;
        }
        time.sleep_ns(left).await;
    }
}

/// The PPM capture task: the handset's frame as falling edges, each stamped (by the
/// capture timer, exact to 1 µs) and handed to the core; a tick at the core's frame
/// release deadline (`App::ppm_deadline_us`); without edges, the idle tick. The handset
/// encodes each frame from the sticks as they are at the frame's first edge.
async fn ppm_in_task(b: &Board, shared: &Shared) {
    let mut clock = b.clock.clone();
    let mut frame_start = clock.now_us();
    loop {
        b.check_in(Watched::PpmIn);
        // Not earlier: read at the previous frame's release (8.5 ms before this frame
        // started), the sticks reached the air a whole frame late whenever they moved in
        // between.
        clock.sleep_until_us(frame_start).await;
        let input = shared.borrow().input;
        if !input.handset_connected {
            sleep_ms(b.time(), PPM_IDLE_MS).await;
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
            let next = match ch.get(i).filter(|_| i < PPM_CHANNELS) {
                Some(v) => edge + u64::from(ticks_to_us(*v)),
                None => frame_start + PPM_FRAME_US,
            };
            // The firmware task also wakes at the core's release deadline when no edge
            // comes first (the frame's sync gap proven after its last channel).
            let deadline = b.app.borrow().ppm_deadline_us();
            if let Some(d) = deadline {
                let at = edge + u64::from(d.wrapping_sub(t));
                if at < next {
                    clock.sleep_until_us(at).await;
                    b.app.borrow_mut().on_ppm_tick(d);
                }
            }
            edge = next;
        }
        frame_start += PPM_FRAME_US;
    }
}

/// The JR-line task (the firmware's `jr_line_task`) with EdgeTX at the other end. CRSF: the
/// radio sends the pilot's channels every [`CRSF_PERIOD_US`] — in the period after its
/// model selection (`PilotInput::radio_model`) changes, the model-select command instead,
/// as EdgeTX does at start and on a model change; once the frame has crossed the
/// line the module decodes it (`on_handset_bytes`, `on_handset_idle`) and its reply goes
/// back; a save or bind the radio asked for is carried out. Push modes: the scheduler is
/// asked every [`PUSH_POLL_MS`]. Every burst the module sends is recorded with the
/// scenario time in `WorldState::handset_tx`.
async fn jr_line_task(b: &Board, shared: &Shared) {
    let mode = b.app.borrow().handset().line_mode();
    let mut clock = b.clock.clone();
    let mut reply = [0u8; MAX_LINE_BURST];
    let mut frame_start = clock.now_us();
    let mut model_sent: Option<u8> = None;
    loop {
        let sent = match mode {
            LineMode::Crsf { baud } => {
                let input = shared.borrow().input;
                let mut sent = 0;
                if input.handset_connected {
                    let mut frame = [0u8; 64];
                    let radio_frame = match input.radio_model {
                        Some(model_id) if model_sent != Some(model_id) => {
                            model_sent = Some(model_id);
                            let select = ModelSelect {
                                destination: address::TX_MODULE,
                                origin: address::RADIO,
                                model_id,
                            };
                            Frame::new(
                                address::TX_MODULE,
                                frame_type::COMMAND,
                                &select.to_payload(),
                            )
                            .ok()
                        }
                        _ => Some(
                            RcChannels {
                                ticks: transmitter(&input),
                            }
                            .to_frame(),
                        ),
                    };
                    let n = radio_frame
                        .and_then(|f| f.encode(&mut frame).ok().map(<[u8]>::len))
                        .unwrap_or(0);
                    // 10 bits per byte on the line.
                    let line_us = (n as u64 * 10 * 1_000_000).div_ceil(u64::from(baud));
                    clock.sleep_until_us(frame_start + line_us).await;
                    let now = clock.now_us();
                    let mut app = b.app.borrow_mut();
                    app.on_handset_bytes(now, frame.get(..n).unwrap_or(&[]));
                    app.on_handset_idle(now);
                    sent = app.next_handset_bytes(now, &mut reply).len();
                    while let Some(action) = app.take_action() {
                        carry_out(shared, Some(action));
                    }
                }
                frame_start += CRSF_PERIOD_US;
                clock.sleep_until_us(frame_start).await;
                sent
            }
            LineMode::Push { .. } => {
                let now = clock.now_us();
                let sent = b.app.borrow_mut().next_handset_bytes(now, &mut reply).len();
                sleep_ms(b.time(), PUSH_POLL_MS).await;
                sent
            }
            LineMode::Off => {
                sleep_ms(b.time(), 100).await;
                0
            }
        };
        if let Some(bytes) = reply.get(..sent).filter(|r| !r.is_empty()) {
            let mut s = shared.borrow_mut();
            let t = s.scenario_s();
            s.handset_tx.push((t, bytes.to_vec()));
        }
    }
}

/// The 10 Hz app task.
async fn app_task(b: &Board, shared: &Shared) {
    loop {
        b.check_in(Watched::App);
        let action = b.app.borrow_mut().on_tick();
        carry_out(shared, action);
        sleep_ms(b.time(), 100).await;
    }
}

/// A message from the phone, as the HM-10 hands its bytes to the module.
fn send_to_flight(b: &Board, message: &Message) {
    let mut buf = [0u8; FRAMED_MAX_BYTES];
    if let Ok(bytes) = encode_message(message, &mut buf) {
        b.app.borrow_mut().on_phone_bytes(bytes);
    }
}

/// The HM-10 task with a phone connected: records to the phone (decoded: what the module
/// received; raw to an attached page), the scenario's setting changes and an attached
/// page's bytes from the phone.
async fn hm10_task(b: &Board, shared: &Shared) {
    let mut reader = MessageReader::new();
    let mut phone = shared.borrow().phone_key.map(Signer::new);
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
        // An attached phone's writes, as the UART delivers them (at most a read's worth).
        let written: Vec<u8> = match shared.borrow_mut().phone.as_mut() {
            Some(p) => {
                let n = p.from_phone.len().min(HM10_READ_BYTES);
                p.from_phone.drain(..n).collect()
            }
            None => Vec::new(),
        };
        if !written.is_empty() {
            b.app.borrow_mut().on_phone_bytes(&written);
        }
        loop {
            let Some(n) = b.app.borrow_mut().next_phone_frame(&mut frame) else {
                break;
            };
            let sent = frame.get(..n).unwrap_or(&[]);
            if let Some(p) = shared.borrow_mut().phone.as_mut() {
                p.to_phone.extend(sent);
                let excess = p.to_phone.len().saturating_sub(TO_PHONE_MAX);
                p.to_phone.drain(..excess);
            }
            for &byte in sent {
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
        sleep_ms(b.time(), HM10_POLL_MS).await;
    }
}

/// The supervisor: every 100 ms, fed if every expected task checked in (not while the
/// NVMC halts the CPU).
async fn supervisor_task(b: &Board, shared: &Shared) {
    loop {
        sleep_ms(b.time(), u64::from(FEED_PERIOD_MS)).await;
        wait_while_halted(shared, b.time()).await;
        if b.check_ins.poll() {
            b.last_feed_ms.set(b.now_ms());
        }
    }
}

/// The WDT: returns when it expires.
async fn watchdog(b: &Board) {
    loop {
        sleep_ms(b.time(), 5).await;
        if u64::from(b.now_ms().wrapping_sub(b.last_feed_ms.get())) >= MODULE_WATCHDOG_MS {
            return;
        }
    }
}

/// The module board, forever: boot, run, reset on the WDT.
pub(crate) async fn module_board(
    shared: Shared,
    medium: Medium,
    time: VirtualTime,
    chip: ModuleChip,
    seed: u64,
) {
    let chip = RefCell::new(chip);
    let mut cause = BootCause::PowerOn;
    loop {
        sleep_ms(&time, MODULE_BOOT_MS).await;
        let settings: ModuleSettings = shared.borrow_mut().module_flash.load();
        let Ok(mut app) = App::new(settings, AirLink::new(), Handset::new(&settings), true) else {
            return;
        };
        // The firmware's RNG at boot seeds the module's secrets.
        let mut boot_rng = SplitMix64::new(seed ^ crate::clock::virtual_us(&medium));
        let mut random = [0u8; 32];
        for chunk in random.chunks_exact_mut(8) {
            chunk.copy_from_slice(&boot_rng.next_u64().to_le_bytes());
        }
        app.seed_random(&random);
        shared.borrow_mut().record_boot(End::Module, cause, false);
        let clock = SimClock::booting_now(medium.time(), MODULE_DRIFT_PPM);
        let board = Board {
            app: RefCell::new(app),
            last_feed_ms: Cell::new(clock.now_ms()),
            clock,
            check_ins: CheckIns::new(),
        };
        for task in EXPECTED {
            board.check_ins.expect(task);
        }
        let tasks = join(
            join5(
                link_task(&board, &chip, &shared, seed),
                ppm_in_task(&board, &shared),
                app_task(&board, &shared),
                hm10_task(&board, &shared),
                supervisor_task(&board, &shared),
            ),
            join(
                jr_line_task(&board, &shared),
                settings_task(&board, &shared),
            ),
        );
        let _ = select(tasks, watchdog(&board)).await;
        shared.borrow_mut().watchdog_resets.module += 1;
        cause = BootCause::Watchdog;
    }
}
