//! The link-protocol choice and the OpenLRSng bind parameters: which air protocol the module
//! speaks (TauLink, or OpenLRSng 3.8 / 3.9 to fly existing OpenLRSng receivers) and the
//! settings an OpenLRSng transmitter keeps (carrier, modem profile, channel mode, telemetry,
//! hop channels), with OpenLRSng's factory values, turned into the 41-byte bind data the
//! `openlrs` TX role flies and sends when binding.
//!
//! OpenLRSng frames carry no authentication: anyone who hears the bind packet (or guesses
//! the 4-byte magic) can fly or jam the link. TauLink is the default for that reason; the
//! handset labels the OpenLRSng choices "(no auth)".
//!
//! Hop channels are not stored one by one: `hop_seed` 0 means OpenLRSng's factory list and
//! magic (`bindInitDefaults()`, what an unbound OpenLRSng receiver listens to), any other
//! seed is expanded with OpenLRSng's own `bindRandomize(true)` into a magic and six hop
//! channels that all lie inside the band plan the module is set to. A bind draws a fresh
//! seed while it is still 0, so a bound link has its own identity.

use ::openlrs::RfmType;
use openlrs::BindingVersion;
use openlrs::bind::{self, BindData, MODEM_PROFILE_COUNT, TelemetryMode};
use openlrs::random::bind_randomize;

use super::{Band, OutputProtocol, Role, Settings};

/// Which air protocol the link runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkProtocol {
    /// TauLink (authenticated bind, both ends TauLink firmware). The factory choice.
    TauLink,
    /// OpenLRSng 3.8 (binding version 0x38: v3.8.x releases, dRonin, Tau Labs).
    OpenLrs38,
    /// OpenLRSng 3.9 (binding version 0x39: OpenLRSng master).
    OpenLrs39,
}

impl LinkProtocol {
    /// The OpenLRSng binding version, `None` for TauLink.
    pub const fn openlrs_version(self) -> Option<BindingVersion> {
        match self {
            Self::TauLink => None,
            Self::OpenLrs38 => Some(BindingVersion::V38),
            Self::OpenLrs39 => Some(BindingVersion::V39),
        }
    }

    /// The record byte.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The protocol for a record byte.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Self::TauLink),
            1 => Some(Self::OpenLrs38),
            2 => Some(Self::OpenLrs39),
            _ => None,
        }
    }
}

/// OpenLRSng's modem profile index for 19 200 bit/s, its factory rate (`DEFAULT_DATARATE`).
pub const DEFAULT_PROFILE: u8 = 2;
/// The fastest profile (125 000 bit/s).
pub const FASTEST_PROFILE: u8 = MODEM_PROFILE_COUNT - 1;
/// OpenLRSng's channel modes (`flags & 7`) 1..=6: 4+4, 8, 8+4, 12, 12+4, 16 channels.
pub const CHANNEL_MODES: core::ops::RangeInclusive<u8> = 1..=6;
/// The factory channel mode: 8 channels (`DEFAULT_CHANNELS_CONFIG`).
pub const DEFAULT_CHANNEL_MODE: u8 = 2;
/// The channel mode that carries 16 channels at full resolution.
pub const SIXTEEN_CHANNELS: u8 = 6;

/// The OpenLRSng transmitter's bind parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OpenLrsSettings {
    /// Carrier of hop channel 0, Hz; 0 = the band's default ([`default_carrier_hz`]).
    pub frequency_hz: u32,
    /// Modem profile 0..=4: 4800, 9600, 19 200, 57 600, 125 000 bit/s.
    pub profile: u8,
    /// Channel mode ([`CHANNEL_MODES`]).
    pub channel_mode: u8,
    /// The receiver answers every packet with a telemetry frame (RSSI, link quality, serial).
    pub telemetry: bool,
    /// 0 = OpenLRSng's factory hop list and magic, else the seed of `bindRandomize`.
    pub hop_seed: u32,
}

impl Default for OpenLrsSettings {
    /// `bindInitDefaults()`: 19 200 bit/s, 8 channels, telemetry on, factory hops.
    fn default() -> Self {
        Self {
            frequency_hz: 0,
            profile: DEFAULT_PROFILE,
            channel_mode: DEFAULT_CHANNEL_MODE,
            telemetry: true,
            hop_seed: 0,
        }
    }
}

/// Why the settings make no OpenLRSng link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OpenLrsError {
    /// The protocol setting is TauLink.
    NotOpenLrs,
    /// The module's receiver role speaks TauLink only.
    ReceiverRole,
    /// A field out of its range.
    Field,
    /// The carrier or a hop channel lies outside the module's band plan.
    OutOfPlan,
    /// The crate refuses the bind data.
    BindData(bind::Error),
}

impl core::fmt::Display for OpenLrsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotOpenLrs => f.write_str("the link protocol is TauLink"),
            Self::ReceiverRole => f.write_str("OpenLRSng runs in the transmitter role only"),
            Self::Field => f.write_str("OpenLRSng setting out of range"),
            Self::OutOfPlan => f.write_str("OpenLRSng carrier or hops outside the band plan"),
            Self::BindData(e) => write!(f, "OpenLRSng bind data: {e:?}"),
        }
    }
}

impl core::error::Error for OpenLrsError {}

/// The frequencies the band plan allows, Hz (inclusive): the same legal limits as the
/// TauLink plans (`telemetry::link::Band`), not OpenLRSng's wider module ranges.
pub const fn plan_hz(band: Band) -> (u32, u32) {
    match band {
        Band::Mhz433 => (430_000_000, 440_000_000),
        Band::Ism433 => (433_050_000, 434_790_000),
        Band::Mhz868 => (863_000_000, 870_000_000),
        Band::Mhz915 => (902_000_000, 928_000_000),
    }
}

/// The carrier of hop channel 0 when the setting is 0: OpenLRSng's default (435 / 915 MHz),
/// except where its factory hops (up to 2.45 MHz above it) would leave the plan: 865 MHz in
/// the EU plan (OpenLRSng's 868 MHz reaches 870.45 MHz), 50 kHz above the lower edge of the
/// narrow ISM sub-band (which OpenLRSng cannot use anyway: see [`bind_data`]).
pub const fn default_carrier_hz(band: Band) -> u32 {
    match band {
        Band::Ism433 => 433_100_000,
        Band::Mhz868 => 865_000_000,
        _ => RfmType::for_band(band).default_carrier_frequency_hz(),
    }
}

/// Whether a stored carrier can be valid anywhere (record decoding: 0 or inside one of
/// OpenLRSng's module ranges).
pub fn carrier_in_range(frequency_hz: u32) -> bool {
    frequency_hz == 0 || RfmType::containing(u64::from(frequency_hz)).is_some()
}

/// The bind data the OpenLRSng transmitter flies and sends when binding, from `settings`:
/// OpenLRSng's `bindInitDefaults()` for the protocol's version and the module's band, with
/// the settings' carrier, power, profile, channel mode and telemetry, and the hop list and
/// magic of `hop_seed`. Every hop must lie in the band plan, and so must OpenLRSng's fixed
/// binding frequency (435 MHz for 433 MHz modules, outside the 433.05–434.79 MHz ISM
/// sub-band: OpenLRSng is refused on that plan).
pub fn bind_data(settings: &Settings) -> Result<BindData, OpenLrsError> {
    let version = settings
        .protocol
        .openlrs_version()
        .ok_or(OpenLrsError::NotOpenLrs)?;
    if settings.role != Role::Transmitter {
        return Err(OpenLrsError::ReceiverRole);
    }
    let o = &settings.openlrs;
    if o.profile >= MODEM_PROFILE_COUNT || !CHANNEL_MODES.contains(&o.channel_mode) {
        return Err(OpenLrsError::Field);
    }
    let band = RfmType::for_band(settings.band);
    let (low_hz, high_hz) = plan_hz(settings.band);
    let mut data = BindData::defaults(version, band);
    data.rf_frequency_hz = match o.frequency_hz {
        0 => default_carrier_hz(settings.band),
        f => f,
    };
    data.rf_power = settings.tx_power.min(7);
    data.modem_profile = o.profile;
    let telemetry = match (o.telemetry, settings.output) {
        (false, _) => TelemetryMode::Off,
        (true, OutputProtocol::SPort) => TelemetryMode::SmartPort,
        (true, OutputProtocol::FrskyHub) => TelemetryMode::FrskyHub,
        (true, OutputProtocol::Off | OutputProtocol::Crsf) => TelemetryMode::Passthrough,
    };
    let telemetry_bits = match telemetry {
        TelemetryMode::Off => 0x00,
        TelemetryMode::Passthrough => 0x08,
        TelemetryMode::FrskyHub => 0x10,
        TelemetryMode::SmartPort => 0x18,
    };
    data.flags = o.channel_mode | telemetry_bits;
    let in_plan = |f: u64| f >= u64::from(low_hz) && f <= u64::from(high_hz);
    if !in_plan(data.rf_frequency_hz.into()) || !in_plan(band.binding_frequency_hz().into()) {
        return Err(OpenLrsError::OutOfPlan);
    }
    if o.hop_seed != 0 {
        let fallback = data;
        bind_randomize(&mut data, o.hop_seed, true, high_hz, &fallback);
    }
    let hops = data.hop_channels.iter().take(data.hop_count());
    if !hops.map(|&ch| data.channel_frequency_hz(ch)).all(in_plan) {
        return Err(OpenLrsError::OutOfPlan);
    }
    data.validate_for(band).map_err(OpenLrsError::BindData)?;
    Ok(data)
}

/// The whole set is usable: TauLink always, OpenLRSng when [`bind_data`] accepts it.
pub fn check(settings: &Settings) -> Result<(), OpenLrsError> {
    match bind_data(settings) {
        Ok(_) | Err(OpenLrsError::NotOpenLrs) => Ok(()),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use openlrs::bind::{DEFAULT_HOP_LIST, DEFAULT_RF_MAGIC};

    fn olrs(protocol: LinkProtocol) -> Settings {
        Settings {
            protocol,
            ..Settings::default()
        }
    }

    #[test]
    fn factory_settings_give_openlrsng_factory_bind_data() {
        assert_eq!(Settings::default().protocol, LinkProtocol::TauLink);
        assert_eq!(
            bind_data(&Settings::default()),
            Err(OpenLrsError::NotOpenLrs)
        );
        for (protocol, version) in [
            (LinkProtocol::OpenLrs38, BindingVersion::V38),
            (LinkProtocol::OpenLrs39, BindingVersion::V39),
        ] {
            let settings = Settings {
                output: OutputProtocol::Off,
                ..olrs(protocol)
            };
            let data = bind_data(&settings).unwrap();
            // Exactly bindInitDefaults(): the bind packet an OpenLRSng TX sends fresh.
            assert_eq!(data, BindData::defaults(version, RfmType::Mhz433));
            assert_eq!(data.rf_magic, DEFAULT_RF_MAGIC);
            assert_eq!(data.hop_channels[..6], DEFAULT_HOP_LIST);
            assert_eq!(data.channel_mode().channel_count(), 8);
        }
    }

    #[test]
    fn parameters_reach_the_bind_data() {
        let settings = Settings {
            band: Band::Mhz868,
            tx_power: 3,
            openlrs: OpenLrsSettings {
                frequency_hz: 864_000_000,
                profile: FASTEST_PROFILE,
                channel_mode: SIXTEEN_CHANNELS,
                telemetry: true,
                hop_seed: 0x1234_5678,
            },
            ..olrs(LinkProtocol::OpenLrs39)
        };
        let data = bind_data(&settings).unwrap();
        assert_eq!(data.rf_frequency_hz, 864_000_000);
        assert_eq!((data.rf_power, data.modem_profile), (3, 4));
        assert_eq!(data.channel_mode().channel_count(), 16);
        assert_eq!(data.telemetry_mode(), TelemetryMode::SmartPort);
        assert_ne!(data.rf_magic, DEFAULT_RF_MAGIC);
        assert_eq!(data.hop_count(), 6);
        // The same seed always gives the same link (it survives a reboot).
        assert_eq!(bind_data(&settings), Ok(data));
        let off = Settings {
            openlrs: OpenLrsSettings {
                telemetry: false,
                ..settings.openlrs
            },
            ..settings
        };
        assert_eq!(
            bind_data(&off).unwrap().telemetry_mode(),
            TelemetryMode::Off
        );
    }

    #[test]
    fn carriers_and_hops_outside_the_band_plan_are_refused() {
        // 435 MHz is outside the EU 868 plan.
        let wrong = Settings {
            band: Band::Mhz868,
            openlrs: OpenLrsSettings {
                frequency_hz: 435_000_000,
                ..OpenLrsSettings::default()
            },
            ..olrs(LinkProtocol::OpenLrs38)
        };
        assert_eq!(bind_data(&wrong), Err(OpenLrsError::OutOfPlan));
        // Near the top of the amateur plan the factory hops (up to channel 49 × 50 kHz)
        // leave it.
        let high = Settings {
            openlrs: OpenLrsSettings {
                frequency_hz: 438_000_000,
                ..OpenLrsSettings::default()
            },
            ..olrs(LinkProtocol::OpenLrs38)
        };
        assert_eq!(bind_data(&high), Err(OpenLrsError::OutOfPlan));
        let eu = Settings {
            band: Band::Mhz868,
            ..olrs(LinkProtocol::OpenLrs39)
        };
        assert_eq!(bind_data(&eu).unwrap().rf_frequency_hz, 865_000_000);
        // OpenLRSng binds on 435 MHz, outside the ISM sub-band: refused there, whatever
        // the hops.
        let ism = Settings {
            band: Band::Ism433,
            openlrs: OpenLrsSettings {
                hop_seed: 5,
                ..OpenLrsSettings::default()
            },
            ..olrs(LinkProtocol::OpenLrs39)
        };
        assert_eq!(bind_data(&ism), Err(OpenLrsError::OutOfPlan));
        // Seeded hop lists stay inside the plan they are drawn for, even from a carrier
        // 2 MHz below its top (the factory list would leave it).
        for band in [Band::Mhz433, Band::Mhz868, Band::Mhz915] {
            let (low, high) = plan_hz(band);
            for seed in 1..200 {
                let seeded = Settings {
                    band,
                    openlrs: OpenLrsSettings {
                        frequency_hz: high - 2_000_000,
                        hop_seed: seed,
                        ..OpenLrsSettings::default()
                    },
                    ..olrs(LinkProtocol::OpenLrs39)
                };
                let data = bind_data(&seeded).unwrap();
                for &ch in &data.hop_channels[..data.hop_count()] {
                    let f = data.channel_frequency_hz(ch);
                    assert!(
                        (u64::from(low)..=u64::from(high)).contains(&f),
                        "{seed}: {f}"
                    );
                }
            }
        }
        let receiver = Settings {
            role: Role::Receiver,
            ..olrs(LinkProtocol::OpenLrs39)
        };
        assert_eq!(bind_data(&receiver), Err(OpenLrsError::ReceiverRole));
        assert_eq!(check(&receiver), Err(OpenLrsError::ReceiverRole));
        assert_eq!(check(&Settings::default()), Ok(()));
    }
}
