//! The link task's embassy plumbing: the board as `module_core::link_task::LinkPorts` (the
//! core behind its lock, the radio task's check-in, the action signals). The clock and the
//! driver adapters are radio-rfm22b's `EmbassyClock` (embassy-time in µs: the same clock the
//! JR-line task stamps CRSF frames with), `LinkRadio` and `DualRadio`; the task body is
//! `module_core::link_task::run_link_step`.

use module_core::air::AirLink;
use module_core::app::{Action, App};
use module_core::handset::Handset;
use module_core::link_task::LinkPorts;

use crate::firmware::shared::{carry_out, now_ms, with_app};
use crate::firmware::tasks::supervisor::{Watched, check_in};

pub use radio_rfm22b::link::EmbassyClock;

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
