//! The module core's periodic work at 10 Hz: link state, failsafe, handset statistics, LED;
//! and the derivation of a binding phrase typed on the radio, in steps.

use embassy_time::{Duration, Ticker};

use super::supervisor::{Watched, check_in};
use crate::firmware::shared::{carry_out, with_app};

#[embassy_executor::task]
pub async fn app_task() {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        check_in(Watched::App);
        carry_out(with_app(|app| app.on_tick()).flatten());
        // A phrase typed on the radio: its derivation (≈ 2 s of the nRF52840), one iteration
        // (≈ 0.4 ms) under the core's lock at a time, yielding between them so the JR line
        // and the link keep their timing.
        while with_app(|app| app.step_phrase_job(1)).unwrap_or(false) {
            check_in(Watched::App);
            embassy_futures::yield_now().await;
        }
        while let Some(action) = with_app(|app| app.take_action()).flatten() {
            carry_out(Some(action));
        }
        ticker.next().await;
    }
}
