//! The bound link's parameters in the settings: written after an over-the-air bind so the
//! flight controller finds its module again after a power cycle (the ≥ 32-bit bind ID and
//! what the module offered with it).

use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, LinkParams, RateMode};

use crate::settings::{ParamError, Settings, Value};

const BANDS: [Band; 3] = [Band::Mhz433, Band::Mhz868, Band::Mhz915];
const RATES: [RateMode; 5] = [
    RateMode::L50,
    RateMode::M100,
    RateMode::F250,
    RateMode::F500,
    RateMode::F700,
];
const FORMATS: [ChannelFormat; 3] = [
    ChannelFormat::Full16,
    ChannelFormat::Compact8,
    ChannelFormat::Sticks16,
];

/// The band to listen for a bind offer on: the stored `link.band` (433 MHz if out of range).
pub fn bind_band(s: &Settings) -> Band {
    BANDS
        .get(s.u32("link.band") as usize)
        .copied()
        .unwrap_or(Band::Mhz433)
}

/// The stored link, or `None` if this flight controller was never bound.
pub fn stored_link(s: &Settings) -> Option<LinkParams> {
    let bind_id = s.u32("link.bind_id");
    if bind_id == 0 {
        return None;
    }
    let pick = |name: &str| s.u32(name) as usize;
    Some(LinkParams {
        bind_id,
        band: BANDS.get(pick("link.band")).copied()?,
        rate: RATES.get(pick("link.rate")).copied()?,
        format: FORMATS.get(pick("link.channels")).copied()?,
        telemetry_ratio: u8::try_from(s.u32("link.telemetry_ratio")).ok()?,
    })
}

/// Writes a freshly bound link into `s` (in RAM; the storage task persists it): all five
/// values or none (see [`Settings::set_many`]).
pub fn store_link(s: &mut Settings, link: &LinkParams) -> Result<(), ParamError> {
    let index = |found: Option<usize>| {
        found
            .map(|i| Value::U32(i as u32))
            .ok_or(ParamError::OutOfRange)
    };
    s.set_many(&[
        ("link.bind_id", Value::U32(link.bind_id)),
        (
            "link.band",
            index(BANDS.iter().position(|b| *b == link.band))?,
        ),
        (
            "link.rate",
            index(RATES.iter().position(|r| *r == link.rate))?,
        ),
        (
            "link.channels",
            index(FORMATS.iter().position(|f| *f == link.format))?,
        ),
        (
            "link.telemetry_ratio",
            Value::U32(u32::from(link.telemetry_ratio)),
        ),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bound_link_round_trips_through_the_settings() {
        let mut s = Settings::default();
        assert_eq!(stored_link(&s), None, "factory settings are unbound");
        let link = LinkParams::new(
            0xC0FF_EE01,
            Band::Mhz868,
            RateMode::F500,
            ChannelFormat::Compact8,
            8,
        );
        store_link(&mut s, &link).unwrap();
        assert_eq!(s.u32("link.rate"), 3);
        assert_eq!(stored_link(&s), Some(link));
        // A ratio outside the table's 2–128 is refused, not stored.
        let odd = LinkParams {
            telemetry_ratio: 200,
            ..link
        };
        assert_eq!(store_link(&mut s, &odd), Err(ParamError::OutOfRange));
        assert_eq!(stored_link(&s), Some(link));
        // A ratio that is no power of two, on a new bind ID: none of the five values is
        // stored (the old code stored the first four, then refused the ratio... or took 3).
        let three = LinkParams {
            bind_id: 0x1234_5678,
            band: Band::Mhz433,
            telemetry_ratio: 3,
            ..link
        };
        assert!(store_link(&mut s, &three).is_err());
        assert_eq!(stored_link(&s), Some(link), "the old link, whole");
    }
}
