//! The simulators' one board clock ([`sim_exec::SimClock`]: an epoch offset and a crystal's
//! drift over virtual time) as the link's [`LinkClock`], for both rungs: the packet-level
//! mock here and the chip-level world of `si4432-sim`.

use crate::link::LinkClock;
use sim_exec::SimClock;

impl LinkClock for SimClock {
    fn now_us(&self) -> u64 {
        SimClock::now_us(self)
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        SimClock::sleep_until_us(self, deadline_us).await;
    }
}
