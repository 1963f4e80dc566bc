//! Shared fixture of the link-loop tests: a module and a flight node 100 m apart on a fresh
//! mock medium, in virtual time, with the link parameters of a rate mode.
#![allow(dead_code)] // each test binary uses its own part

use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, LinkParams, RateMode};
use telemetry::mock::{ChannelModel, Executor, Medium, Node, VirtualTime};

/// Two link ends on one medium, not yet spawned.
pub struct Pair {
    /// The shared virtual time.
    pub time: VirtualTime,
    /// The medium both nodes are on.
    pub medium: Medium,
    /// The module's (master's) node, at 0 m.
    pub module_node: usize,
    /// The flight side's (follower's) node, at 100 m.
    pub flight_node: usize,
    /// The link: Compact8 at L50 (its only format), Full16 otherwise; telemetry 1:4.
    pub params: LinkParams,
    /// The executor to spawn the ends on.
    pub executor: Executor<'static>,
}

/// A fresh pair at `rate`, the medium seeded with `seed`.
pub fn pair(rate: RateMode, seed: u64) -> Pair {
    let format = if rate == RateMode::L50 {
        ChannelFormat::Compact8
    } else {
        ChannelFormat::Full16
    };
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), seed);
    let module_node = medium.add_node(Node::default());
    let flight_node = medium.add_node(Node {
        position_m: 100.0,
        ..Node::default()
    });
    Pair {
        executor: Executor::new(time.clone()),
        time,
        medium,
        module_node,
        flight_node,
        params: LinkParams::new(0x5EED_1234, Band::Mhz433, rate, format, 4),
    }
}
