//! Binding: the parameters both ends store, the identity bytes derived from the bind ID, and
//! the pure halves of the over-the-air bind exchange on the fixed bind channel and rate.

use super::hopping::{Band, mix32};
use super::radio::RadioConfig;
use super::rate::{BIND_RATE, RateMode};
use super::schedule::Schedule;
use crate::channels::ChannelFormat;
use crate::frame::{BindOffer, Frame, Received, decode};

/// CRC key of bind frames (fixed: both ends must read them before sharing anything).
pub const BIND_KEY: u32 = 0x7A17_B1ED;
/// Hardware header of bind frames ("TLB" + protocol version 1).
pub const BIND_HEADER: [u8; 4] = *b"TLB\x01";

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

    /// The bind offer carrying these parameters.
    pub fn offer(&self) -> BindOffer {
        BindOffer {
            bind_id: self.bind_id,
            band: self.band,
            rate: self.rate,
            format: self.format,
            telemetry_ratio: self.telemetry_ratio,
        }
    }

    /// The link of radio model `model_id` (model match, spec §12.6): the same band, rate,
    /// format and ratio under an identity mixed from the bind ID and the model ID, so a
    /// receiver bound under one model never hears (the chip's header check drops its
    /// frames) nor is heard by the module flying another. The mix is keyed like
    /// [`LinkParams::header`], never 0 or the bind key; keyed links derive their model key
    /// with `LinkKey::for_model` instead, which the bind ID then follows.
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
/// The follower answers an offer this many times, one L50 slot apart, so one lost accept
/// does not leave the master offering forever.
pub const ACCEPT_REPEATS: u8 = 3;

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

/// Master side: is this packet the follower's accept of our offer?
pub fn is_accept_of(packet: &[u8], params: &LinkParams) -> bool {
    matches!(decode(packet, BIND_KEY), Received::Accepted(Frame::BindAccept { bind_id }) if bind_id == params.bind_id)
}

/// Follower side: the parameters offered in this packet, if it is a valid offer.
pub fn offered_params(packet: &[u8]) -> Option<LinkParams> {
    match decode(packet, BIND_KEY) {
        Received::Accepted(Frame::BindOffer(offer)) => Some(LinkParams::from_offer(&offer)),
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
    fn offer_accept_exchange() {
        let p = params(0x1357_9BDF);
        let mut buf = [0u8; 32];
        let n = encode(&Frame::BindOffer(p.offer()), BIND_KEY, &mut buf).unwrap();
        assert_eq!(offered_params(&buf[..n]), Some(p));
        let n = encode(
            &Frame::BindAccept { bind_id: p.bind_id },
            BIND_KEY,
            &mut buf,
        )
        .unwrap();
        assert!(is_accept_of(&buf[..n], &p));
        assert!(!is_accept_of(&buf[..n], &params(0x1357_9BDE)));
        // A frame keyed with a link ID is not a bind frame.
        let n = encode(
            &Frame::BindAccept { bind_id: p.bind_id },
            p.bind_id,
            &mut buf,
        )
        .unwrap();
        assert!(!is_accept_of(&buf[..n], &p));
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
        assert_eq!(LinkParams::from_offer(&m3.offer()), m3);
    }
}
