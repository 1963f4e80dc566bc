//! Hands the flight loop's reports to the application (thread mode, under the app's lock,
//! which the loop never takes): `FlightApp::on_loop_report` (the loop's watchdog check-in,
//! alerts, arming refusals, what the console and telemetry show), a designed setup into the
//! loop's mailbox once the loop reports the motors stopped, the gains a resume needs into
//! the no-init record.

use flight_app::app::FlightApp;

use crate::firmware::fault::with_record;
use crate::firmware::shared::{
    LOOP_REPORT, REPORTED, SETUP, now_ms, put, take, with_app, with_slot,
};

#[embassy_executor::task]
pub async fn loop_report_task() {
    loop {
        REPORTED.wait().await;
        let Some(report) = take(&LOOP_REPORT) else {
            continue;
        };
        with_app(|a| {
            a.on_loop_report(now_ms(), &report);
            if !report.armed {
                offer_setup(a);
            }
            with_record(|r| a.keep_resume_gains(&mut r.gains));
        });
    }
}

/// A designed setup into the loop's mailbox, if one waits and the mailbox is free.
fn offer_setup(app: &mut FlightApp) {
    if with_slot(&SETUP, |s| !s.is_empty()).unwrap_or(true) {
        return;
    }
    if let Some(setup) = app.take_pending_setup() {
        put(&SETUP, setup);
    }
}
