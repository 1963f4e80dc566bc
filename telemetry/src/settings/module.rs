//! The module's settings as every end reads them: each one's stable key, its name (the word
//! a host tool's `--module-set` or a console types: `rate=F500`), its type and range or
//! choice words, and its factory value — the same [`Param`] rows as the flight side's table.
//! Where the module stores each one, how the radio's device tool shows it and what a change
//! does is the module's own binding of these rows (`module_core::settings::table`).
//!
//! The link's words (rate, band, air protocol) are the flight side's ([`RATES`], [`BANDS`],
//! [`PROTOCOLS`]), so `rate=F500` here is `link.rate F500` there. Keys are the module's
//! 10xx; a retired key is never reused.

use super::{BANDS, Choice, Kind, PROTOCOLS, Param, RATES, Value};

/// Transmitter (the JR bay) or receiver (PPM out).
pub const ROLES: Choice = &["transmitter", "receiver"];
/// The handset input: PPM, or CRSF at 400 kBd, 115 200 Bd or 921 600 Bd.
pub const INPUTS: Choice = &["ppm", "crsf", "crsf115200", "crsf921600"];
/// What goes back to the handset.
pub const OUTPUTS: Choice = &["off", "crsf", "sport", "frsky_hub"];
/// The PPM output's failsafe (receiver role).
pub const FAILSAFES: Choice = &["hold_last", "stop_pulses"];
/// A switch.
pub const OFF_ON: Choice = &["off", "on"];
/// OpenLRSng's modem profiles, bit/s.
pub const OLRS_PROFILES: Choice = &["4800", "9600", "19200", "57600", "125000"];
/// OpenLRSng's channel modes 1…6, as channel counts.
pub const OLRS_CHANNELS: Choice = &["4+4", "8", "8+4", "12", "12+4", "16"];

const fn choice(key: u16, name: &'static str, words: Choice, default: u32) -> Param {
    Param {
        key,
        name,
        kind: Kind::Choice(words),
        default: Value::U32(default),
    }
}

const fn number(key: u16, name: &'static str, min: u32, max: u32, default: u32) -> Param {
    Param {
        key,
        name,
        kind: Kind::U32 { min, max },
        default: Value::U32(default),
    }
}

/// Transmitter or receiver.
pub const ROLE: Param = choice(1000, "role", ROLES, 0);
/// The air packet rate (the link's rate mode). Factory: L50, the longest range.
pub const RATE: Param = choice(1001, "rate", RATES, 0);
/// The handset input.
pub const INPUT: Param = choice(1002, "input", INPUTS, 0);
/// The handset telemetry output. Factory: S.Port, which EdgeTX and OpenTX read from a PPM
/// module.
pub const OUTPUT: Param = choice(1003, "output", OUTPUTS, 2);
/// The RF band plan. Factory: the 70 cm amateur plan.
pub const BAND: Param = choice(1004, "band", BANDS, 0);
/// The RFM22B's power step 0…7 (+1 … +20 dBm).
pub const TX_POWER: Param = number(1005, "tx_power", 0, 7, 7);
/// The PPM output's failsafe. Factory: stop the pulses (holding the last values would hold
/// the throttle on a lost link).
pub const FAILSAFE: Param = choice(1006, "failsafe", FAILSAFES, 1);
/// The identity shared with the bound peer (written by a bind; 0: never bound).
pub const BIND_ID: Param = number(1007, "bind_id", 0, u32::MAX, 0);
/// Transmitter role: the handset input counts as lost after this long without a frame, ms
/// (never shorter than a few frames of the slowest input, never seconds of stale sticks).
pub const INPUT_TIMEOUT_MS: Param = number(1008, "input_timeout_ms", 100, 2_000, 500);
/// One link slot in this many is a downlink slot (a power of two the link takes).
pub const TELEMETRY_RATIO: Param = number(1009, "telemetry_ratio", 2, 128, 4);
/// Model match (spec §12.6): the link's identity mixed with the radio's model ID.
pub const MODEL_MATCH: Param = choice(1010, "model_match", OFF_ON, 0);
/// The air protocol: TauLink, or OpenLRSng 3.8 / 3.9 (unauthenticated).
pub const PROTOCOL: Param = choice(1011, "protocol", PROTOCOLS, 0);
/// OpenLRSng: the modem profile. Factory: 19 200 bit/s (`bindInitDefaults()`).
pub const OLRS_PROFILE: Param = choice(1012, "olrs_profile", OLRS_PROFILES, 2);
/// OpenLRSng: the channel mode. Factory: 8 channels.
pub const OLRS_CHANNELS_MODE: Param = choice(1013, "olrs_channels", OLRS_CHANNELS, 1);
/// OpenLRSng: the receiver answers every packet with telemetry.
pub const OLRS_TELEMETRY: Param = choice(1014, "olrs_telemetry", OFF_ON, 1);
/// OpenLRSng: the carrier of hop channel 0, Hz (0: the band's default).
pub const OLRS_FREQUENCY_HZ: Param = number(1015, "olrs_frequency_hz", 0, u32::MAX, 0);
/// OpenLRSng: the seed of the hop list and magic (0: OpenLRSng's factory list).
pub const OLRS_HOP_SEED: Param = number(1016, "olrs_hop_seed", 0, u32::MAX, 0);
/// The explicit setting for an unauthenticated link (spec §12.1).
pub const PLAIN: Param = choice(1017, "plain", OFF_ON, 0);
/// Dynamic transmit power (`telemetry::link::power`): the power follows the link up to
/// `tx_power`; off, the module always sends at `tx_power`.
pub const DYNAMIC_POWER: Param = choice(1018, "dynamic_power", OFF_ON, 1);

/// Every module setting with a value of its own, in the record's order. The binding phrase
/// and the BLE PIN (typed as text, stored as a derivation or a PIN) are the module's.
pub const MODULE_PARAMS: [&Param; 19] = [
    &ROLE,
    &RATE,
    &INPUT,
    &OUTPUT,
    &BAND,
    &TX_POWER,
    &FAILSAFE,
    &BIND_ID,
    &INPUT_TIMEOUT_MS,
    &TELEMETRY_RATIO,
    &MODEL_MATCH,
    &PROTOCOL,
    &OLRS_PROFILE,
    &OLRS_CHANNELS_MODE,
    &OLRS_TELEMETRY,
    &OLRS_FREQUENCY_HZ,
    &OLRS_HOP_SEED,
    &PLAIN,
    &DYNAMIC_POWER,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_and_names_are_unique_and_defaults_in_range() {
        for (i, p) in MODULE_PARAMS.iter().enumerate() {
            assert_eq!(p.check(p.default), Ok(p.default), "{}", p.name);
            assert!((1000..1100).contains(&p.key), "{}", p.name);
            for q in &MODULE_PARAMS[i + 1..] {
                assert_ne!(p.key, q.key);
                assert_ne!(p.name, q.name);
            }
            assert!(
                super::super::PARAMS.iter().all(|f| f.key != p.key),
                "{} shares a flight key",
                p.name
            );
        }
    }
}
