//! `--attack`: a third radio in the chip-level medium that hears everything on air and
//! attacks the keyed link (spec §12) — forging, replaying, or spoofing binds while the flight
//! side power-cycles — and the means to count what the victims accepted: a radio wrapper
//! that asks the medium who sent each packet it delivered ([`Witnessed`]), so the ends'
//! hooks can attribute every frame their link core accepted.
//!
//! The attackers are the attacker's behaviour, not the link's: the victims run the real
//! link cores (and, for the flight side's boot decision, the real `flight_app` app).

mod grid;
pub mod guess;
mod replay;

use std::cell::Cell;
use std::future::Future;
use std::pin::pin;
use std::rc::Rc;
use std::task::Poll;

use si4432_sim::{ChipHandle, Medium, Outcome as ChipOutcome, RadioId, SimDelay};
use telemetry::channels::{ChannelFormat, Channels, pack};
use telemetry::frame::{Downlink, Frame, StreamHeader, Uplink, encode, seal};
use telemetry::link::auth::TagContext;
use telemetry::link::bind::{Offering, bind_radio_config};
use telemetry::link::follower::run_follower;
use telemetry::link::{
    BIND_KEY, BindAuth, HOP_CHANNELS, HopSequence, LinkKey, LinkParams, LinkRx, PacketRadio,
    RadioConfig, RateMode, Schedule,
};
use telemetry::mock::SplitMix64;

use crate::driver::SimClock;
use crate::ends::{FlightStart, follower_for};
use crate::probe::{FlightApp, Shared};
use crate::scenario::{Attack, Scenario};

/// Throttle the forger tries to fly.
pub const FORGED_THROTTLE: u16 = 1811;
/// Bind ID of the spoofed bind offers.
const SPOOF_BIND_ID: u32 = 0xBAD_B1D5;
/// Gap between spoofed bind offers: four times the module's offer rate.
const SPOOF_PERIOD_US: u64 = 20_000;
/// How long a power-cycled flight side stays off.
const POWER_OFF_US: u64 = 300_000;

/// What the guesser of `--attack guess` recorded and found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuessFigures {
    /// Bind frames recorded.
    pub bind_frames: u32,
    /// Link frames recorded after the bind.
    pub link_frames: u32,
    /// Of them, epoch-nonce frames.
    pub nonce_frames: u32,
    /// The dictionary's verdict.
    pub verdict: guess::Verdict,
}

/// A radio that, on every packet delivered, notes which radio sent it (from the medium's
/// trace).
pub struct Witnessed<R> {
    inner: R,
    medium: Medium,
    me: RadioId,
    last_sender: Rc<Cell<Option<RadioId>>>,
    enabled: bool,
}

impl<R> Witnessed<R> {
    /// `inner`, the radio `me` in `medium`; looks senders up only when `enabled`.
    pub fn new(inner: R, medium: Medium, me: RadioId, enabled: bool) -> Self {
        Self {
            inner,
            medium,
            me,
            last_sender: Rc::new(Cell::new(None)),
            enabled,
        }
    }

    /// Where the sender of the last delivered packet is kept.
    pub fn last_sender(&self) -> Rc<Cell<Option<RadioId>>> {
        self.last_sender.clone()
    }
}

impl<R: PacketRadio> PacketRadio for Witnessed<R> {
    type Error = R::Error;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        self.inner.configure(config).await
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error> {
        self.inner.set_channel(channel).await
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        self.inner.transmit(frame).await
    }

    async fn begin_transmit(&mut self, len: usize) -> Result<(), Self::Error> {
        self.inner.begin_transmit(len).await
    }

    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        self.inner.finish_transmit(frame).await
    }

    async fn set_tx_power(&mut self, step: u8) -> Result<(), Self::Error> {
        self.inner.set_tx_power(step).await
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, Self::Error> {
        let outcome = self.inner.receive(buf, timeout_us).await?;
        if self.enabled && matches!(outcome, LinkRx::Packet { .. }) {
            let me = self.me;
            let sender = self.medium.with_trace(|frames| {
                frames
                    .iter()
                    .rev()
                    .find(|f| {
                        f.receptions.iter().any(|r| {
                            r.radio == me && matches!(r.outcome, ChipOutcome::Delivered { .. })
                        })
                    })
                    .map(|f| f.radio)
            });
            self.last_sender.set(sender);
        }
        Ok(outcome)
    }

    async fn check_health(&mut self) -> Result<(), Self::Error> {
        self.inner.check_health().await
    }

    async fn recover(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        self.inner.recover(config).await
    }
}

/// Runs `work` until it ends or `stop` completes first (then `work` is dropped, as power
/// loss would stop it).
async fn until<T>(work: impl Future<Output = T>, stop: impl Future<Output = ()>) -> Option<T> {
    let mut work = pin!(work);
    let mut stop = pin!(stop);
    std::future::poll_fn(|cx| {
        if let Poll::Ready(v) = work.as_mut().poll(cx) {
            return Poll::Ready(Some(v));
        }
        if stop.as_mut().poll(cx).is_ready() {
            return Poll::Ready(None);
        }
        Poll::Pending
    })
    .await
}

/// When the flight side is switched off and on again (virtual µs) under `attack`.
pub fn power_plan(attack: Attack, duration_s: f64) -> Vec<(u64, u64)> {
    let end_us = (duration_s * 1e6) as u64;
    let offs: Vec<u64> = match attack {
        Attack::Forge | Attack::Guess => Vec::new(),
        // One earlier session to record, then the attack on the next.
        Attack::NonceReplay => vec![end_us / 6],
        Attack::Replay => vec![end_us / 3, 2 * end_us / 3],
        Attack::BindSpoof => (1..)
            .map(|k| k * 5_000_000)
            .take_while(|t| *t < end_us)
            .collect(),
    };
    offs.into_iter().map(|t| (t, t + POWER_OFF_US)).collect()
}

/// How the power-cycled flight side runs.
pub(crate) struct Powered {
    /// Virtual time (for the power plan).
    pub medium: Medium,
    /// Sleeps in virtual time.
    pub delay: SimDelay,
    /// The flight side's radio chip (it loses power too).
    pub chip: ChipHandle,
    /// (off, on) virtual µs.
    pub plan: Vec<(u64, u64)>,
    /// The module's link (the flight side must never run another).
    pub module_params: LinkParams,
}

impl Powered {
    async fn sleep_until_virtual(&self, t_us: u64) {
        let now_ns = self.medium.now().as_nanos() as u64;
        self.delay
            .sleep_ns((t_us * 1000).saturating_sub(now_ns))
            .await;
    }
}

/// The flight end of an attacked run: bound before the run (its flash holds the module's
/// link), it boots, asks the real flight application what to run — `flight_app`'s explicit
/// bind: a bind only after the console's command, so never here — and runs it, until the
/// power plan switches it off; then again from boot, with a fresh nonce seed as a hardware
/// RNG would give.
pub(crate) async fn flight_end_powered<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    start: FlightStart,
    mut app: FlightApp,
    record: Shared,
    power: Powered,
) {
    let mut flash = flight_app::settings::Settings::default();
    if flight_app::pipeline::store_link(&mut flash, &start.params).is_err() {
        return;
    }
    if let Some((key, _)) = start.key {
        flash.set_link_key(Some(key));
    }
    let boot_delay = clock.now_us() + 123_457;
    clock.sleep_until_us(boot_delay).await;
    let mut plan = power.plan.iter().copied();
    for boot in 0u64.. {
        let off = plan.next();
        let session = async {
            let Some(mut fc) = flight_app::app::FlightApp::new(flash.clone(), 0) else {
                return;
            };
            let params = if matches!(fc.next_link_step(), flight_app::app::LinkStep::Bind { .. }) {
                start
                    .bind(&mut radio, &mut clock)
                    .await
                    .map(|(params, _)| params)
            } else {
                fc.link_params()
            };
            let Some(params) = params else {
                return;
            };
            {
                let mut rec = record.borrow_mut();
                if params != power.module_params {
                    rec.rebinds += 1;
                }
                rec.follower_params = Some(params);
                rec.bound_us
                    .get_or_insert(power.medium.now().as_micros() as u64);
            }
            let key = start
                .key
                .map(|(k, seed)| (k, seed ^ boot.wrapping_mul(0x9E37)));
            let mut follower = follower_for(params, start.failsafe_us, key);
            let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut app).await;
        };
        let Some((off_us, on_us)) = off else {
            session.await;
            return;
        };
        if until(session, power.sleep_until_virtual(off_us))
            .await
            .is_some()
        {
            return;
        }
        record.borrow_mut().power_cycles += 1;
        power.sleep_until_virtual(on_us).await;
        power.chip.power_on_reset();
    }
}

/// What the attacker knows of the victim link: public values only.
pub(crate) struct Victim {
    /// The link's public identity (bind ID), heard in the header.
    pub bind_id: u32,
    /// The link's radio configuration (header from the public bind ID).
    pub config: RadioConfig,
    /// The hop sequence (heard on air).
    pub hops: HopSequence,
    /// Rate and telemetry ratio (heard on air).
    pub schedule: Schedule,
    /// Band (for bind spoofing).
    pub band: telemetry::link::Band,
    /// Channel format.
    pub format: ChannelFormat,
}

/// The victim link as an attacker sees it: everything derived from `params` (the public
/// bind ID: header and hop sequence), never the key.
pub(crate) fn victim_of(s: &Scenario, params: &LinkParams) -> Victim {
    Victim {
        bind_id: params.bind_id,
        config: params.radio_config(),
        hops: HopSequence::new(params.bind_id),
        schedule: Schedule {
            rate: s.rate,
            telemetry_ratio: s.telemetry_ratio,
        },
        band: s.band,
        format: s.format,
    }
}

/// Runs the attacker of `attack` on `radio` until the simulation ends (the guesser with
/// `dictionary`).
pub(crate) async fn attacker<R: PacketRadio>(
    attack: Attack,
    radio: R,
    clock: SimClock,
    victim: Victim,
    record: Shared,
    seed: u64,
    dictionary: Vec<String>,
) {
    let _ = match attack {
        Attack::Forge => forge(radio, clock, &victim, &record, seed).await,
        Attack::Replay => replay::replay(radio, clock, &victim, &record).await,
        Attack::BindSpoof => bind_spoof(radio, clock, &victim, &record, seed).await,
        Attack::NonceReplay => replay::nonce_replay(radio, clock, &victim, &record).await,
        Attack::Guess => guess::guess(radio, clock, &victim, &record, &dictionary).await,
    };
}

/// Forged frames on the victim's hop channels, one every ¾ slot, walking the slot numbers:
/// uplinks with full throttle and the save-failsafe flag (sealed under a guessed key with a
/// guessed counter, or as version 1 frames with the public bind ID's CRC), downlinks and
/// epoch-nonce frames under guessed keys.
async fn forge<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    victim: &Victim,
    record: &Shared,
    seed: u64,
) -> Result<(), R::Error> {
    radio.configure(&victim.config).await?;
    let mut rng = SplitMix64::new(seed ^ 0xF0F6_E000);
    let mut evil: Channels = [992; 16];
    evil[2] = FORGED_THROTTLE;
    let mut packed = [0u8; 22];
    let Some(packed) = packed.get_mut(..victim.format.packed_bytes()) else {
        return Ok(());
    };
    pack(&evil, victim.format, packed);
    let gap = u64::from(victim.schedule.slot_us()) * 3 / 4;
    for n in 0u64.. {
        let slot = (n % 256) as u8;
        let guess = LinkKey::from_bytes(core::array::from_fn(|_| rng.next_u64() as u8));
        let counter = TagContext::Counter(rng.next_u64() >> 32);
        let mut buf = [0u8; 64];
        let up = Frame::Uplink(Uplink {
            slot,
            stream: StreamHeader::default(),
            report: None,
            save_failsafe: true,
            input_lost: false,
            format: victim.format,
            packed_channels: packed,
            data: &[],
        });
        let len = match n % 5 {
            0 => seal(&up, &guess, &counter, &mut buf),
            1 => encode(&up, victim.bind_id, &mut buf),
            2 => seal(
                &Frame::Downlink(Downlink {
                    slot,
                    stream: StreamHeader::default(),
                    report: None,
                    data: b"setting!",
                }),
                &guess,
                &counter,
                &mut buf,
            ),
            3 => seal(
                &Frame::Nonce {
                    slot,
                    nonce: rng.next_u64() | 1,
                    proof: None,
                },
                &guess,
                &TagContext::FollowerNonce,
                &mut buf,
            ),
            _ => seal(
                &Frame::MasterNonce {
                    slot,
                    nonce: rng.next_u64() | 1,
                },
                &guess,
                &TagContext::MasterNonce {
                    follower_nonce: rng.next_u64() | 1,
                },
                &mut buf,
            ),
        };
        if let Some(frame) = len.ok().and_then(|len| buf.get(..len)) {
            radio
                .set_channel(victim.hops.channel(usize::from(slot) % HOP_CHANNELS))
                .await?;
            radio.transmit(frame).await?;
            record.borrow_mut().attacker_sent += 1;
        }
        let next = clock.now_us() + gap;
        clock.sleep_until_us(next).await;
    }
    Ok(())
}

/// Bind offers of the attacker's own link (a key agreement without a phrase, which any
/// follower in a bind window without one would take) on the band's bind channel, every
/// 20 ms.
async fn bind_spoof<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    victim: &Victim,
    record: &Shared,
    seed: u64,
) -> Result<(), R::Error> {
    radio.configure(&bind_radio_config(victim.band)).await?;
    radio.set_channel(0).await?;
    let params = LinkParams::new(
        SPOOF_BIND_ID,
        victim.band,
        RateMode::F500,
        ChannelFormat::Full16,
        4,
    );
    let random = crate::scenario::seed_bytes(seed, 0x5b00f);
    let offer = Frame::BindOffer(Offering::new(&params, &BindAuth::Anonymous, &random).offer());
    let mut buf = [0u8; 64];
    let Ok(len) = encode(&offer, BIND_KEY, &mut buf) else {
        return Ok(());
    };
    let frame = buf.get(..len).unwrap_or(&[]);
    loop {
        radio.transmit(frame).await?;
        record.borrow_mut().attacker_sent += 1;
        let next = clock.now_us() + SPOOF_PERIOD_US;
        clock.sleep_until_us(next).await;
    }
}
