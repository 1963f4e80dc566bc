//! The module's settings as CRSF parameters, as the radio's device tool (the ExpressLRS Lua
//! script EdgeTX users run for any CRSF module) lists and changes them; the wire format is
//! `taulink_handset::crsf::params`. This module owns the table: numbers, names, options,
//! what a write changes and which changes restart the link.
//!
//! Changes apply at once to the settings in RAM; the **Save** command persists them (after a
//! confirmation). Packet rate, telemetry ratio and band restart the link (the session ends
//! with `SessionEnd::SettingsChanged`) and the changed row then reads "(link restarted)"; the
//! receiver learns them at the next **Bind**. Input, telemetry output and TX power are read at
//! power-up (they would cut the JR line the tool talks over, or the radio's power is set
//! when the chip starts), so their rows say "(on power-up)".
//!
//! Numbering (fixed; the radio reads 1 … [`PARAMETER_COUNT`]). Model match (13, restarts
//! the link) and the "Model" row (14, INFO: the radio's model and whether a receiver was
//! bound under it — "mismatch" tells the pilot why the link does not come up) were added
//! at the end.
//!
//! **Protocol** (15) picks the air protocol; its OpenLRSng options say "(no auth)" because
//! OpenLRSng frames carry no authentication. The **OpenLRSng** folder (16) holds the
//! OpenLRSng transmitter's bind parameters (modem rate, channel mode, telemetry); the carrier
//! and the hop seed are set from the other settings paths (`settings::text`). Any write after
//! which the set would not run (`Settings::validate`: an OpenLRSng link outside the band
//! plan, OpenLRSng in the receiver role) is refused and changes nothing.
//!
//! **Bind Phrase** (20) is a STRING row the pilot types the binding phrase into (the
//! ExpressLRS Lua tool edits STRING parameters with the radio's name editor); the text is
//! never stored or shown, only its slow derivation (`crate::phrase`), which runs for ≈ 2 s
//! and is then saved; the next bind agrees the link's key with it. The **Link Key** row (22)
//! shows the fingerprint of the running link's key — to compare with the flight console's
//! `status` — and whether a phrase is set ("NO AUTH" instead of a fingerprint on an
//! unauthenticated link), or what the last phrase write did (deriving, refused: armed quad, empty text, too
//! weak). The HM-10 PIN in force is the read-only **BLE PIN** row (21); the link's
//! authentication failures (spec §12.2), down at the module and up at the flight side, are
//! the read-only **Tag Fails** row (23), with "ALERT" when they run above what noise
//! explains.

use core::fmt::Write;

use heapless::{String, Vec};
use taulink_handset::crsf::params::{CommandStatus, Entry, MAX_ENTRY_LEN};

use crate::phrase::{self, HANDSET_PHRASE_MAX, PhraseNote};
use crate::ppm::FailsafeOutput;
use crate::settings::openlrs::{CHANNEL_MODES, DEFAULT_CHANNEL_MODE, DEFAULT_PROFILE};
use crate::settings::{
    Band, DEFAULT_INPUT_TIMEOUT_MS, DEFAULT_TELEMETRY_RATIO, INPUT_TIMEOUT_MS, InputProtocol,
    LinkProtocol, OutputProtocol, RateMode, Settings, TELEMETRY_RATIOS,
};

/// Packet rate (the link's rate modes).
pub const PACKET_RATE: u8 = 1;
/// Telemetry ratio.
pub const TELEMETRY_RATIO: u8 = 2;
/// TX power.
pub const TX_POWER: u8 = 3;
/// RF band.
pub const BAND: u8 = 4;
/// Folder: the JR-line side.
pub const HANDSET_FOLDER: u8 = 5;
/// Input (PPM / CRSF).
pub const INPUT: u8 = 6;
/// Telemetry output to the handset.
pub const TELEMETRY_OUTPUT: u8 = 7;
/// Handset input timeout.
pub const INPUT_TIMEOUT: u8 = 8;
/// Folder: receiver-role settings.
pub const RECEIVER_FOLDER: u8 = 9;
/// PPM failsafe in the receiver role.
pub const PPM_FAILSAFE: u8 = 10;
/// Command: bind.
pub const BIND: u8 = 11;
/// Command: save the settings.
pub const SAVE: u8 = 12;
/// Model match on/off.
pub const MODEL_MATCH: u8 = 13;
/// The radio's model and whether it matches (INFO).
pub const MODEL: u8 = 14;
/// Link protocol (TauLink / OpenLRSng 3.8 / 3.9).
pub const PROTOCOL: u8 = 15;
/// Folder: the OpenLRSng transmitter's bind parameters.
pub const OPENLRS_FOLDER: u8 = 16;
/// OpenLRSng modem rate (profile 0..4).
pub const OPENLRS_RATE: u8 = 17;
/// OpenLRSng channel mode.
pub const OPENLRS_CHANNELS: u8 = 18;
/// OpenLRSng telemetry on/off.
pub const OPENLRS_TELEMETRY: u8 = 19;
/// The binding phrase (STRING: typed on the radio, never shown).
pub const BIND_PHRASE: u8 = 20;
/// Info: the HM-10 pairing PIN in force.
pub const BLE_PIN: u8 = 21;
/// Info: the link key's fingerprint and the phrase's state, or what the last phrase write did.
pub const LINK_KEY: u8 = 22;
/// Info: the link's authentication failures, both ends.
pub const TAG_FAILS: u8 = 23;
/// Parameters the module offers (DEVICE_INFO's count).
pub const PARAMETER_COUNT: u8 = 23;

/// The key row of a link without a key (before the phrase's state).
pub const UNAUTHENTICATED: &str = "NO AUTH";

/// How often the radio polls a running command, 10 ms units.
const POLL_10MS: u8 = 50;
const ON_POWER_UP: &str = " (on power-up)";
const RESTARTED: &str = " (link restarted)";

/// The commands' handshake state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Commands {
    /// A bind started from the radio is running.
    pub binding: bool,
    /// How the last bind from the radio ended (`Some(true)` bound).
    pub bind_result: Option<bool>,
    /// Save waits for the pilot's confirmation.
    pub save_confirming: bool,
    /// The last save from the radio was handed to the firmware.
    pub saved: bool,
    /// The parameter whose change last restarted the link.
    pub restarted_by: Option<u8>,
    /// The model ID the radio last selected (CRSF model select), for the "Model" row.
    pub radio_model: Option<u8>,
    /// The HM-10 PIN in force (the set one, or the factory one of this chip), for its row;
    /// the core fills it in (`App::set_unique_id`). `None`: not known yet.
    pub ble_pin: Option<crate::hm10::at::Pin>,
    /// The flight side reported its motors armed (its last `ArmState`); the core fills it
    /// in from telemetry. A phrase change is refused while set.
    pub flight_armed: bool,
    /// What the last phrase write did, for the "Link Key" row.
    pub phrase_note: Option<PhraseNote>,
    /// The link's authentication failures for the "Tag Fails" row: down at the module, up at
    /// the flight side (its last report), and whether either runs above what noise explains
    /// (the core fills it in every tick).
    pub tag_failures: crate::ports::TagFailures,
}

/// What a write asks of the core beyond the settings change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Effect {
    /// Nothing (or an invalid write, ignored).
    None,
    /// The link must restart with the new settings.
    RestartLink,
    /// Apply the input timeout to the link.
    InputTimeout,
    /// Apply the PPM failsafe to the encoder.
    PpmFailsafe,
    /// Start a bind (the radio's Bind command).
    Bind,
    /// Persist the settings.
    Save,
    /// Answer with the command's entry (its new status).
    CommandStatus,
    /// A new binding phrase from the radio: start its derivation (the core takes the text
    /// from the write, `crate::phrase::phrase_from_write`).
    DerivePhrase,
}

/// The name the radio shows for a rate mode, with its packet rate.
fn rate_label(rate: RateMode) -> &'static str {
    match rate {
        RateMode::L50 => "L50 (50 Hz)",
        RateMode::M100 => "M100 (100 Hz)",
        RateMode::F250 => "F250 (250 Hz)",
        RateMode::F500 => "F500 (500 Hz)",
        RateMode::F700 => "F700 (700 Hz)",
    }
}

/// The RFM22B's eight power steps (`radio_rfm22b::TxPower`): nominal dBm and mW.
const TX_POWER_LABELS: [&str; 8] = [
    "1dBm 1mW",
    "2dBm 2mW",
    "5dBm 3mW",
    "8dBm 6mW",
    "11dBm 13mW",
    "14dBm 25mW",
    "17dBm 50mW",
    "20dBm 100mW",
];

/// Band options, in `Band` order, with their legal meaning.
const BAND_LABELS: [&str; 4] = ["433 HAM licence", "868 EU SRD", "915 US ISM", "433 ISM LPD"];
const INPUT_LABELS: [&str; 4] = ["PPM", "CRSF 400k", "CRSF 115k", "CRSF 921k"];
const OUTPUT_LABELS: [&str; 4] = ["Off", "CRSF", "S.Port", "FrSky D"];
const FAILSAFE_LABELS: [&str; 2] = ["Hold last", "Stop pulses"];
const OFF_ON_LABELS: [&str; 2] = ["Off", "On"];

/// The "Model" row: with model match on, the radio's model ID and whether a receiver was
/// bound under it ("mismatch": none was, so nothing answers until one is bound).
fn model_text(settings: &Settings, commands: &Commands) -> Option<String<24>> {
    let mut text = String::new();
    match (settings.model_match, commands.radio_model) {
        (false, _) => text.push_str("any (match off)").ok()?,
        (true, None) => text.push_str("no ID from radio").ok()?,
        (true, Some(m)) if settings.model_bound(m) => write!(text, "{m} bound").ok()?,
        (true, Some(m)) => write!(text, "{m} Model mismatch").ok()?,
    }
    Some(text)
}
/// Protocol options, in `LinkProtocol` order: the OpenLRSng ones say they are unauthenticated.
const PROTOCOL_LABELS: [&str; 3] = ["TauLink", "OLRSng3.8 (no auth)", "OLRSng3.9 (no auth)"];
/// OpenLRSng's modem profiles.
const OPENLRS_RATE_LABELS: [&str; 5] = ["4800bps", "9600bps", "19k2bps", "57k6bps", "125kbps"];
/// OpenLRSng's channel modes 1..6.
const OPENLRS_CHANNEL_LABELS: [&str; 6] = ["4+4", "8", "8+4", "12", "12+4", "16"];

fn ratio_index(ratio: u8) -> u8 {
    TELEMETRY_RATIOS
        .iter()
        .position(|r| *r == ratio)
        .and_then(|i| u8::try_from(i).ok())
        .unwrap_or(0)
}

fn unit(commands: &Commands, number: u8, base: &'static str) -> &'static str {
    if commands.restarted_by == Some(number) {
        RESTARTED
    } else {
        base
    }
}

/// Parameter `number`'s description for `settings`, `None` for an unknown number.
pub fn entry(
    number: u8,
    settings: &Settings,
    commands: &Commands,
) -> Option<Vec<u8, MAX_ENTRY_LEN>> {
    let entry = match number {
        PACKET_RATE => {
            let labels: Vec<&str, 8> = RateMode::ALL.iter().map(|r| rate_label(*r)).collect();
            Entry::selection(
                0,
                "Packet Rate",
                &labels,
                settings.rate.code(),
                RateMode::L50.code(),
                unit(commands, number, ""),
            )
        }
        TELEMETRY_RATIO => {
            let mut texts: Vec<String<6>, 8> = Vec::new();
            for ratio in TELEMETRY_RATIOS {
                let mut text = String::new();
                write!(text, "1:{ratio}").ok()?;
                texts.push(text).ok()?;
            }
            let labels: Vec<&str, 8> = texts.iter().map(|t| t.as_str()).collect();
            Entry::selection(
                0,
                "Telem Ratio",
                &labels,
                ratio_index(settings.telemetry_ratio),
                ratio_index(DEFAULT_TELEMETRY_RATIO),
                unit(commands, number, ""),
            )
        }
        TX_POWER => Entry::selection(
            0,
            "TX Power",
            &TX_POWER_LABELS,
            settings.tx_power,
            7,
            ON_POWER_UP,
        ),
        BAND => Entry::selection(
            0,
            "Band",
            &BAND_LABELS,
            Band::code(settings.band),
            0,
            unit(commands, number, ""),
        ),
        HANDSET_FOLDER => Entry::folder(0, "Handset"),
        INPUT => Entry::selection(
            HANDSET_FOLDER,
            "Input",
            &INPUT_LABELS,
            settings.input as u8,
            0,
            ON_POWER_UP,
        ),
        TELEMETRY_OUTPUT => Entry::selection(
            HANDSET_FOLDER,
            "Telem Output",
            &OUTPUT_LABELS,
            settings.output as u8,
            OutputProtocol::SPort as u8,
            ON_POWER_UP,
        ),
        INPUT_TIMEOUT => Entry::uint16(
            HANDSET_FOLDER,
            "Input Timeout",
            settings.input_timeout_ms,
            *INPUT_TIMEOUT_MS.start(),
            *INPUT_TIMEOUT_MS.end(),
            DEFAULT_INPUT_TIMEOUT_MS,
            "ms",
        ),
        RECEIVER_FOLDER => Entry::folder(0, "Receiver Role"),
        PPM_FAILSAFE => Entry::selection(
            RECEIVER_FOLDER,
            "PPM Failsafe",
            &FAILSAFE_LABELS,
            settings.failsafe as u8,
            FailsafeOutput::StopPulses as u8,
            "",
        ),
        BIND => {
            let (status, info) = match (commands.binding, commands.bind_result) {
                (true, _) => (CommandStatus::Progress, "Binding"),
                (false, Some(true)) => (CommandStatus::Ready, "Bound"),
                (false, Some(false)) => (CommandStatus::Ready, "No receiver"),
                (false, None) => (CommandStatus::Ready, ""),
            };
            Entry::command(0, "Bind", status, POLL_10MS, info)
        }
        SAVE => {
            let (status, info) = match (commands.save_confirming, commands.saved) {
                // With PPM input the next power-up has no CRSF line, so no device tool: the
                // only way back is a settings change from elsewhere. Say so before it sticks.
                (true, _) if settings.input == InputProtocol::Ppm => (
                    CommandStatus::ConfirmationNeeded,
                    "Save? PPM input ends this menu",
                ),
                (true, _) => (CommandStatus::ConfirmationNeeded, "Save settings?"),
                (false, true) => (CommandStatus::Ready, "Saved"),
                (false, false) => (CommandStatus::Ready, ""),
            };
            Entry::command(0, "Save", status, POLL_10MS, info)
        }
        MODEL_MATCH => Entry::selection(
            0,
            "Model Match",
            &OFF_ON_LABELS,
            u8::from(settings.model_match),
            0,
            unit(commands, number, ""),
        ),
        MODEL => Entry::info(0, "Model", &model_text(settings, commands)?),
        PROTOCOL => Entry::selection(
            0,
            "Protocol",
            &PROTOCOL_LABELS,
            settings.protocol.code(),
            LinkProtocol::TauLink.code(),
            unit(commands, number, ""),
        ),
        OPENLRS_FOLDER => Entry::folder(0, "OpenLRSng"),
        OPENLRS_RATE => Entry::selection(
            OPENLRS_FOLDER,
            "OLRS Rate",
            &OPENLRS_RATE_LABELS,
            settings.openlrs.profile,
            DEFAULT_PROFILE,
            unit(commands, number, ""),
        ),
        OPENLRS_CHANNELS => Entry::selection(
            OPENLRS_FOLDER,
            "OLRS Channels",
            &OPENLRS_CHANNEL_LABELS,
            settings
                .openlrs
                .channel_mode
                .saturating_sub(*CHANNEL_MODES.start()),
            DEFAULT_CHANNEL_MODE - CHANNEL_MODES.start(),
            unit(commands, number, ""),
        ),
        OPENLRS_TELEMETRY => Entry::selection(
            OPENLRS_FOLDER,
            "OLRS Telem",
            &OFF_ON_LABELS,
            u8::from(settings.openlrs.telemetry),
            1,
            unit(commands, number, ""),
        ),
        // The value is always empty: the phrase is not kept, and the radio's editor starts
        // from the value, so anything shown would have to be overwritten.
        BIND_PHRASE => Entry::string(0, "Bind Phrase", "", HANDSET_PHRASE_MAX),
        LINK_KEY => {
            let mut text: String<24> = String::new();
            let key = crate::air::link_key(settings, model_of(settings, commands));
            let phrase = if settings.phrase_prs.is_some() {
                " +phrase"
            } else {
                " no phrase"
            };
            match (commands.phrase_note.and_then(PhraseNote::text), key) {
                (Some(note), _) => text.push_str(note).ok()?,
                (None, Some(key)) => write!(text, "{}{phrase}", key.fingerprint()).ok()?,
                (None, None) if crate::air::link_params(settings).is_some() => {
                    write!(text, "{UNAUTHENTICATED}{phrase}").ok()?
                }
                (None, None) => write!(text, "not bound{phrase}").ok()?,
            }
            Entry::info(0, "Link Key", &text)
        }
        TAG_FAILS => {
            let mut text: String<24> = String::new();
            let t = commands.tag_failures;
            write!(text, "{} / {}", t.down, t.up).ok()?;
            if t.alert {
                text.push_str(" ALERT").ok()?;
            }
            Entry::info(0, "Tag Fails", &text)
        }
        BLE_PIN => {
            let mut text: String<8> = String::new();
            match commands.ble_pin {
                Some(pin) => {
                    for d in pin.digits() {
                        text.push(char::from(d)).ok()?;
                    }
                }
                None => text.push_str("not set").ok()?,
            }
            Entry::info(0, "BLE PIN", &text)
        }
        _ => return None,
    };
    entry.finish().ok()
}

/// Applies a write of `value` to parameter `number`; invalid values change nothing.
pub fn write(number: u8, value: &[u8], settings: &mut Settings, commands: &mut Commands) -> Effect {
    let byte = value.first().copied();
    let before = *settings;
    let effect = match (number, byte) {
        (PACKET_RATE, Some(code)) => match RateMode::from_code(code) {
            Some(rate) => {
                settings.rate = rate;
                Effect::RestartLink
            }
            None => Effect::None,
        },
        (TELEMETRY_RATIO, Some(index)) => match TELEMETRY_RATIOS.get(usize::from(index)) {
            Some(ratio) => {
                settings.telemetry_ratio = *ratio;
                Effect::RestartLink
            }
            None => Effect::None,
        },
        (TX_POWER, Some(step @ 0..=7)) => {
            settings.tx_power = step;
            Effect::None
        }
        (BAND, Some(index)) => Band::from_code(index).map_or(Effect::None, |band| {
            settings.band = band;
            Effect::RestartLink
        }),
        (INPUT, Some(index)) => {
            if let Some(input) = match index {
                0 => Some(InputProtocol::Ppm),
                1 => Some(InputProtocol::Crsf),
                2 => Some(InputProtocol::Crsf115200),
                3 => Some(InputProtocol::Crsf921600),
                _ => None,
            } {
                settings.input = input;
            }
            Effect::None
        }
        (TELEMETRY_OUTPUT, Some(index)) => {
            if let Some(output) = match index {
                0 => Some(OutputProtocol::Off),
                1 => Some(OutputProtocol::Crsf),
                2 => Some(OutputProtocol::SPort),
                3 => Some(OutputProtocol::FrskyHub),
                _ => None,
            } {
                settings.output = output;
            }
            Effect::None
        }
        (INPUT_TIMEOUT, _) => match value {
            [high, low] if INPUT_TIMEOUT_MS.contains(&u16::from_be_bytes([*high, *low])) => {
                settings.input_timeout_ms = u16::from_be_bytes([*high, *low]);
                Effect::InputTimeout
            }
            _ => Effect::None,
        },
        (PPM_FAILSAFE, Some(index @ 0..=1)) => {
            settings.failsafe = if index == 0 {
                FailsafeOutput::HoldLast
            } else {
                FailsafeOutput::StopPulses
            };
            Effect::PpmFailsafe
        }
        (BIND, Some(step)) => match CommandStatus::from_byte(step) {
            Some(CommandStatus::Start) if !commands.binding => {
                commands.binding = true;
                commands.bind_result = None;
                Effect::Bind
            }
            // A cancel closes the radio's popup; a bind under way runs to its end (it cannot
            // be half-done), and its result shows at the next read.
            Some(_) => Effect::CommandStatus,
            None => Effect::None,
        },
        (MODEL_MATCH, Some(on @ 0..=1)) => {
            settings.model_match = on == 1;
            Effect::RestartLink
        }
        (PROTOCOL, Some(code)) => match LinkProtocol::from_code(code) {
            Some(protocol) => {
                settings.protocol = protocol;
                Effect::RestartLink
            }
            None => Effect::None,
        },
        (OPENLRS_RATE, Some(profile)) if usize::from(profile) < OPENLRS_RATE_LABELS.len() => {
            settings.openlrs.profile = profile;
            openlrs_change(settings)
        }
        (OPENLRS_CHANNELS, Some(index)) if usize::from(index) < OPENLRS_CHANNEL_LABELS.len() => {
            settings.openlrs.channel_mode = CHANNEL_MODES.start() + index;
            openlrs_change(settings)
        }
        (OPENLRS_TELEMETRY, Some(on @ 0..=1)) => {
            settings.openlrs.telemetry = on == 1;
            openlrs_change(settings)
        }
        (BIND_PHRASE, Some(_)) => match phrase::phrase_from_write(value) {
            Ok(_) if commands.flight_armed => {
                commands.phrase_note = Some(PhraseNote::Armed);
                Effect::None
            }
            Ok(_) => {
                commands.phrase_note = Some(PhraseNote::Deriving);
                Effect::DerivePhrase
            }
            Err(note) => {
                commands.phrase_note = Some(note);
                Effect::None
            }
        },
        (SAVE, Some(step)) => match CommandStatus::from_byte(step) {
            Some(CommandStatus::Start) => {
                commands.save_confirming = true;
                commands.saved = false;
                Effect::CommandStatus
            }
            Some(CommandStatus::Confirm) if commands.save_confirming => {
                commands.save_confirming = false;
                commands.saved = true;
                Effect::Save
            }
            Some(CommandStatus::Cancel) => {
                commands.save_confirming = false;
                Effect::CommandStatus
            }
            Some(_) => Effect::CommandStatus,
            None => Effect::None,
        },
        _ => Effect::None,
    };
    if settings.validate().is_err() && before.validate().is_ok() {
        // The change would make the set unusable (an OpenLRSng link outside the band plan):
        // nothing changes. A set that was already unusable (a damaged record) stays
        // editable, so the pilot can repair it from the radio.
        *settings = before;
        return Effect::None;
    }
    if effect == Effect::RestartLink {
        if *settings == before {
            // The same value again: the link keeps running.
            return Effect::None;
        }
        commands.restarted_by = Some(number);
    } else if number != BIND && number != SAVE && *settings != before {
        commands.restarted_by = None;
    }
    effect
}

/// The radio model the module's link is mixed with (model match on, transmitter role).
fn model_of(settings: &Settings, commands: &Commands) -> Option<u8> {
    (settings.model_match && settings.role == crate::settings::Role::Transmitter)
        .then_some(commands.radio_model)
        .flatten()
}

/// An OpenLRSng parameter changed: the running link restarts only if it is OpenLRSng.
fn openlrs_change(settings: &Settings) -> Effect {
    if settings.protocol.openlrs_version().is_some() {
        Effect::RestartLink
    } else {
        Effect::None
    }
}

#[cfg(test)]
#[path = "params_tests.rs"]
mod tests;
