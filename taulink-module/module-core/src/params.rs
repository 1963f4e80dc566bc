//! The module's settings as CRSF parameters, as the radio's device tool (the ExpressLRS Lua
//! script EdgeTX users run for any CRSF module) lists and changes them; the wire format is
//! `taulink_handset::crsf::params`. This module owns the numbering, the rows that are no
//! setting (folders, commands, what the module reports) and what a write asks of the core;
//! a setting's row — label, options, folder, the effect of a change — is its row of
//! `crate::settings::table`, and reads and writes of those rows are one loop over it.
//!
//! Changes apply at once to the settings in RAM; the **Save** command persists them (after a
//! confirmation). Packet rate, telemetry ratio and band restart the link (the session ends
//! with `SessionEnd::SettingsChanged`) and the changed row then reads "(link restarted)"; the
//! receiver learns them at the next **Bind**. Input and telemetry output are read at
//! power-up (they would cut the JR line the tool talks over), so their rows say "(on
//! power-up)". **TX Power** (3) is the maximum and **Dynamic Power** (24, Off / On, added at
//! the end) whether the power follows the link below it (`telemetry::link::power`); both
//! apply from the link's next slot.
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
use crate::settings::table::{self, Crsf, OnChange, Options, Row};
use crate::settings::{InputProtocol, Settings};

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
/// Dynamic transmit power, Off / On.
pub const DYNAMIC_POWER: u8 = 24;
/// Parameters the module offers (DEVICE_INFO's count).
pub const PARAMETER_COUNT: u8 = 24;

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
    /// Apply the power limits (TX power, dynamic power) to the link.
    TxPower,
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
/// `base`, or "(link restarted)" on the row whose change last restarted the link.
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
    let entry = match table::by_crsf(number) {
        Some((row, crsf)) => setting_entry(row, crsf, settings, commands),
        None => other_entry(number, settings, commands)?,
    };
    entry.finish().ok()
}

/// A setting's row as the radio shows it ([`table::ROWS`]).
fn setting_entry(row: &Row, crsf: Crsf, settings: &Settings, commands: &Commands) -> Entry {
    let (value, default) = ((row.get)(settings), row.default);
    let unit = match row.on_change {
        OnChange::RestartLink | OnChange::OpenLrs => unit(commands, crsf.number, ""),
        OnChange::PowerUp => ON_POWER_UP,
        OnChange::InputTimeout | OnChange::PpmFailsafe | OnChange::TxPower => "",
    };
    let (folder, label) = (crsf.folder, crsf.label);
    match crsf.options {
        Options::Labels(labels) => {
            let index = |v: u32| u8::try_from(v).unwrap_or(0);
            Entry::selection(folder, label, labels, index(value), index(default), unit)
        }
        Options::Values(labels, values) => {
            let index = |v: u32| {
                let i = values.iter().position(|x| u32::from(*x) == v);
                i.and_then(|i| u8::try_from(i).ok()).unwrap_or(0)
            };
            Entry::selection(folder, label, labels, index(value), index(default), unit)
        }
        Options::Uint16(unit) => {
            let number = |v: u32| u16::try_from(v).unwrap_or(0);
            let (min, max) = (number(row.min), number(row.max));
            Entry::uint16(
                folder,
                label,
                number(value),
                min,
                max,
                number(default),
                unit,
            )
        }
    }
}

/// The rows that are no setting: folders, commands and what the module reports.
fn other_entry(number: u8, settings: &Settings, commands: &Commands) -> Option<Entry> {
    let entry = match number {
        HANDSET_FOLDER => Entry::folder(0, "Handset"),
        RECEIVER_FOLDER => Entry::folder(0, "Receiver Role"),
        OPENLRS_FOLDER => Entry::folder(0, "OpenLRSng"),
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
        MODEL => Entry::info(0, "Model", &model_text(settings, commands)?),
        // The value is always empty: the phrase is not kept, and the radio's editor starts
        // from the value, so anything shown would have to be overwritten.
        BIND_PHRASE => Entry::string(0, "Bind Phrase", "", HANDSET_PHRASE_MAX),
        LINK_KEY => Entry::info(0, "Link Key", &link_key_text(settings, commands)?),
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
    Some(entry)
}

/// The "Link Key" row: the running key's fingerprint and whether a phrase is set, or what
/// the last phrase write did.
fn link_key_text(settings: &Settings, commands: &Commands) -> Option<String<24>> {
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
    Some(text)
}

/// Applies a write of `value` to parameter `number`; invalid values change nothing.
pub fn write(number: u8, value: &[u8], settings: &mut Settings, commands: &mut Commands) -> Effect {
    let before = *settings;
    let effect = match table::by_crsf(number) {
        Some((row, crsf)) => write_setting(row, crsf, value, settings),
        None => write_other(number, value, commands),
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

/// A write to a setting's row: a selection's index (one byte) or a 16-bit number (two,
/// big-endian), within the row's options or range; anything else changes nothing.
fn write_setting(row: &Row, crsf: Crsf, value: &[u8], settings: &mut Settings) -> Effect {
    let chosen = match (crsf.options, value) {
        (Options::Labels(labels), [index, ..]) if usize::from(*index) < labels.len() => {
            Some(u32::from(*index))
        }
        (Options::Values(_, values), [index, ..]) => {
            values.get(usize::from(*index)).map(|v| u32::from(*v))
        }
        (Options::Uint16(_), [high, low]) => Some(u32::from(u16::from_be_bytes([*high, *low]))),
        _ => None,
    };
    if !chosen.is_some_and(|v| row.assign(settings, v)) {
        return Effect::None;
    }
    match row.on_change {
        OnChange::RestartLink => Effect::RestartLink,
        OnChange::OpenLrs => openlrs_change(settings),
        OnChange::PowerUp => Effect::None,
        OnChange::InputTimeout => Effect::InputTimeout,
        OnChange::PpmFailsafe => Effect::PpmFailsafe,
        OnChange::TxPower => Effect::TxPower,
    }
}

/// A write to a command or the phrase's row.
fn write_other(number: u8, value: &[u8], commands: &mut Commands) -> Effect {
    match (number, value.first().copied()) {
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
    }
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
