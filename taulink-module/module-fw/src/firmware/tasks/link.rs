//! Owns the RFM22B and carries out the module core's link steps (`module_core::session`):
//! probe the chip, run the master or follower loop with the core as its hook, bind. What to
//! do next, when to stop and what a bind means are the core's decisions.

use embassy_nrf::rng::Rng;
use embassy_time::{Delay, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use module_core::air::radio::LinkRadio;
use module_core::session::{BindOutcome, LinkStep, POLL_MS};
use module_core::settings::Settings;
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
    let mut chip = LinkRadio::new(Rfm22b::new(device, radio.nirq, radio.sdn, Delay), power);
    let (chip, clock, hooks) = (&mut chip, &mut EmbassyClock, &mut Hooks);
    loop {
        check_in(Watched::Radio);
        let random = rng.blocking_next_u32();
        let step = with_app(|app| app.next_link_step(now_ms(), random));
        let action = match step.unwrap_or(LinkStep::Wait { ms: POLL_MS }) {
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
        };
        carry_out(action.flatten());
    }
}
