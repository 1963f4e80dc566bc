//! The link task's embassy plumbing: embassy-time as the link's `LinkClock`, and the board
//! as `module_core::link_task::LinkPorts` (the core behind its lock, the radio task's
//! check-in, the action signals). The driver adapters are radio-rfm22b's `LinkRadio` and
//! `DualRadio`; the task body is `module_core::link_task::run_link_step`.

use embassy_time::{Instant, Timer};
use module_core::air::AirLink;
use module_core::app::{Action, App};
use module_core::handset::Handset;
use module_core::link_task::LinkPorts;
use telemetry::link::LinkClock;

use crate::firmware::shared::{carry_out, now_ms, with_app};
use crate::firmware::tasks::supervisor::{Watched, check_in};

/// embassy-time in µs: the same clock the JR-line task stamps CRSF frames with, so the
/// link's slot times are directly the CRSF timing frame's phase.
#[derive(Clone, Copy)]
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}

/// The board as the link task's body sees it.
pub struct Ports;

impl LinkPorts for Ports {
    type Handset = Handset;

    fn with_app<R>(&self, f: impl FnOnce(&mut App<AirLink, Handset>) -> R) -> Option<R> {
        with_app(f)
    }

    fn check_in(&self) {
        check_in(Watched::Radio);
    }

    fn now_ms(&self) -> u32 {
        now_ms()
    }

    fn carry_out(&self, action: Action) {
        carry_out(Some(action));
    }
}
