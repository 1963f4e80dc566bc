//! The master asks its application for channels once each uplink's transmitter is on and its
//! PLL settled (`uplink_latch_offset_us` into the slot), not at the slot start: every uplink
//! carries the freshest handset input the slot allows (issue 17). Downlink slots are still
//! announced at their start.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;

use telemetry::channels::ChannelFormat;
use telemetry::link::core::Master;
use telemetry::link::master::{MasterHooks, run_master, uplink_latch_offset_us};
use telemetry::link::{Band, LinkParams, RateMode, SlotKind};
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

/// (slot start, time of the call, kind of the slot) of every hook call.
type Calls = Rc<RefCell<Vec<(u64, u64, SlotKind)>>>;

struct Hooks(Calls, VirtualTime);

impl MasterHooks for Hooks {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let kind = master.schedule().kind(master.slot());
        self.0.borrow_mut().push((now_us, self.1.now_us(), kind));
    }
}

fn calls(rate: RateMode) -> Vec<(u64, u64, SlotKind)> {
    let params = LinkParams::new(0x1A7C_4ED5, Band::Mhz433, rate, ChannelFormat::Full16, 4);
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), 3);
    let node = medium.add_node(Node::default());
    let executor = Executor::new(time.clone());
    let log: Calls = Rc::default();
    let mut hooks = Hooks(log.clone(), time.clone());
    let mut radio = MockRadio::new(medium, node);
    let mut clock = SimClock::new(time, 0, 0.0);
    executor.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
    });
    executor.run_until_us(200_000);
    drop(executor);
    Rc::try_unwrap(log).ok().unwrap().into_inner()
}

#[test]
fn channels_are_latched_right_before_each_uplink() {
    for rate in RateMode::ALL {
        let calls = calls(rate);
        assert!(calls.len() > 8, "{rate:?}");
        let latch = u64::from(uplink_latch_offset_us(rate));
        for &(slot_start, at, kind) in &calls {
            let expected = match kind {
                SlotKind::Uplink => slot_start + latch,
                SlotKind::Downlink => slot_start,
            };
            assert_eq!(at, expected, "{rate:?} {kind:?}");
        }
    }
    // F500: 400 µs after the slot start (100 lead, 100 SPI set-up, 200 PLL) where it was
    // 70 µs, before the set-up; F700 310 µs where it was at the slot start.
    let f500 = calls(RateMode::F500);
    let (start, at, _) = f500[0];
    assert_eq!(at - start, 400);
    let f700 = calls(RateMode::F700);
    let (start, at, _) = f700[0];
    assert_eq!(at - start, 310);
}
