//! Dynamic power's radio side: the loop writes the power step the application handed the
//! state machine (`Master::set_tx_power`) into the radio once per change, between slots —
//! after the slot's packet has left, before the next slot starts — and never again while
//! the step stays.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;

use telemetry::channels::ChannelFormat;
use telemetry::link::core::Master;
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::link::{Band, LinkParams, LinkRx, PacketRadio, RadioConfig, RateMode};
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

/// (time, step) of every power write.
type Writes = Rc<RefCell<Vec<(u64, u8)>>>;

/// The mock radio, recording power writes.
struct Recording(MockRadio, Writes, VirtualTime);

impl PacketRadio for Recording {
    type Error = std::convert::Infallible;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        self.0.configure(config).await
    }
    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error> {
        self.0.set_channel(channel).await
    }
    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        self.0.transmit(frame).await
    }
    async fn begin_transmit(&mut self, len: usize) -> Result<(), Self::Error> {
        self.0.begin_transmit(len).await
    }
    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        self.0.finish_transmit(frame).await
    }
    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, Self::Error> {
        self.0.receive(buf, timeout_us).await
    }
    async fn set_tx_power(&mut self, step: u8) -> Result<(), Self::Error> {
        self.1.borrow_mut().push((self.2.now_us(), step));
        Ok(())
    }
}

/// Asks for step 3 from slot 10 and step 5 from slot 20 (slots start every 4 ms at F250).
struct Hooks;

impl MasterHooks for Hooks {
    fn on_slot(&mut self, _now_us: u64, master: &mut Master) {
        match master.slot() {
            10..20 => master.set_tx_power(3),
            20.. => master.set_tx_power(5),
            _ => {}
        }
    }
}

#[test]
fn the_master_loop_writes_each_new_step_once_between_slots() {
    let params = LinkParams::new(
        0x090E_75E7,
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), 3);
    let node = medium.add_node(Node::default());
    let executor = Executor::new(time.clone());
    let writes: Writes = Rc::default();
    let mut radio = Recording(MockRadio::new(medium, node), writes.clone(), time.clone());
    let mut clock = SimClock::new(time, 0, 0.0);
    executor.spawn(async move {
        let mut master = Master::new(params);
        let _ = run_master(&mut radio, &mut clock, &mut master, &mut Hooks).await;
    });
    executor.run_until_us(200_000);
    drop(executor);
    let writes = writes.borrow().clone();
    assert_eq!(writes.len(), 2, "{writes:?}");
    let slot_us = u64::from(RateMode::F250.slot_us());
    // Slot 10 is an uplink: its frame went out at the old power; the write follows it,
    // inside slot 10, before slot 11 starts.
    for (&(at, step), (slot, want)) in writes.iter().zip([(10, 3), (20, 5)]) {
        assert_eq!(step, want);
        assert!(
            (slot * slot_us..(slot + 1) * slot_us).contains(&at),
            "step {step} written at {at} µs"
        );
    }
}
