//! The module core's periodic work at 10 Hz: link state, failsafe, handset statistics, LED.

use embassy_time::{Duration, Ticker};

use super::supervisor::{Watched, check_in};
use crate::firmware::shared::{carry_out, with_app};

#[embassy_executor::task]
pub async fn app_task() {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        check_in(Watched::App);
        carry_out(with_app(|app| app.on_tick()).flatten());
        ticker.next().await;
    }
}
