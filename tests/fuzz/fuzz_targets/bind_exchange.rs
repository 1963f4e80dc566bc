//! The bind's key agreement (`telemetry::link::bind`: `Offering`, `Answering`,
//! `offer_needs`) and the phrase rule (`check_phrase`): a true exchange between a master and
//! a follower on one phrase derivation (or none), whose accept and confirmation the input
//! flips bytes in, and fuzzed bind packets into both sides.
//!
//! Invariants: a master binds only on the accept a follower with its derivation made — a
//! flipped or foreign one is a mismatch or ignored, never bound — and then hands over
//! exactly its key; a follower takes the key only from that master's confirmation, and it is
//! the master's key; a fuzzed packet never binds either side; a follower whose derivation
//! differs is refused at the confirmation; `offer_needs` refuses a plain offer unless plain
//! links are allowed, and asks for a phrase exactly when the offer has a salt; a phrase
//! `check_phrase` accepts is trimmed, 12 to 64 bytes' worth of at least 6 different
//! printable characters.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::{Input, seal};
use telemetry::frame::{Frame, encode};
use telemetry::link::bind::{Accepted, Answering, OfferNeeds, Offering, offer_needs, offered};
use telemetry::link::phrase::{PHRASE_MAX_BYTES, PHRASE_MIN_CHARS};
use telemetry::link::{
    BIND_KEY, Band, BindAuth, FollowerAuth, LinkKey, LinkParams, PhraseSecret, RateMode,
    check_phrase,
};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let text = String::from_utf8_lossy(input.chunk(80)).into_owned();
    if let Ok(Some(phrase)) = check_phrase(&text) {
        assert_eq!(phrase, phrase.trim());
        assert!(phrase.len() <= PHRASE_MAX_BYTES);
        assert!(phrase.chars().count() >= PHRASE_MIN_CHARS);
        assert!(!phrase.chars().any(char::is_control));
    }

    let params = LinkParams::new(
        input.u32(),
        Band::from_code(input.u8() % 3).unwrap_or(Band::Mhz433),
        RateMode::from_code(input.u8() % 5).unwrap_or(RateMode::F250),
        telemetry::channels::ChannelFormat::Full16,
        4,
    );
    let secret = PhraseSecret {
        salt: [input.u8(); 8],
        prs: [input.u8(); 32],
    };
    let auth = match input.u8() % 3 {
        0 => BindAuth::Plain,
        1 => BindAuth::Anonymous,
        _ => BindAuth::Phrase(secret),
    };
    let key = LinkKey::from_bytes([input.u8(); 16]);
    let master = Offering::new(&params, &auth, &[input.u8(); 32]);
    let offer = master.offer();
    let mut buf = [0u8; 80];
    let n = encode(&Frame::BindOffer(offer), BIND_KEY, &mut buf).expect("an offer encodes");
    assert_eq!(offered(&buf[..n]), Some(offer));

    let allow_plain = input.bool();
    let has_phrase = input.bool();
    let follower_auth = FollowerAuth {
        phrase: None,
        stored: has_phrase.then_some(secret),
        allow_plain,
    };
    match offer_needs(&offer, &follower_auth) {
        OfferNeeds::Plain => assert!(offer.exchange.is_none() && allow_plain),
        OfferNeeds::Anonymous => {
            assert!(offer.exchange.is_some_and(|x| x.salt.is_none()) && !has_phrase)
        }
        OfferNeeds::Phrase { salt, stored } => {
            assert_eq!(offer.exchange.and_then(|x| x.salt), Some(salt));
            assert_eq!(stored, Some(secret));
        }
        OfferNeeds::Refused(_) => {}
    }

    // Fuzzed packets into the master: never bound.
    let packet = seal(input.chunk(70), BIND_KEY);
    assert!(
        !matches!(
            master.on_accept(&packet, &key),
            Some(Accepted::Bound { .. })
        ) || offer.exchange.is_none()
    );

    let Some(exchange) = offer.exchange else {
        return;
    };
    // The follower's derivation: the master's, or another.
    let prs: Vec<u8> = match (exchange.salt, input.u8() < 32) {
        (None, _) => Vec::new(),
        (Some(_), false) => secret.prs.to_vec(),
        (Some(_), true) => vec![input.u8(); 32],
    };
    let same = prs.as_slice() == secret.prs.as_slice() || exchange.salt.is_none();
    let Some(follower) = Answering::new(&offer, &prs, &[input.u8() | 1; 32]) else {
        panic!("a follower refused a true offer");
    };
    assert!(follower.is_repeat(&buf[..n]));
    assert_eq!(follower.on_confirm(&packet).flatten(), None);
    let mut accept = [0u8; 80];
    let m = encode(&follower.accept(), BIND_KEY, &mut accept).expect("an accept encodes");
    let flipped = input.u8() < 64 && {
        let at = usize::from(input.u8()) % (m - 2);
        accept[at] ^= input.u8().max(1);
        true
    };
    // The link CRC is made again: the flip reaches the key agreement.
    let accept = seal(&accept[..m - 2], BIND_KEY);
    let Some(Accepted::Bound {
        key: Some(handed),
        confirm: Some(confirm),
    }) = master.on_accept(&accept, &key)
    else {
        assert!(flipped || !same, "a true accept was not bound");
        return;
    };
    assert!(
        same && !flipped,
        "bound on an accept without the derivation"
    );
    assert_eq!(handed, key);
    let mut frame = [0u8; 80];
    let k = encode(&confirm, BIND_KEY, &mut frame).expect("a confirmation encodes");
    let forged = input.u8() < 64 && {
        let at = usize::from(input.u8()) % (k - 2);
        frame[at] ^= input.u8().max(1);
        true
    };
    let frame = seal(&frame[..k - 2], BIND_KEY);
    match follower.on_confirm(&frame) {
        Some(Some(got)) => {
            assert!(!forged, "a forged confirmation taken");
            assert_eq!(got, key);
        }
        Some(None) | None => assert!(forged, "a true confirmation refused"),
    }
});
