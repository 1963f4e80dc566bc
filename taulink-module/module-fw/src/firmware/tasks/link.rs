//! Owns the RFM22B and carries out the module core's link steps (`module_core::session`):
//! probe the chip, run the master or follower loop with the core as its hook, bind — or,
//! with the OpenLRSng protocol, the core's OpenLRSng transmitter loop
//! (`module_core::air::openlrs::run_openlrs_transmitter`) and OpenLRSng's bind, the driver's
//! parts lent to an OpenLRSng radio for the step. What to do next, when to stop and what a
//! bind means are the core's decisions.

use embassy_futures::select::{Either, select};
use embassy_nrf::rng::Rng;
use embassy_time::{Delay, Instant, Timer};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use embedded_hal_bus::spi::ExclusiveDevice;
use module_core::air::openlrs::run_openlrs_transmitter;
use module_core::app::Action;
use module_core::session::{BindOutcome, LinkStep, POLL_MS, SessionEnd};
use module_core::settings::Settings;
use openlrs::BindingVersion;
use openlrs::radio::Radio as OpenLrsRadio;
use openlrs::roles::tx_bind;
use openlrs::tx::Transmitter;
use radio_rfm22b::RfmType;
use radio_rfm22b::{Rfm22b, TxPower};
use telemetry::link::follower::{bind_follower, run_follower};
use telemetry::link::master::{bind_master, run_master};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;
use crate::firmware::link_radio::{EmbassyClock, Hooks, keep_alive, log, poll_session, run};
use crate::firmware::shared::{carry_out, now_ms, with_app};

#[embassy_executor::task]
pub async fn link_task(radio: Radio, boot_settings: Settings) {
    let Ok(device) = ExclusiveDevice::new_no_delay(radio.spim, radio.nsel);
    let mut rng = Rng::new_blocking(radio.rng);
    let power = TxPower::from_step(boot_settings.tx_power);
    let mut slot = Some(LinkRadio::new(
        Rfm22b::new(device, radio.nirq, radio.sdn, Delay),
        power,
    ));
    // A receiver-role follower's epoch nonces (spec §12.2): a fresh seed every boot.
    let seed = u64::from(rng.blocking_next_u32()) << 32 | u64::from(rng.blocking_next_u32());
    with_app(|app| app.seed_link_nonces(seed));
    let (clock, hooks) = (&mut EmbassyClock, &mut Hooks);
    loop {
        check_in(Watched::Radio);
        let random = rng.blocking_next_u32();
        let step = with_app(|app| app.next_link_step(now_ms(), random));
        let step = step.unwrap_or(LinkStep::Wait { ms: POLL_MS });
        if let LinkStep::RunOpenLrsTx(_) | LinkStep::BindOpenLrsTx { .. } = step {
            let action = openlrs_step(&mut slot, power, step).await;
            carry_out(action.flatten());
            continue;
        }
        let Some(chip) = slot.as_mut() else {
            return;
        };
        let action = match step {
            LinkStep::Probe => {
                let present = chip.driver().reset().await.inspect_err(log).is_ok();
                with_app(|app| app.on_radio_present(present))
            }
            LinkStep::Wait { ms } => {
                keep_alive(Timer::after_millis(ms.into())).await;
                None
            }
            LinkStep::WaitForBind => {
                let end = poll_session().await;
                with_app(|app| app.on_session_end(end))
            }
            // The core builds the loops: keyed with the binding phrase's key when one is set.
            LinkStep::RunMaster(params) => match with_app(|app| app.master(params)) {
                Some(mut master) => {
                    let end = run(run_master(chip, clock, &mut master, hooks)).await;
                    with_app(|app| app.on_session_end(end))
                }
                None => None,
            },
            LinkStep::RunFollower {
                params,
                failsafe,
                failsafe_us,
            } => match with_app(|app| app.follower(params, failsafe, failsafe_us)) {
                Some(mut follower) => {
                    let end = run(run_follower(chip, clock, &mut follower, hooks)).await;
                    with_app(|app| app.on_session_end(end))
                }
                None => None,
            },
            LinkStep::BindMaster { params, timeout_us } => {
                let accepted = keep_alive(bind_master(chip, clock, &params, timeout_us)).await;
                let outcome = BindOutcome::offered(accepted.inspect_err(log));
                with_app(|app| app.on_bind_outcome(outcome))
            }
            LinkStep::BindFollower { band, timeout_us } => {
                let offer = keep_alive(bind_follower(chip, clock, band, timeout_us)).await;
                let outcome = BindOutcome::listened(offer.inspect_err(log));
                with_app(|app| app.on_bind_outcome(outcome))
            }
            LinkStep::RunOpenLrsTx(_) | LinkStep::BindOpenLrsTx { .. } => None,
        };
        carry_out(action.flatten());
    }
}

/// An OpenLRSng step: the driver's parts become an OpenLRSng radio for the step (the
/// OpenLRSng role programs the chip its own way) and go back afterwards.
async fn openlrs_step<SPI, IRQ, SDN>(
    slot: &mut Option<LinkRadio<SPI, IRQ, SDN, Delay>>,
    power: TxPower,
    step: LinkStep,
) -> Option<Option<Action>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    openlrs::radio::Error<SPI::Error, IRQ::Error>: defmt::Format,
{
    let (LinkStep::RunOpenLrsTx(data) | LinkStep::BindOpenLrsTx { data, .. }) = step else {
        return None;
    };
    let link = slot.take()?;
    let (spi, irq, sdn, delay) = link.release().release();
    let version = BindingVersion::from_byte(data.version).unwrap_or(BindingVersion::V39);
    let band = data.band().unwrap_or(RfmType::Mhz433);
    let now = || Instant::now().as_micros();
    let mut radio = OpenLrsRadio::new(spi, irq, delay, now, version, band);
    let action = match step {
        LinkStep::BindOpenLrsTx { data, timeout_us } => {
            let until = radio.now_us().saturating_add(timeout_us);
            let accepted = keep_alive(tx_bind(&mut radio, &data, until)).await;
            let outcome = BindOutcome::offered(accepted.inspect_err(log));
            with_app(|app| app.on_bind_outcome(outcome))
        }
        _ => {
            let end = match Transmitter::new(data, radio.now_us()) {
                Ok(tx) => {
                    let mut tx = tx.with_stale_input_stop();
                    let run = run_openlrs_transmitter(
                        &mut radio,
                        &mut tx,
                        |tx| {
                            with_app(|app| app.on_openlrs_send(tx));
                        },
                        |now_us, tx, events| {
                            with_app(|app| app.on_openlrs_step(now_us, now_ms(), tx, events));
                        },
                    );
                    match select(run, poll_session()).await {
                        Either::First(e) => {
                            log(&e);
                            SessionEnd::RadioFailed
                        }
                        Either::Second(end) => end,
                    }
                }
                Err(_) => poll_session().await,
            };
            with_app(|app| app.on_session_end(end))
        }
    };
    let (spi, irq, delay, _) = radio.release();
    *slot = Some(LinkRadio::new(Rfm22b::new(spi, irq, sdn, delay), power));
    Some(action.flatten())
}
