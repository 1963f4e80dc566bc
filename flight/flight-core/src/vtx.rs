//! The BrushedSparky's 5.8 GHz VTX: which frequency a band and channel select, and which
//! levels its five select pins take for them. The pins themselves are the firmware's
//! (`flight-fw`'s `board.rs`: RF_S1/RF_S2 on PA9/PA10, RF_CH1–3 on PB12/PB13/PB14); the
//! Sparky2 has no VTX.
//!
//! **The module.** The board's footprint is labelled SM215T (pins S1, S2, CH1, CH2, CH3,
//! audio, video, 5 V, GND, antenna; `../shared/reference/hardware.md` §2), a pin-select
//! 32-channel module of the Boscam family: two band bits and three channel bits, each pin
//! pulled up inside the module, a pin held low reads 0. No datasheet of the SM215T itself
//! was found; the frequencies per band and channel below are Boscam's published 32-channel
//! table as the board's own firmware names them (Tau Labs, `flight/targets/sparky2/fw/
//! pios_board.c`, `set_vtx_channel` and the option names of `HwSparky2.VTX_Ch`, e.g.
//! "BoscamA CH1 5725"): band code 0 = Boscam A, 1 = Boscam B, 2 = Boscam E, 3 = Airwave
//! (FatShark), channel code 0…7 = channel 1…8. Two slips of that firmware are not copied:
//! its "A CH1" case falls through to A CH2 (a missing `break`), and its Airwave CH8 reads
//! 5860 MHz, the same as CH7, where Airwave's (FatShark's) eighth channel is 5880 MHz.
//!
//! **The pins.** Open-drain without a pull on the MCU side: a 1 bit is *released* (the
//! module's pull-up makes it high), a 0 bit is driven low. Band bit 0 → RF_S1, bit 1 →
//! RF_S2; channel bit 0 → RF_CH3, bit 1 → RF_CH2, bit 2 → RF_CH1 (the board's wiring, as the
//! Tau Labs firmware drives it).

use crate::settings::{Settings, handles};

/// The module's four bands (setting `vtx.band`, `settings::params::VTX_BANDS`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Band {
    /// Boscam A (5725…5865 MHz, 20 MHz apart).
    A = 0,
    /// Boscam B (5733…5866 MHz, 19 MHz apart).
    B = 1,
    /// Boscam E (5705…5645 and 5885…5945 MHz).
    E = 2,
    /// Airwave / FatShark (5740…5880 MHz, 20 MHz apart).
    Airwave = 3,
}

impl Band {
    /// Every band, in code order.
    pub const ALL: [Band; 4] = [Band::A, Band::B, Band::E, Band::Airwave];

    /// The band with code `code` (the setting's value).
    pub const fn from_code(code: u32) -> Option<Band> {
        Some(match code {
            0 => Band::A,
            1 => Band::B,
            2 => Band::E,
            3 => Band::Airwave,
            _ => return None,
        })
    }

    /// The name the handset shows.
    pub const fn label(self) -> &'static str {
        match self {
            Band::A => "A",
            Band::B => "B",
            Band::E => "E",
            Band::Airwave => "Airwave",
        }
    }
}

/// Channels per band.
pub const CHANNELS: u8 = 8;

/// Frequency of each band's channels 1…8, MHz (Boscam's table, see the module docs).
const FREQUENCIES_MHZ: [[u16; CHANNELS as usize]; 4] = [
    [5725, 5745, 5765, 5785, 5805, 5825, 5845, 5865],
    [5733, 5752, 5771, 5790, 5809, 5828, 5847, 5866],
    [5705, 5685, 5665, 5645, 5885, 5905, 5925, 5945],
    [5740, 5760, 5780, 5800, 5820, 5840, 5860, 5880],
];

/// Frequency of `channel` (1…8) in `band`, MHz; `None` for another channel.
pub fn frequency_mhz(band: Band, channel: u8) -> Option<u16> {
    FREQUENCIES_MHZ
        .get(band as usize)?
        .get(usize::from(channel.checked_sub(1)?))
        .copied()
}

/// The five select pins' levels: `true` = released (high through the module's pull-up),
/// `false` = driven low.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VtxPins {
    /// RF_S1 (PA9): band bit 0.
    pub rf_s1: bool,
    /// RF_S2 (PA10): band bit 1.
    pub rf_s2: bool,
    /// RF_CH1 (PB12): channel bit 2.
    pub rf_ch1: bool,
    /// RF_CH2 (PB13): channel bit 1.
    pub rf_ch2: bool,
    /// RF_CH3 (PB14): channel bit 0.
    pub rf_ch3: bool,
}

/// A band and channel the VTX transmits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VtxChannel {
    /// Band.
    pub band: Band,
    /// Channel, 1…8.
    pub channel: u8,
}

impl VtxChannel {
    /// The settings' band and channel (`vtx.band`, `vtx.channel`; the table's ranges keep
    /// them valid, a stray value falls back to A 1).
    pub fn from_settings(settings: &Settings) -> Self {
        let band = Band::from_code(settings.get(handles::VTX_BAND)).unwrap_or(Band::A);
        let channel = u8::try_from(settings.get(handles::VTX_CHANNEL))
            .ok()
            .filter(|c| (1..=CHANNELS).contains(c))
            .unwrap_or(1);
        Self { band, channel }
    }

    /// Its frequency, MHz.
    pub fn frequency_mhz(self) -> u16 {
        frequency_mhz(self.band, self.channel).unwrap_or(0)
    }

    /// The pin levels that select it.
    pub fn pins(self) -> VtxPins {
        let band = self.band as u8;
        let code = self.channel.saturating_sub(1);
        VtxPins {
            rf_s1: band & 0b01 != 0,
            rf_s2: band & 0b10 != 0,
            rf_ch1: code & 0b100 != 0,
            rf_ch2: code & 0b010 != 0,
            rf_ch3: code & 0b001 != 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pins read back as the module decodes them: band = S2·2 + S1, channel code =
    /// CH1·4 + CH2·2 + CH3 (released = 1).
    fn decode(pins: VtxPins) -> (u8, u8) {
        let bit = |b: bool| u8::from(b);
        (
            bit(pins.rf_s2) * 2 + bit(pins.rf_s1),
            bit(pins.rf_ch1) * 4 + bit(pins.rf_ch2) * 2 + bit(pins.rf_ch3),
        )
    }

    #[test]
    fn every_band_and_channel_selects_its_table_frequency() {
        // Boscam's 32-channel table, band by band (module docs).
        let table: [(Band, [u16; 8]); 4] = [
            (Band::A, [5725, 5745, 5765, 5785, 5805, 5825, 5845, 5865]),
            (Band::B, [5733, 5752, 5771, 5790, 5809, 5828, 5847, 5866]),
            (Band::E, [5705, 5685, 5665, 5645, 5885, 5905, 5925, 5945]),
            (
                Band::Airwave,
                [5740, 5760, 5780, 5800, 5820, 5840, 5860, 5880],
            ),
        ];
        let mut seen = Vec::new();
        for (band_code, (band, mhz)) in table.iter().enumerate() {
            assert_eq!(Band::from_code(band_code as u32), Some(*band));
            for (index, want) in mhz.iter().enumerate() {
                let channel = index as u8 + 1;
                let vtx = VtxChannel {
                    band: *band,
                    channel,
                };
                assert_eq!(vtx.frequency_mhz(), *want, "{band:?} {channel}");
                assert_eq!(
                    decode(vtx.pins()),
                    (band_code as u8, index as u8),
                    "{band:?} {channel}: pins select another code"
                );
                seen.push(vtx.pins());
            }
        }
        seen.sort_by_key(|p| decode(*p));
        seen.dedup();
        assert_eq!(seen.len(), 32, "every pair has its own pin levels");
        assert_eq!(frequency_mhz(Band::A, 0), None);
        assert_eq!(frequency_mhz(Band::A, 9), None);
    }

    #[test]
    fn a1_drives_every_pin_low_and_airwave_8_releases_them_all() {
        let a1 = VtxChannel {
            band: Band::A,
            channel: 1,
        }
        .pins();
        assert_eq!(
            a1,
            VtxPins {
                rf_s1: false,
                rf_s2: false,
                rf_ch1: false,
                rf_ch2: false,
                rf_ch3: false,
            },
            "A 1 is 5725 MHz, not A 2 (the seed firmware's fall-through)"
        );
        let e2 = VtxChannel {
            band: Band::E,
            channel: 2,
        }
        .pins();
        assert!(!e2.rf_s1 && e2.rf_s2 && !e2.rf_ch1 && !e2.rf_ch2 && e2.rf_ch3);
    }

    #[test]
    fn the_settings_choose_the_channel() {
        let mut settings = Settings::default();
        assert_eq!(VtxChannel::from_settings(&settings).frequency_mhz(), 5725);
        settings.set_text("vtx.band", "e").unwrap();
        settings.set_text("vtx.channel", "5").unwrap();
        let vtx = VtxChannel::from_settings(&settings);
        assert_eq!(
            (vtx.band, vtx.channel, vtx.frequency_mhz()),
            (Band::E, 5, 5885)
        );
        assert!(settings.set_text("vtx.channel", "9").is_err());
    }
}
