//! The application's half of the loop's exchange (`flight_core::loop_side`): the inputs it
//! hands the loop before a step ([`FlightApp::loop_inputs`]), what it does with the loop's
//! report after it ([`FlightApp::on_loop_report`]), and — on hosts that do not run the two
//! sides apart — one loop on its own side ([`FlightApp::on_imu_sample`]).

pub use crate::loop_side::{
    EstimatorStatus, ImuStep, LoopHealth, LoopInputs, LoopNews, LoopReport, LoopSide,
};

use super::{FlightApp, Task};
use crate::alerts::Alert;
use crate::logging::{Event, LoopContext, Profile};
use crate::loop_side::ImuFault;
use crate::outputs::Command;
use crate::pipeline::{Controllers, FlightSetup, ImuSample};

impl FlightApp {
    /// What the loop needs for its next step: the one-shot measurements are handed over
    /// once.
    pub fn loop_inputs(&mut self) -> LoopInputs {
        let mut inputs = LoopInputs {
            link: self.link_input,
            climb_mps: None,
            baro_m: None,
            gps: None,
            battery_critical: false,
            settings_problem: false,
            vertical_lost: false,
            usb_connected: false,
            magcal_collecting: false,
            mag_cal: None,
            setup_pending: false,
            log_loop: false,
        };
        self.loop_inputs_into(&mut inputs);
        inputs
    }

    /// Brings a mailbox the loop takes its inputs from up to date (the firmware's tasks, after
    /// each call into the app): the standing fields now, and a one-shot measurement only
    /// into an empty slot, so none the loop has not taken yet is lost.
    pub fn loop_inputs_into(&mut self, mailbox: &mut LoopInputs) {
        mailbox.link = self.link_input;
        mailbox.climb_mps = self.climb_mps;
        mailbox.battery_critical = self.battery_critical;
        mailbox.settings_problem = self.settings_problem.is_some();
        mailbox.vertical_lost = self.baro.failed();
        mailbox.usb_connected = self.board.usb_connected;
        mailbox.magcal_collecting = self.magcal.collecting();
        mailbox.setup_pending = self.pending_setup.is_some();
        mailbox.log_loop = self.log.profile() != Profile::Off;
        if mailbox.baro_m.is_none() {
            mailbox.baro_m = self.pending_baro_m.take();
        }
        if mailbox.gps.is_none() {
            mailbox.gps = self.gps.next_pvt();
        }
        if mailbox.mag_cal.is_none() {
            mailbox.mag_cal = self.mag_cal_changed.take();
        }
    }

    /// The designed setup for the loop to install (call only while the loop is disarmed):
    /// from here on the app's side runs it too (battery monitor, channel map, the gains a
    /// resume keeps).
    pub fn take_pending_setup(&mut self) -> Option<(FlightSetup, Controllers)> {
        let (setup, controllers, flown) = self.pending_setup.take()?;
        self.flown = flown;
        self.designs = Some(*controllers.designs());
        self.gains_changed = true;
        self.battery_monitor = crate::battery::BatteryMonitor::new(setup.battery);
        self.link.set_channel_map(setup.channels);
        self.log
            .reconfigure(super::log_profile(&self.live), setup.loop_rate_hz);
        self.setup = setup;
        Some((setup, controllers))
    }

    /// What the loop reported after a step at `now_ms` (the firmware's IMU task hands it
    /// over under the app's lock): the IMU task's check-in, arming refusals and the alerts,
    /// the identification for the link, the calibration's readings, the GPS fusion, the
    /// flight log's loop topics and events.
    pub fn on_loop_report(&mut self, now_ms: u32, report: &LoopReport) {
        self.watchdog.check_in(Task::Imu);
        for out in &report.news {
            self.record(*out);
        }
        if report.disarmed_for_sensor {
            self.player.push(Alert::SensorFault);
        }
        self.identified = report.identification;
        if let Some(id) = &report.identification {
            self.link.queue_identification(id);
        }
        // Arming ends a calibration being collected.
        if report.armed && self.magcal.collecting() {
            self.magcal.cancel();
        }
        if let Some(raw) = report.mag_raw {
            self.magcal.offer(now_ms, raw);
        }
        // The calibration's stick gesture (held for seconds: a merged report's coarser
        // cadence does not matter).
        self.on_magcal_gesture(now_ms);
        if let Some(update) = report.gps_update {
            self.gps.on_fused(now_ms, update, report.estimator.home);
        }
        let fault_before = self.view.as_ref().and_then(|v| v.imu_fault);
        self.view = Some(LoopReport {
            news: LoopNews::new(),
            ..report.clone()
        });
        if self.log.profile() != Profile::Off {
            self.log_report(now_ms, report, fault_before.is_none());
        }
    }

    /// The flight log's share of a report: a restart, the loop sample (steps merged away
    /// marked lost), a ride-through's decision, a finished identification.
    fn log_report(&mut self, now_ms: u32, report: &LoopReport, fault_new: bool) {
        if report.restarted {
            self.log.on_event(now_ms, Event::LoopRestarted);
        }
        let logged = u32::from(report.log.is_some());
        self.log
            .on_loops_missed(now_ms, report.log_steps.saturating_sub(logged));
        if let (Some(snapshot), Some(out)) = (&report.log, &report.out) {
            let context = LoopContext {
                snapshot,
                out,
                baro_altitude_m: self.baro_altitude_m(),
                arming_blockers: self.arming_blockers(),
                imu_fault: report.imu_fault,
            };
            self.log.on_loop(now_ms, &context);
        } else if report.imu_fault.is_some() {
            // No step ran: the ride-through holds; its decision, once it expires.
            if fault_new {
                self.log.on_event(now_ms, Event::ImuFault);
            }
            for out in &report.news {
                self.log.on_event(now_ms, Event::Decision(out.decision));
            }
        }
        if let Some(id) = &report.identification {
            self.log.on_identified(now_ms, id);
        }
    }

    /// One loop on the app's own loop side (hosts: the tests and simulators that do not run
    /// the two sides apart): inputs, a setup to install while disarmed, the step, the
    /// report — the sequence the firmware's IMU task runs.
    fn run_loop(
        &mut self,
        now_ms: u32,
        run: impl FnOnce(&mut LoopSide, &LoopInputs) -> (ImuStep, LoopReport),
    ) -> ImuStep {
        // The side is borrowed in place, not moved out and back: it is kilobytes (the INS's
        // covariance), and a move copies all of it (≈ 11 000 instructions a sample).
        let stopped = ImuStep {
            motors: [Command::Stopped; 4],
            reprobe: false,
        };
        let Some(armed) = self.loop_side.as_ref().map(LoopSide::armed) else {
            return stopped;
        };
        let inputs = self.loop_inputs();
        let install = inputs.setup_pending && !armed;
        let pending = if install {
            self.take_pending_setup()
        } else {
            None
        };
        let Some(side) = self.loop_side.as_mut() else {
            return stopped;
        };
        if let Some((setup, controllers)) = pending {
            side.install(&setup, controllers);
        }
        let (step, report) = run(side, &inputs);
        self.on_loop_report(now_ms, &report);
        step
    }

    /// A sample from the IMU at `now_ms`, on the app's own loop side ([`LoopSide::step`]
    /// with the exchange around it).
    pub fn on_imu_sample(&mut self, now_ms: u32, sample: &ImuSample) -> ImuStep {
        self.run_loop(now_ms, |side, inputs| side.step(now_ms, sample, inputs))
    }

    /// No usable sample, on the app's own loop side ([`LoopSide::missing`]).
    pub fn on_imu_missing(&mut self, now_ms: u32, cause: ImuFault) -> ImuStep {
        self.run_loop(now_ms, |side, inputs| side.missing(now_ms, cause, inputs))
    }

    /// The loop side, for the firmware's IMU task to run apart from the rest (`None` once
    /// taken): from then on it trades [`FlightApp::loop_inputs`] and
    /// [`FlightApp::on_loop_report`] with the app.
    pub fn take_loop_side(&mut self) -> Option<LoopSide> {
        self.loop_side.take()
    }

    /// The app's own loop side, while it has one.
    pub fn loop_side(&self) -> Option<&LoopSide> {
        self.loop_side.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::tests::resting;
    use crate::pipeline::LinkInput;
    use crate::settings::Settings;
    use crate::supervisor::Decision;
    use crate::supervisor::Sticks;

    fn app() -> FlightApp {
        FlightApp::new(Settings::default(), 0).unwrap()
    }

    #[test]
    fn a_mailbox_loses_no_one_shot_measurement() {
        let mut app = app();
        let mut mailbox = app.loop_inputs();
        app.on_baro(20, Some(101.0));
        app.loop_inputs_into(&mut mailbox);
        assert_eq!(mailbox.baro_m, Some(101.0));
        // A later reading waits in the app while the mailbox still holds one.
        app.on_baro(40, Some(102.0));
        app.loop_inputs_into(&mut mailbox);
        assert_eq!(mailbox.take().baro_m, Some(101.0));
        assert_eq!(mailbox.baro_m, None, "taken");
        app.loop_inputs_into(&mut mailbox);
        assert_eq!(mailbox.take().baro_m, Some(102.0));
    }

    #[test]
    fn split_or_together_the_loop_flies_the_same() {
        // The app running its own loop side, and the two sides apart trading the mailbox and
        // the reports as the firmware does, fed the same: the same motors, bit for bit.
        let mut together = app();
        let mut apart = app();
        let mut side = apart.take_loop_side().unwrap();
        let mut mailbox = apart.loop_inputs();
        let arm = LinkInput {
            up: true,
            sticks: Sticks {
                yaw: 1.0,
                ..Sticks::default()
            },
            arm_switch: None,
            mode_channel: -1.0,
        };
        for t in 0..3_000u32 {
            let link = if t < 1_500 {
                arm
            } else {
                LinkInput {
                    sticks: Sticks {
                        throttle: 0.5,
                        ..Sticks::default()
                    },
                    ..arm
                }
            };
            together.link_input = link;
            apart.link_input = link;
            if t % 20 == 0 {
                together.on_baro(t, Some(100.0));
                apart.on_baro(t, Some(100.0));
            }
            let a = together.on_imu_sample(t, &resting(t));
            apart.loop_inputs_into(&mut mailbox);
            let (b, report) = side.step(t, &resting(t), &mailbox.take());
            apart.on_loop_report(t, &report);
            assert_eq!(a, b, "{t}");
        }
        assert!(together.armed() && apart.armed());
        assert_eq!(together.arming_blockers(), apart.arming_blockers());
    }

    #[test]
    fn merged_reports_keep_every_decision() {
        let mut app = app();
        let mut side = app.take_loop_side().unwrap();
        let inputs = app.loop_inputs();
        let (_, mut pending) = side.step(0, &resting(0), &inputs);
        let first = pending.out.unwrap();
        // A refused arm (the sticks are a gesture, the link says down) makes news; merged
        // with later steadier reports it stays.
        let mut refused = first;
        refused.decision = Decision::ArmRefused(crate::supervisor::ArmBlocker::LinkDown);
        let mut news = LoopNews::new();
        news.push_back(refused).unwrap();
        pending.merge(LoopReport {
            news,
            ..pending.clone()
        });
        for t in 1..10 {
            let (_, later) = side.step(t, &resting(t), &inputs);
            pending.merge(later);
        }
        assert_eq!(pending.news.len(), 1);
        app.on_loop_report(10, &pending);
        assert_ne!(app.arming_blockers(), 0);
    }

    #[test]
    fn missed_edges_and_overruns_are_counted() {
        let mut side = app().take_loop_side().unwrap();
        // 1 kHz: edges 1 ms apart, steps of 140 µs.
        side.timing(1_000, 1_140);
        side.timing(2_000, 2_140);
        assert_eq!(side.health(), LoopHealth::default());
        // Two edges came and went while the loop could not run.
        side.timing(5_000, 5_140);
        assert_eq!(side.health().missed, 2);
        // A step that ran past the next edge.
        side.timing(6_000, 7_200);
        assert_eq!(side.health().overruns, 1);
        // A stall reported by the adapter is a missed sample too.
        let inputs = LoopInputs::default();
        let (_, report) = side.missing(8, ImuFault::Stalled, &inputs);
        assert_eq!(report.health.missed, 3);
    }
}
