//! Air frames (`telemetry::frame::decode`) and the bind helpers, with the link CRC re-sealed
//! so every frame kind is reached — the key-agreement bind frames (version 2: offers with
//! and without a salt, accepts with a share and tag, confirmations) among them.
//! Invariants: a sealed frame is never refused for its CRC; every accepted frame re-encodes
//! to exactly the bytes received; the bind helpers agree with the decoder: an offer's link
//! parameters re-make the offer, a plain accept is recognised for its bind ID and an accept
//! carrying a share never counts as a plain one.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::{Input, seal};
use telemetry::frame::{Frame, Received, Rejection, decode, encode};
use telemetry::link::BIND_KEY;
use telemetry::link::bind::{LinkParams, is_accept_of, offered};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let key = if input.bool() { BIND_KEY } else { input.u32() };
    let body = input.rest();

    // Raw bytes: whatever they are, decoding never panics and accepted frames round-trip.
    check(body, key);

    let frame = seal(body, key);
    if let Received::Rejected(Rejection::Crc) = decode(&frame, key) {
        panic!("a sealed frame failed its CRC");
    }
    check(&frame, key);

    if key == BIND_KEY {
        let offer = offered(&frame);
        match decode(&frame, BIND_KEY) {
            Received::Accepted(Frame::BindOffer(o)) => {
                assert_eq!(offer, Some(o));
                assert_eq!(LinkParams::from_offer(&o).offer(o.exchange), o);
            }
            _ => assert_eq!(offer, None),
        }
        if let Received::Accepted(Frame::BindAccept { bind_id, exchange }) =
            decode(&frame, BIND_KEY)
        {
            let params = LinkParams::new(
                bind_id,
                telemetry::link::Band::Mhz433,
                telemetry::link::RateMode::L50,
                telemetry::channels::ChannelFormat::Full16,
                4,
            );
            // `new` remaps 0 and the bind key itself; every other ID is taken as is.
            assert_eq!(
                is_accept_of(&frame, &params),
                params.bind_id == bind_id && exchange.is_none()
            );
        }
    }
});

fn check(packet: &[u8], key: u32) {
    if let Received::Accepted(frame) = decode(packet, key) {
        let mut out = vec![0u8; packet.len() + 8];
        let n = encode(&frame, key, &mut out).expect("an accepted frame re-encodes");
        assert_eq!(&out[..n], packet, "re-encoding changed the frame");
    }
}
