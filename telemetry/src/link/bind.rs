//! Binding: the parameters both ends store, the identity bytes derived from the bind ID, and
//! the pure halves of the over-the-air bind exchange on the fixed bind channel and rate.

use super::auth::{KEY_BYTES, LinkKey};
use super::hopping::{Band, mix32};
use super::pake::{Exchange, Role, SessionKey, tags_equal};
use super::phrase::PhraseSecret;
use super::radio::RadioConfig;
use super::rate::{BIND_RATE, RateMode};
use super::schedule::Schedule;
use crate::channels::ChannelFormat;
use crate::frame::{
    AcceptExchange, BIND_TAG_BYTES, BindOffer, Frame, OfferExchange, Received, SESSION_BYTES,
    SHARE_BYTES, decode,
};

/// CRC key of bind frames (fixed: both ends must read them before sharing anything).
pub const BIND_KEY: u32 = 0x7A17_B1ED;
/// Hardware header of bind frames ("TLB" + bind version 2, the key agreement).
pub const BIND_HEADER: [u8; 4] = *b"TLB\x02";

/// Everything a bound link is: stored by both ends after a bind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkParams {
    /// 32-bit link identity.
    pub bind_id: u32,
    /// Band.
    pub band: Band,
    /// Rate mode.
    pub rate: RateMode,
    /// Uplink channel format.
    pub format: ChannelFormat,
    /// One slot in this many is a downlink slot.
    pub telemetry_ratio: u8,
}

impl LinkParams {
    /// A new link with a bind ID from `random` (an injected random 32-bit value; the module
    /// draws it from its hardware RNG). 0 and the bind key are avoided. A `format` whose
    /// uplink does not fit the mode's frame is replaced by the stick format
    /// ([`format_for`]: 16 channels at F700 travel as [`ChannelFormat::Sticks16`]).
    pub fn new(
        random: u32,
        band: Band,
        rate: RateMode,
        format: ChannelFormat,
        telemetry_ratio: u8,
    ) -> Self {
        let bind_id = match random {
            0 | BIND_KEY => mix32(random) | 1,
            id => id,
        };
        Self {
            bind_id,
            band,
            rate,
            format: format_for(rate, format),
            telemetry_ratio,
        }
    }

    /// The four hardware header bytes: a mix of the bind ID, so links whose IDs differ in
    /// any bit almost surely differ here (a 2^-32 chance to collide), and never the bind
    /// header.
    pub fn header(&self) -> [u8; 4] {
        let h = mix32(self.bind_id ^ 0x4EAD_E125).to_be_bytes();
        if h == BIND_HEADER {
            [h[0] ^ 0xFF, h[1], h[2], h[3]]
        } else {
            h
        }
    }

    /// The slot schedule of the bound link: its rate's slots, its telemetry ratio.
    pub fn schedule(&self) -> Schedule {
        Schedule {
            rate: self.rate,
            telemetry_ratio: self.telemetry_ratio,
        }
    }

    /// The radio configuration of the bound link: its rate, its header, its band's grid.
    pub fn radio_config(&self) -> RadioConfig {
        RadioConfig {
            rate: self.rate,
            header: self.header(),
            base_hz: self.band.grid(self.rate).0,
            spacing_hz: self.band.grid(self.rate).1,
            reduced_power: false,
        }
    }

    /// The bind offer carrying these parameters and `exchange`.
    pub fn offer(&self, exchange: Option<OfferExchange>) -> BindOffer {
        BindOffer {
            bind_id: self.bind_id,
            band: self.band,
            rate: self.rate,
            format: self.format,
            telemetry_ratio: self.telemetry_ratio,
            exchange,
        }
    }

    /// The link of radio model `model_id` (model match, spec §12.6): the same band, rate,
    /// format and ratio under an identity mixed from the bind ID and the model ID, so a
    /// receiver bound under one model never hears (the chip's header check drops its
    /// frames) nor is heard by the module flying another. The mix is keyed like
    /// [`LinkParams::header`], never 0 or the bind key; a keyed link's key follows the
    /// mixed bind ID (`LinkKey::for_link` of the module key).
    pub fn for_model(&self, model_id: u8) -> Self {
        let mixed = mix32(self.bind_id ^ mix32(0x6D0D_E100 ^ u32::from(model_id)));
        Self {
            bind_id: match mixed {
                0 | BIND_KEY => mix32(mixed) | 1,
                id => id,
            },
            ..*self
        }
    }

    /// Parameters from a received offer.
    pub fn from_offer(offer: &BindOffer) -> Self {
        Self {
            bind_id: offer.bind_id,
            band: offer.band,
            rate: offer.rate,
            format: offer.format,
            telemetry_ratio: offer.telemetry_ratio,
        }
    }
}

/// The channel format a link at `rate` carries when `format` is asked for: `format` itself
/// if an uplink of it with a link report fits the mode's largest frame, else
/// [`ChannelFormat::Sticks16`] (F700's 21-byte frame has no room for 22 bytes of channels;
/// every other mode keeps what it is asked for).
pub const fn format_for(rate: RateMode, format: ChannelFormat) -> ChannelFormat {
    if crate::frame::uplink_overhead(format, true) <= rate.max_frame_bytes() {
        format
    } else {
        ChannelFormat::Sticks16
    }
}

/// Bind-mode timing: the master offers every `OFFER_PERIOD_US` and listens in between.
pub const OFFER_PERIOD_US: u32 = 4 * RateMode::L50.slot_us();
/// The follower answers an offer at most this many times (one lost accept must not leave
/// the master offering), and the master sends its confirmation this many times.
pub const ACCEPT_REPEATS: u8 = 3;
/// How long a follower that answered waits for the master's confirmation (or for a repeated
/// offer that says its accept was lost): long enough for the master's share arithmetic on a
/// 64 MHz Cortex-M4.
pub const CONFIRM_WAIT_US: u64 = 1_000_000;

/// The radio configuration of bind mode in `band`: bind rate and header, channel 0 on the
/// bind frequency, at reduced power (both ends bind from close by).
pub fn bind_radio_config(band: Band) -> RadioConfig {
    RadioConfig {
        rate: BIND_RATE,
        header: BIND_HEADER,
        base_hz: band.bind_hz(),
        spacing_hz: band.grid(BIND_RATE).1,
        reduced_power: true,
    }
}

/// The CPace channel identifier of binds.
const BIND_CI: &[u8] = b"TauLink/2 bind";
const LABEL_ACCEPT: &[u8] = b"TauLink/2 accept";
const LABEL_CONFIRM: &[u8] = b"TauLink/2 confirm";
const LABEL_WRAP: &[u8] = b"TauLink/2 key wrap";

/// How a master agrees the link key at bind (spec §12.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindAuth {
    /// No key: an unauthenticated link (the explicit setting; the follower must allow it).
    Plain,
    /// CPace without a phrase: an authenticated link whose key anyone bound in the window
    /// from close by could have agreed.
    Anonymous,
    /// CPace on the binding phrase's derivation: only a follower with the phrase gets the
    /// key.
    Phrase(PhraseSecret),
}

/// What a follower brings to a bind window.
#[derive(Clone, Copy, Debug, Default)]
pub struct FollowerAuth<'a> {
    /// The binding phrase typed for this window (its derivation is run with the salt the
    /// module offers).
    pub phrase: Option<&'a str>,
    /// A derivation this end stored (a module in the receiver role), used when the offer's
    /// salt is its own.
    pub stored: Option<PhraseSecret>,
    /// Whether an unauthenticated link may be bound (the explicit setting).
    pub allow_plain: bool,
}

/// Why a follower did not bind to an offer it heard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BindRefusal {
    /// The module binds with a phrase and none was given here.
    PhraseWanted,
    /// A phrase was given here and the module has none.
    NoPhraseOffered,
    /// The module offers an unauthenticated link and this end does not allow it.
    PlainRefused,
    /// The key agreement did not confirm: the phrases differ (or another radio answered).
    NotConfirmed,
}

impl BindRefusal {
    /// What to tell the owner.
    pub fn describe(self) -> &'static str {
        match self {
            BindRefusal::PhraseWanted => "the module binds with a phrase: give it here too",
            BindRefusal::NoPhraseOffered => "the module has no phrase: bind without one",
            BindRefusal::PlainRefused => "the module offers an unauthenticated link",
            BindRefusal::NotConfirmed => "no confirmation: the phrases differ",
        }
    }
}

/// The CPace session of a bind: the bind ID and the offer's session nonce.
fn bind_sid(bind_id: u32, session: &[u8; SESSION_BYTES]) -> [u8; 4 + SESSION_BYTES] {
    let mut sid = [0u8; 4 + SESSION_BYTES];
    let (id, rest) = sid.split_at_mut(4);
    id.copy_from_slice(&bind_id.to_le_bytes());
    rest.copy_from_slice(session);
    sid
}

/// The offer's associated data in the CPace transcript: every offered parameter, so a
/// changed offer gives another key and fails the confirmation.
fn offer_ad(offer: &BindOffer) -> [u8; 17] {
    let mut ad = [0u8; 17];
    let (head, salt) = ad.split_at_mut(9);
    let [a, b, c, d] = offer.bind_id.to_le_bytes();
    let auth = offer
        .exchange
        .map_or(0, |x| if x.salt.is_some() { 2 } else { 1 });
    head.copy_from_slice(&[
        a,
        b,
        c,
        d,
        offer.band.code(),
        offer.rate.code(),
        offer.format.code(),
        offer.telemetry_ratio,
        auth,
    ]);
    if let Some(s) = offer.exchange.and_then(|x| x.salt) {
        salt.copy_from_slice(&s);
    }
    ad
}

/// The confirmation tag of the master, over the sealed key it carries.
fn confirm_tag(isk: &SessionKey, sealed: &[u8; KEY_BYTES]) -> [u8; BIND_TAG_BYTES] {
    let mut label = [0u8; LABEL_CONFIRM.len() + KEY_BYTES];
    let (l, k) = label.split_at_mut(LABEL_CONFIRM.len());
    l.copy_from_slice(LABEL_CONFIRM);
    k.copy_from_slice(sealed);
    isk.derive16(&label)
}

fn xor16(a: &[u8; 16], b: &[u8; 16]) -> [u8; 16] {
    core::array::from_fn(|i| a.get(i).copied().unwrap_or(0) ^ b.get(i).copied().unwrap_or(0))
}

/// The master's side of a bind: the offer (with its CPace share) and what it makes of an
/// accept.
#[derive(Debug)]
pub struct Offering {
    offer: BindOffer,
    exchange: Option<Exchange>,
}

/// What a master makes of an accept of its offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accepted {
    /// Bound: the link key to store and use (`None`: an unauthenticated link), and for a
    /// key agreement the confirmation to send (it carries `key`, sealed).
    Bound {
        /// The link's key.
        key: Option<LinkKey>,
        /// The frame that confirms it to the follower ([`Frame::BindConfirm`]).
        confirm: Option<Frame<'static>>,
    },
    /// The follower's confirmation is wrong: the phrases differ, or another radio guessed.
    /// The bind ends here: one guess per bind.
    Mismatch,
}

impl Offering {
    /// An offer of `params` agreeing `key` (the link's key to hand over, which the module
    /// chose; ignored for [`BindAuth::Plain`]) as `auth` says, the CPace scalar and session
    /// from `random` (32 bytes of a hardware RNG).
    pub fn new(params: &LinkParams, auth: &BindAuth, random: &[u8; 32]) -> Self {
        let (salt, prs): (Option<[u8; 8]>, &[u8]) = match auth {
            BindAuth::Plain => {
                return Self {
                    offer: params.offer(None),
                    exchange: None,
                };
            }
            BindAuth::Anonymous => (None, &[]),
            BindAuth::Phrase(secret) => (Some(secret.salt), &secret.prs),
        };
        let session = session_of(random);
        let sid = bind_sid(params.bind_id, &session);
        let exchange = Exchange::start(prs, BIND_CI, &sid, random);
        let offer = params.offer(Some(OfferExchange {
            salt,
            session,
            share: exchange.share(),
        }));
        Self {
            offer,
            exchange: Some(exchange),
        }
    }

    /// The offer to send.
    pub fn offer(&self) -> BindOffer {
        self.offer
    }

    /// `packet` if it is an accept of this offer: bound (handing over `key`, for a key
    /// agreement) or a mismatch. `None`: not an accept of this offer (another link's, or a
    /// plain accept of a key agreement), to be ignored.
    pub fn on_accept(&self, packet: &[u8], key: &LinkKey) -> Option<Accepted> {
        let Received::Accepted(Frame::BindAccept { bind_id, exchange }) = decode(packet, BIND_KEY)
        else {
            return None;
        };
        if bind_id != self.offer.bind_id {
            return None;
        }
        let (Some(own), Some(theirs), Some(offered)) =
            (&self.exchange, exchange, self.offer.exchange)
        else {
            return (self.exchange.is_none() && exchange.is_none()).then_some(Accepted::Bound {
                key: None,
                confirm: None,
            });
        };
        let sid = bind_sid(bind_id, &offered.session);
        let ad = offer_ad(&self.offer);
        let Some(isk) = own.finish(Role::Initiator, &theirs.share, &ad, &[], &sid) else {
            return Some(Accepted::Mismatch);
        };
        if !tags_equal(&isk.derive16(LABEL_ACCEPT), &theirs.tag) {
            return Some(Accepted::Mismatch);
        }
        let sealed = xor16(&key.to_bytes(), &isk.derive16(LABEL_WRAP));
        Some(Accepted::Bound {
            key: Some(*key),
            confirm: Some(Frame::BindConfirm {
                bind_id,
                tag: confirm_tag(&isk, &sealed),
                sealed,
            }),
        })
    }
}

/// The session nonce of an offer, one-way from the bind's random bytes (the scalar is
/// another hash of them).
fn session_of(random: &[u8; 32]) -> [u8; SESSION_BYTES] {
    let digest = super::sha512::sha512(&[b"TauLink/2 session", random]);
    core::array::from_fn(|i| digest.get(i).copied().unwrap_or(0))
}

/// What a follower brings to a key-agreement offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OfferNeeds {
    /// An unauthenticated link, allowed here: accept it as it is.
    Plain,
    /// A key agreement without a phrase.
    Anonymous,
    /// A key agreement on the phrase's derivation under this salt: run it from the phrase
    /// (slow), unless `stored` already is it.
    Phrase {
        /// The module's salt.
        salt: [u8; 8],
        /// This end's stored derivation under that salt.
        stored: Option<PhraseSecret>,
    },
    /// Not bindable with what this end has.
    Refused(BindRefusal),
}

/// What `offer` needs from a follower with `auth`.
pub fn offer_needs(offer: &BindOffer, auth: &FollowerAuth<'_>) -> OfferNeeds {
    let has_phrase = auth.phrase.is_some() || auth.stored.is_some();
    match offer.exchange {
        None if auth.allow_plain => OfferNeeds::Plain,
        None => OfferNeeds::Refused(BindRefusal::PlainRefused),
        Some(OfferExchange { salt: None, .. }) if has_phrase => {
            OfferNeeds::Refused(BindRefusal::NoPhraseOffered)
        }
        Some(OfferExchange { salt: None, .. }) => OfferNeeds::Anonymous,
        Some(OfferExchange {
            salt: Some(salt), ..
        }) => {
            let stored = auth.stored.filter(|s| s.salt == salt);
            if auth.phrase.is_none() && stored.is_none() {
                OfferNeeds::Refused(BindRefusal::PhraseWanted)
            } else {
                OfferNeeds::Phrase { salt, stored }
            }
        }
    }
}

/// The follower's side of a key agreement: the accept it sends, and what it makes of the
/// master's confirmation.
#[derive(Debug)]
pub struct Answering {
    offer: BindOffer,
    share: [u8; SHARE_BYTES],
    isk: SessionKey,
}

impl Answering {
    /// The answer to `offer` with `prs` (the phrase's derivation under the offer's salt, or
    /// empty), the scalar from `random`; `None` if the offer agrees no key or its share is
    /// not a valid element.
    pub fn new(offer: &BindOffer, prs: &[u8], random: &[u8; 32]) -> Option<Self> {
        let offered = offer.exchange?;
        let sid = bind_sid(offer.bind_id, &offered.session);
        let exchange = Exchange::start(prs, BIND_CI, &sid, random);
        let isk = exchange.finish(Role::Responder, &offered.share, &[], &offer_ad(offer), &sid)?;
        Some(Self {
            offer: *offer,
            share: exchange.share(),
            isk,
        })
    }

    /// The accept to send: the share and the confirmation of the key derived.
    pub fn accept(&self) -> Frame<'static> {
        Frame::BindAccept {
            bind_id: self.offer.bind_id,
            exchange: Some(AcceptExchange {
                share: self.share,
                tag: self.isk.derive16(LABEL_ACCEPT),
            }),
        }
    }

    /// Whether `packet` is this offer again (the master did not hear the accept).
    pub fn is_repeat(&self, packet: &[u8]) -> bool {
        matches!(decode(packet, BIND_KEY), Received::Accepted(Frame::BindOffer(o)) if o == self.offer)
    }

    /// `packet` if it is the master's confirmation of this bind: `Some(Some(key))` for the
    /// right one (the link's key, unsealed), `Some(None)` for a wrong one (the bind ends:
    /// one guess), `None` for anything else.
    pub fn on_confirm(&self, packet: &[u8]) -> Option<Option<LinkKey>> {
        let Received::Accepted(Frame::BindConfirm {
            bind_id,
            tag,
            sealed,
        }) = decode(packet, BIND_KEY)
        else {
            return None;
        };
        if bind_id != self.offer.bind_id {
            return None;
        }
        Some(
            tags_equal(&confirm_tag(&self.isk, &sealed), &tag)
                .then(|| LinkKey::from_bytes(xor16(&sealed, &self.isk.derive16(LABEL_WRAP)))),
        )
    }

    /// The link parameters offered.
    pub fn params(&self) -> LinkParams {
        LinkParams::from_offer(&self.offer)
    }
}

/// Master side, unauthenticated binds: is this packet the follower's plain accept of our
/// offer?
pub fn is_accept_of(packet: &[u8], params: &LinkParams) -> bool {
    matches!(decode(packet, BIND_KEY), Received::Accepted(Frame::BindAccept { bind_id, exchange: None }) if bind_id == params.bind_id)
}

/// Follower side: the offer in this packet, if it is a valid one.
pub fn offered(packet: &[u8]) -> Option<BindOffer> {
    match decode(packet, BIND_KEY) {
        Received::Accepted(Frame::BindOffer(offer)) => Some(offer),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_f700_swaps_a_format_that_does_not_fit() {
        for rate in [
            RateMode::L50,
            RateMode::M100,
            RateMode::F250,
            RateMode::F500,
        ] {
            for format in [ChannelFormat::Full16, ChannelFormat::Compact8] {
                assert_eq!(format_for(rate, format), format, "{rate:?}");
            }
        }
        assert_eq!(
            format_for(RateMode::F700, ChannelFormat::Full16),
            ChannelFormat::Sticks16
        );
        assert_eq!(
            format_for(RateMode::F700, ChannelFormat::Compact8),
            ChannelFormat::Compact8
        );
        let params = LinkParams::new(7, Band::Mhz433, RateMode::F700, ChannelFormat::Full16, 8);
        assert_eq!(params.format, ChannelFormat::Sticks16);
    }
    use crate::frame::encode;

    fn params(id: u32) -> LinkParams {
        LinkParams::new(id, Band::Mhz433, RateMode::F250, ChannelFormat::Full16, 4)
    }

    #[test]
    fn plain_offer_accept_exchange() {
        let p = params(0x1357_9BDF);
        let offering = Offering::new(&p, &BindAuth::Plain, &[0; 32]);
        let mut buf = [0u8; 64];
        let n = encode(&Frame::BindOffer(offering.offer()), BIND_KEY, &mut buf).unwrap();
        assert_eq!(
            n, 13,
            "a plain offer: version, kind, ID, 4 codes, auth, CRC"
        );
        assert_eq!(buf[0], crate::frame::BIND_VERSION);
        let offer = offered(&buf[..n]).unwrap();
        assert_eq!(LinkParams::from_offer(&offer), p);
        let plain = FollowerAuth::default();
        assert_eq!(
            offer_needs(&offer, &plain),
            OfferNeeds::Refused(BindRefusal::PlainRefused),
            "unauthenticated only by the explicit setting"
        );
        let allowed = FollowerAuth {
            allow_plain: true,
            ..plain
        };
        assert_eq!(offer_needs(&offer, &allowed), OfferNeeds::Plain);
        let accept = Frame::BindAccept {
            bind_id: p.bind_id,
            exchange: None,
        };
        let n = encode(&accept, BIND_KEY, &mut buf).unwrap();
        assert!(is_accept_of(&buf[..n], &p));
        assert!(!is_accept_of(&buf[..n], &params(0x1357_9BDE)));
        assert_eq!(
            offering.on_accept(&buf[..n], &key(0)),
            Some(Accepted::Bound {
                key: None,
                confirm: None
            })
        );
        // A frame keyed with a link ID is not a bind frame.
        let n = encode(&accept, p.bind_id, &mut buf).unwrap();
        assert!(!is_accept_of(&buf[..n], &p));
    }

    fn key(n: u8) -> LinkKey {
        LinkKey::from_bytes([n; 16])
    }

    /// Master and follower through the pure halves: offer, accept, confirmation.
    fn bind(
        master_auth: &BindAuth,
        follower_prs: &[u8],
        random: u8,
    ) -> (Option<Accepted>, Option<Option<LinkKey>>, usize) {
        let p = params(0x0BAD_CAFE);
        let handed = key(0x5A);
        let offering = Offering::new(&p, master_auth, &[random; 32]);
        let mut buf = [0u8; 64];
        let n = encode(&Frame::BindOffer(offering.offer()), BIND_KEY, &mut buf).unwrap();
        let offer_len = n;
        let offer = offered(&buf[..n]).unwrap();
        let answering = Answering::new(&offer, follower_prs, &[random ^ 0xFF; 32]).unwrap();
        assert!(answering.is_repeat(&buf[..n]));
        let n = encode(&answering.accept(), BIND_KEY, &mut buf).unwrap();
        let accepted = offering.on_accept(&buf[..n], &handed);
        let confirmed = match accepted {
            Some(Accepted::Bound {
                confirm: Some(confirm),
                ..
            }) => {
                let n = encode(&confirm, BIND_KEY, &mut buf).unwrap();
                answering.on_confirm(&buf[..n])
            }
            _ => None,
        };
        (accepted, confirmed, offer_len)
    }

    #[test]
    fn a_key_agreement_hands_the_links_key_over_only_with_the_same_phrase() {
        let secret = PhraseSecret {
            salt: [1; 8],
            prs: [2; 32],
        };
        let (accepted, confirmed, offer_len) = bind(&BindAuth::Phrase(secret), &secret.prs, 1);
        assert_eq!(offer_len, 61, "fits the 64-byte FIFO");
        assert_eq!(
            accepted.map(|a| matches!(a, Accepted::Bound { key: Some(k), .. } if k == key(0x5A))),
            Some(true)
        );
        assert_eq!(confirmed, Some(Some(key(0x5A))), "the follower has the key");
        // Another phrase: the master sees the mismatch, the follower gets no key.
        let (accepted, confirmed, _) = bind(&BindAuth::Phrase(secret), &[3; 32], 1);
        assert_eq!(accepted, Some(Accepted::Mismatch));
        assert_eq!(confirmed, None);
        // Without a phrase: anyone in the window agrees, and still nobody who only listens.
        let (accepted, confirmed, offer_len) = bind(&BindAuth::Anonymous, &[], 2);
        assert_eq!(offer_len, 53);
        assert!(matches!(
            accepted,
            Some(Accepted::Bound { key: Some(_), .. })
        ));
        assert_eq!(confirmed, Some(Some(key(0x5A))));
    }

    #[test]
    fn the_key_never_travels_in_clear_and_a_wrong_confirmation_is_refused() {
        let p = params(7);
        let offering = Offering::new(&p, &BindAuth::Anonymous, &[9; 32]);
        let offer = offering.offer();
        let answering = Answering::new(&offer, &[], &[8; 32]).unwrap();
        let mut buf = [0u8; 64];
        let n = encode(&answering.accept(), BIND_KEY, &mut buf).unwrap();
        let Some(Accepted::Bound {
            confirm: Some(confirm),
            ..
        }) = offering.on_accept(&buf[..n], &key(0x5A))
        else {
            panic!("bound");
        };
        let n = encode(&confirm, BIND_KEY, &mut buf).unwrap();
        assert!(!buf[..n].windows(16).any(|w| w == [0x5A; 16]), "sealed");
        // A flipped bit anywhere in the confirmation: refused, no key.
        for bit in 6 * 8..(n - 2) * 8 {
            let Frame::BindConfirm {
                bind_id,
                mut tag,
                mut sealed,
            } = confirm
            else {
                panic!()
            };
            let i = bit / 8 - 6;
            if i < 16 {
                tag[i] ^= 1 << (bit % 8);
            } else {
                sealed[i - 16] ^= 1 << (bit % 8);
            }
            let forged = Frame::BindConfirm {
                bind_id,
                tag,
                sealed,
            };
            let m = encode(&forged, BIND_KEY, &mut buf).unwrap();
            assert_eq!(answering.on_confirm(&buf[..m]), Some(None), "bit {bit}");
        }
        // A changed offer (another rate) agrees another key: the confirmation fails.
        let mut changed = offer;
        changed.rate = RateMode::L50;
        let other = Answering::new(&changed, &[], &[8; 32]).unwrap();
        let n = encode(&other.accept(), BIND_KEY, &mut buf).unwrap();
        assert_eq!(
            offering.on_accept(&buf[..n], &key(1)),
            Some(Accepted::Mismatch)
        );
    }

    #[test]
    fn a_follower_takes_only_offers_it_has_the_phrase_for() {
        let secret = PhraseSecret {
            salt: [1; 8],
            prs: [2; 32],
        };
        let p = params(3);
        let with_phrase = Offering::new(&p, &BindAuth::Phrase(secret), &[0; 32]).offer();
        let without = Offering::new(&p, &BindAuth::Anonymous, &[0; 32]).offer();
        let typed = FollowerAuth {
            phrase: Some("amber kettle under the oak"),
            ..FollowerAuth::default()
        };
        let nothing = FollowerAuth::default();
        assert_eq!(
            offer_needs(&with_phrase, &typed),
            OfferNeeds::Phrase {
                salt: [1; 8],
                stored: None
            }
        );
        assert_eq!(
            offer_needs(&with_phrase, &nothing),
            OfferNeeds::Refused(BindRefusal::PhraseWanted)
        );
        assert_eq!(
            offer_needs(&without, &typed),
            OfferNeeds::Refused(BindRefusal::NoPhraseOffered)
        );
        assert_eq!(offer_needs(&without, &nothing), OfferNeeds::Anonymous);
        let stored = FollowerAuth {
            stored: Some(secret),
            ..nothing
        };
        assert_eq!(
            offer_needs(&with_phrase, &stored),
            OfferNeeds::Phrase {
                salt: [1; 8],
                stored: Some(secret)
            }
        );
        let other_salt = FollowerAuth {
            stored: Some(PhraseSecret {
                salt: [9; 8],
                ..secret
            }),
            ..nothing
        };
        assert_eq!(
            offer_needs(&with_phrase, &other_salt),
            OfferNeeds::Refused(BindRefusal::PhraseWanted)
        );
    }

    #[test]
    fn ids_avoid_reserved_values_and_headers_differ() {
        assert_ne!(params(0).bind_id, 0);
        assert_ne!(params(BIND_KEY).bind_id, BIND_KEY);
        assert_eq!(params(77).bind_id, 77);
        let mut headers: Vec<[u8; 4]> = (0..2000u32)
            .map(|i| params(i * 7919 + 1).header())
            .collect();
        headers.sort();
        headers.dedup();
        assert_eq!(headers.len(), 2000);
        assert_ne!(params(1).header(), BIND_HEADER);
    }

    #[test]
    fn each_model_has_its_own_identity() {
        let p = params(0x1357_9BDF);
        let mut ids: Vec<u32> = (0..=255u8).map(|m| p.for_model(m).bind_id).collect();
        ids.push(p.bind_id);
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(
            ids.len(),
            257,
            "every model differs from the others and the base"
        );
        let m3 = p.for_model(3);
        assert_eq!(m3, p.for_model(3), "deterministic");
        assert_ne!(m3.header(), p.header());
        assert_ne!(m3.header(), p.for_model(4).header());
        assert_eq!((m3.band, m3.rate, m3.telemetry_ratio), (p.band, p.rate, 4));
        // A bind offer carries the model's identity; the receiver stores that.
        assert_eq!(LinkParams::from_offer(&m3.offer(None)), m3);
    }
}
