//! The OpenLRSng receiver role (`openlrs::rx::Receiver`): stored bind data and
//! settings from the fuzz bytes, then packets (bind and link, as the radio hands them over
//! after its header and CRC checks), timer polls, RSSI samples and serial input.
//!
//! Invariants: the RX only ever starts a link with bind data valid for its band; every hop
//! it commands is in the hop list; channel outputs have the mode's count and are 10-bit;
//! replies are the 1-byte bind ack or a 9-byte downlink frame that the TX parses; serial
//! output is 1..=8 bytes; link quality stays 0..=15.
#![no_main]

use libfuzzer_sys::fuzz_target;
use openlrs::RfmType;
use openlrs::bind::{BIND_ACK, BIND_DATA_LEN, BindData};
use openlrs::rx::{Command, Config, Output, Receiver};
use openlrs::telemetry::{self, DOWNLINK_FRAME_LEN, Downlink};
use taulink_fuzz::Input;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let (version, band) = taulink_fuzz::openlrs_link(&mut input);
    let config = Config {
        version,
        band,
        failsafe_delay: input.u8(),
        bind_window_us: input.bool().then(|| input.u32() % 2_000_000),
    };
    let stored = if input.bool() {
        let mut bytes = [0u8; BIND_DATA_LEN];
        for (d, s) in bytes.iter_mut().zip(input.bytes(BIND_DATA_LEN)) {
            *d = *s;
        }
        Some(BindData::from_bytes(&bytes))
    } else {
        Some(taulink_fuzz::openlrs_bind(&mut input, version, band))
    };
    let mut rx = Receiver::new(config, stored);
    let mut now = u64::from(input.u16());
    check_command(&rx, Some(rx.clone().start(now)), band);
    rx.start(now);
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()) * 4);
        match input.u8() % 5 {
            0 | 1 => {
                let packet = input.chunk(48);
                let reception = rx.on_packet(now, packet);
                check_command(&rx, reception.command, band);
                if let Some(reply) = &reception.reply {
                    match reply.len() {
                        1 => assert_eq!(reply[0], BIND_ACK),
                        DOWNLINK_FRAME_LEN => assert!(!matches!(
                            telemetry::parse(reply),
                            Downlink::WrongLength { .. } | Downlink::Unknown { .. }
                        )),
                        n => panic!("reply of {n} bytes"),
                    }
                }
                match reception.output {
                    Output::Channels { channels_bits, .. } => {
                        let data = rx.bind_data().expect("channels only on a link");
                        assert_eq!(channels_bits.len(), data.channel_mode().channel_count());
                        assert!(channels_bits.iter().all(|&c| c < 1024));
                    }
                    Output::Serial(bytes) => assert!((1..=8).contains(&bytes.len())),
                    Output::Bound(data) => assert_eq!(data.validate_for(band), Ok(())),
                    _ => {}
                }
            }
            2 => {
                let tick = rx.poll(now);
                check_command(&rx, tick.command, band);
            }
            3 => rx.on_rssi_sample(input.u8()),
            _ => {
                rx.queue_serial(input.chunk(40));
            }
        }
        assert!(rx.link_quality() <= 15);
    }
});

fn check_command(rx: &Receiver, command: Option<Command>, band: RfmType) {
    match command {
        Some(Command::StartLink(data)) => assert_eq!(data.validate_for(band), Ok(())),
        Some(Command::Hop(index)) => {
            let hops = rx.bind_data().map_or(1, BindData::hop_count);
            assert!(usize::from(index) < hops.max(1), "hop {index} of {hops}");
        }
        Some(Command::ListenBind) | None => {}
    }
    if rx.is_linked() {
        assert!(rx.bind_data().is_some_and(|d| d.validate_for(band).is_ok()));
    }
}
