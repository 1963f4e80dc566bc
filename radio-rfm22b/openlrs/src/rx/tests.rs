//! Unit tests of the receiver state machine (timings from the default 3.8 bind data: 25 ms
//! interval, 6 hops, telemetry on).

use super::*;
use heapless::Vec;

use crate::{BindingVersion, RfmType};

fn bound() -> BindData {
    BindData::defaults(BindingVersion::V38, RfmType::Mhz433)
}

fn rc_packet(header: u8) -> Vec<u8, 11> {
    let mut p = Vec::new();
    p.extend_from_slice(&[header, 0, 1, 2, 3, 0, 4, 5, 6, 7, 0])
        .unwrap();
    p
}

#[test]
fn stored_bind_data_gets_a_500_ms_bind_window_then_the_link() {
    let mut rx = Receiver::new(
        Config::new(BindingVersion::V38, RfmType::Mhz433),
        Some(bound()),
    );
    assert_eq!(rx.start(1_000), Command::ListenBind);
    assert_eq!(rx.next_deadline_us(), Some(501_000));
    assert_eq!(rx.poll(500_999).command, None);
    assert_eq!(rx.poll(501_000).command, Some(Command::StartLink(bound())));
    assert!(rx.is_linked());
    // Not acquired yet: slow hopping, one hop per interval · hopcount = 25 ms · 6.
    assert_eq!(rx.next_deadline_us(), Some(501_000 + 150_000 + 1));
    assert_eq!(rx.poll(651_001).command, Some(Command::Hop(1)));
}

#[test]
fn other_generation_or_invalid_stored_data_means_binding_forever() {
    let mut other = bound();
    other.version = 0x39;
    let mut rx = Receiver::new(
        Config::new(BindingVersion::V38, RfmType::Mhz433),
        Some(other),
    );
    assert_eq!(rx.start(0), Command::ListenBind);
    assert_eq!(rx.next_deadline_us(), None);
    assert_eq!(rx.poll(10_000_000).command, None);
}

#[test]
fn save_failsafe_is_reported_once_per_press_and_lost_packets_hop_on_the_grid() {
    let config = Config {
        bind_window_us: None,
        ..Config::new(BindingVersion::V38, RfmType::Mhz433)
    };
    let mut rx = Receiver::new(config, Some(bound()));
    assert_eq!(rx.start(0), Command::StartLink(bound()));
    let saves: [bool; 4] = core::array::from_fn(|k| {
        let header = if k < 3 { 0x01 } else { 0x00 };
        let r = rx.on_packet(25_000 * k as u64, &rc_packet(header));
        assert!(
            r.reply.is_some(),
            "telemetry is on in the default bind data"
        );
        matches!(
            r.output,
            Output::Channels {
                save_failsafe: true,
                ..
            }
        )
    });
    assert_eq!(saves, [true, false, false, false]);
    assert_eq!(rx.hop_index(), 4);
    // Last packet at 75 ms: RSSI is read 23.5 ms later, while the next one should be on
    // air; it is missed 26 ms later and the hop follows the grid.
    assert_eq!(rx.next_deadline_us(), Some(75_000 + 23_500 + 1));
    let tick = rx.poll(98_501);
    assert_eq!((tick.sample_rssi, tick.command), (true, None));
    assert_eq!(rx.next_deadline_us(), Some(75_000 + 26_000 + 1));
    assert_eq!(rx.poll(101_001).command, Some(Command::Hop(5)));
    assert_eq!(rx.next_deadline_us(), Some(100_000 + 23_500 + 1));
    assert!(rx.poll(123_501).sample_rssi);
    assert_eq!(rx.next_deadline_us(), Some(100_000 + 26_000 + 1));
    // Four heard, one missed.
    assert_eq!(rx.link_quality(), 4);
}
