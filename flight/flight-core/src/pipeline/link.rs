//! The bound link's parameters in the settings: written after an over-the-air bind so the
//! flight controller finds its module again after a power cycle (the ≥ 32-bit bind ID and
//! what the module offered with it), and the air protocol (`link.protocol`): TauLink, or
//! OpenLRSng 3.8 / 3.9 with the bind data an OpenLRSng transmitter sent (`link.olrs_*`).

use openlrs::BindingVersion;
use openlrs::RfmType;
use openlrs::bind::{BindData, MAX_HOPS};
use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, LinkParams, RateMode};

use crate::settings::{Change, Handle, ParamError, Settings, handles};

/// `link.band`'s values, in the order of its words (`telemetry::settings::BANDS`).
const BANDS: [Band; 4] = [Band::Mhz433, Band::Mhz868, Band::Mhz915, Band::Ism433];
/// `link.rate`'s values, in the order of its words (`telemetry::settings::RATES`).
const RATES: [RateMode; 5] = RateMode::ALL;
const FORMATS: [ChannelFormat; 3] = [
    ChannelFormat::Full16,
    ChannelFormat::Compact8,
    ChannelFormat::Sticks16,
];

/// The band to listen for a bind offer on: the stored `link.band` (433 MHz if out of range).
pub fn bind_band(s: &Settings) -> Band {
    BANDS
        .get(s.get(handles::LINK_BAND) as usize)
        .copied()
        .unwrap_or(Band::Mhz433)
}

/// The stored link, or `None` if this flight controller was never bound.
pub fn stored_link(s: &Settings) -> Option<LinkParams> {
    let bind_id = s.get(handles::LINK_BIND_ID);
    if bind_id == 0 {
        return None;
    }
    let pick = |handle: Handle<u32>| s.get(handle) as usize;
    Some(LinkParams {
        bind_id,
        band: BANDS.get(pick(handles::LINK_BAND)).copied()?,
        rate: RATES.get(pick(handles::LINK_RATE)).copied()?,
        format: FORMATS.get(pick(handles::LINK_CHANNELS)).copied()?,
        telemetry_ratio: u8::try_from(s.get(handles::LINK_TELEMETRY_RATIO)).ok()?,
    })
}

/// Writes a freshly bound link into `s` (in RAM; the storage task persists it): all five
/// values or none (see [`Settings::apply`]).
pub fn store_link(s: &mut Settings, link: &LinkParams) -> Result<(), ParamError> {
    let index = |found: Option<usize>| found.map(|i| i as u32).ok_or(ParamError::OutOfRange);
    s.apply(&[
        handles::LINK_BIND_ID.to(link.bind_id),
        handles::LINK_BAND.to(index(BANDS.iter().position(|b| *b == link.band))?),
        handles::LINK_RATE.to(index(RATES.iter().position(|r| *r == link.rate))?),
        handles::LINK_CHANNELS.to(index(FORMATS.iter().position(|f| *f == link.format))?),
        handles::LINK_TELEMETRY_RATIO.to(u32::from(link.telemetry_ratio)),
    ])
}

/// The air protocol the flight controller's link speaks (`link.protocol`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Protocol {
    /// TauLink (the factory choice; authenticated bind).
    TauLink,
    /// OpenLRSng with this binding version (0x38 or 0x39); unauthenticated.
    OpenLrs(BindingVersion),
}

/// The stored `link.protocol` (TauLink if out of range).
pub fn protocol(s: &Settings) -> Protocol {
    match s.get(handles::LINK_PROTOCOL) {
        1 => Protocol::OpenLrs(BindingVersion::V38),
        2 => Protocol::OpenLrs(BindingVersion::V39),
        _ => Protocol::TauLink,
    }
}

/// The OpenLRSng module variant for the stored `link.band` (the bind frequency).
pub fn openlrs_band(s: &Settings) -> RfmType {
    RfmType::for_band(bind_band(s))
}

/// The hop-channel words: four channels each, so exactly enough for `MAX_HOPS`.
const HOP_WORDS: [Handle<u32>; MAX_HOPS / 4] = handles::LINK_OLRS_HOPS;

/// The stored OpenLRSng bind data, whether or not `link.protocol` selects it; `None` when
/// never bound over OpenLRSng (magic 0) or when it would not run on this module's band
/// (`BindData::validate_for`: profile, power, hops and carrier inside the band's range).
pub fn stored_openlrs(s: &Settings, version: BindingVersion) -> Option<BindData> {
    let magic = s.get(handles::LINK_OLRS_MAGIC);
    if magic == 0 {
        return None;
    }
    let mut data = BindData::defaults(version, openlrs_band(s));
    data.rf_magic = magic;
    data.rf_frequency_hz = s.get(handles::LINK_OLRS_FREQUENCY_HZ);
    let [spacing, profile, flags, power] = s.get(handles::LINK_OLRS_MODEM).to_le_bytes();
    data.rf_channel_spacing = spacing;
    data.modem_profile = profile;
    data.flags = flags;
    data.rf_power = power;
    for (chunk, word) in data.hop_channels.chunks_mut(4).zip(HOP_WORDS) {
        for (slot, byte) in chunk.iter_mut().zip(s.get(word).to_le_bytes()) {
            *slot = byte;
        }
    }
    data.validate_for(openlrs_band(s)).ok()?;
    Some(data)
}

/// Writes bind data an OpenLRSng transmitter sent into `s` (in RAM): all of it or nothing.
/// The bytes OpenLRSng keeps for the RX's UART rate are not stored (the link never uses
/// them); `data.to_bytes()` of the stored link therefore differs there only.
pub fn store_openlrs(s: &mut Settings, data: &BindData) -> Result<(), ParamError> {
    let mut changes: heapless::Vec<Change, 16> = heapless::Vec::new();
    let mut push = |handle: Handle<u32>, v: u32| {
        changes
            .push(handle.to(v))
            .map_err(|_| ParamError::OutOfRange)
    };
    push(handles::LINK_OLRS_MAGIC, data.rf_magic)?;
    push(handles::LINK_OLRS_FREQUENCY_HZ, data.rf_frequency_hz)?;
    push(
        handles::LINK_OLRS_MODEM,
        u32::from_le_bytes([
            data.rf_channel_spacing,
            data.modem_profile,
            data.flags,
            data.rf_power,
        ]),
    )?;
    for (chunk, word) in data.hop_channels.chunks(4).zip(HOP_WORDS) {
        let mut bytes = [0u8; 4];
        for (slot, byte) in bytes.iter_mut().zip(chunk) {
            *slot = *byte;
        }
        push(word, u32::from_le_bytes(bytes))?;
    }
    s.apply(&changes)
}

/// The whole-set check of the OpenLRSng link: once bound over OpenLRSng and selected, the
/// stored bind data must run on the band.
pub fn openlrs_valid(s: &Settings) -> bool {
    match protocol(s) {
        Protocol::TauLink => true,
        Protocol::OpenLrs(version) => {
            s.get(handles::LINK_OLRS_MAGIC) == 0 || stored_openlrs(s, version).is_some()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Value;

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
        assert_eq!(s.get(handles::LINK_RATE), 3);
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

    #[test]
    fn openlrs_bind_data_round_trips_and_defaults_are_openlrsngs() {
        let mut s = Settings::default();
        assert_eq!(protocol(&s), Protocol::TauLink);
        assert_eq!(stored_openlrs(&s, BindingVersion::V39), None, "never bound");
        // The factory rows are OpenLRSng's bindInitDefaults() (magic aside: 0 = unbound).
        s.set("link.olrs_magic", Value::U32(0xDEAD_FEED)).unwrap();
        assert_eq!(
            stored_openlrs(&s, BindingVersion::V38),
            Some(BindData::defaults(BindingVersion::V38, RfmType::Mhz433))
        );
        let mut data = BindData::defaults(BindingVersion::V39, RfmType::Mhz868);
        data.rf_magic = 0x1234_5678;
        data.rf_frequency_hz = 866_000_000;
        data.modem_profile = 4;
        data.flags = 0x06 | 0x18;
        data.hop_channels = [0; MAX_HOPS];
        for (i, slot) in data.hop_channels.iter_mut().take(23).enumerate() {
            *slot = i as u8 * 3 + 1;
        }
        s.set_text("link.band", "868").unwrap();
        store_openlrs(&mut s, &data).unwrap();
        s.set_text("link.protocol", "openlrs39").unwrap();
        assert_eq!(protocol(&s), Protocol::OpenLrs(BindingVersion::V39));
        assert_eq!(stored_openlrs(&s, BindingVersion::V39), Some(data));
        assert_eq!(data.to_bytes()[0], 0x39);
        // A carrier of the other band cannot be stored while that data is selected.
        let mut wrong = data;
        wrong.rf_frequency_hz = 435_000_000;
        let before = s.clone();
        assert!(store_openlrs(&mut s, &wrong).is_err());
        assert_eq!(s, before, "nothing of it stored");
        // Nor can the band change under it.
        assert!(s.set_text("link.band", "433").is_err());
    }
}
