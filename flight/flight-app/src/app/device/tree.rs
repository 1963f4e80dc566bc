//! The flight controller's rows in the radio's device tool: which number each setting has,
//! which folder holds it, and its CRSF parameter description — built from the settings
//! table itself (`settings::PARAMS`: name, kind, range, default), so a setting added to the
//! table shows up here without a second list.
//!
//! **Numbering** (fixed for a table; the radio reads 1 … [`PARAMETER_COUNT`]): the folders
//! first ([`FOLDERS`], 1 … 10), then every setting in table order (number
//! [`SETTINGS_BASE`] + its table index, the index the phone's `SettingChange` uses), then
//! the commands and the two info rows ([`SAVE`] …).
//!
//! **Types.** A choice is a text selection of its names. A whole number is an unsigned 16
//! when its range is small enough to scroll through ([`UINT16_MAX_SPAN`]), else a FLOAT with
//! no decimals and a step of a tenth of its default's magnitude; past `i32` it is read-only
//! text. A real number is a FLOAT: the Lua tool shows at most three decimals, so a number
//! whose default is below 0.01 (the PID gains) is shown scaled, in thousandths ("3.000e-3")
//! or, below 0.001, millionths ("40.000e-6"), the exponent written as its unit.
//!
//! **Read-only rows.** The bound link's values (`link.bind_id`, band, rate, channels,
//! telemetry ratio, protocol and the OpenLRSng bind data) are INFO rows: they are what the
//! bind agreed with the module, and a change would cut the link the tool talks over.
//! `link.dynamic_power` is not one of them: it changes the power only, from the next slot.

use core::fmt::Write;

use heapless::{String, Vec};
use telemetry::handset::crsf::params::{Entry, MAX_ENTRY_LEN};

use crate::settings::{Kind, PARAMS, Param, Settings, Value, Word};
use crate::vtx::{self, VtxChannel};
use telemetry::settings::COUNT;

/// The folders, in number order (folder `n` is number `n + 1`).
pub const FOLDERS: [&str; 10] = [
    "Rates",
    "Control",
    "Modes & Switches",
    "Failsafe",
    "Outputs",
    "Battery",
    "Sensors",
    "VTX",
    "Link",
    "Logging",
];
/// Number of the first setting (table index 0).
pub const SETTINGS_BASE: u8 = FOLDERS.len() as u8 + 1;
/// Command: save the live settings to flash (after a confirmation).
pub const SAVE: u8 = SETTINGS_BASE + COUNT as u8;
/// Command: open the bind window (as the console's `bind`).
pub const BIND: u8 = SAVE + 1;
/// Command: start a magnetometer calibration (as the console's `magcal start`).
pub const MAGCAL: u8 = SAVE + 2;
/// Info: what the last change from the radio did ("pid.roll.kp set", "refused: armed").
pub const LAST_CHANGE: u8 = SAVE + 3;
/// Info (VTX folder): the frequency the VTX transmits on.
pub const VTX_FREQUENCY: u8 = SAVE + 4;
/// Rows the device offers (DEVICE_INFO's count).
pub const PARAMETER_COUNT: u8 = VTX_FREQUENCY;

/// The rows' texts (one size: one formatting instance in the image).
pub type Text = String<40>;

/// A whole-number row whose range spans at most this is an unsigned 16 (one step a click);
/// a wider one a FLOAT with a coarser step.
pub const UINT16_MAX_SPAN: u32 = 1_000;

/// The folder number holding a setting, by its name's first part (0: the root).
pub fn folder_of(name: &str) -> u8 {
    let prefix = name.split('.').next().unwrap_or("");
    let index = match prefix {
        "rate" | "attitude" => 0,
        "pid" | "lqg" | "loop" => 1,
        "mode" | "arm" => 2,
        "failsafe" => 3,
        "output" | "mixer" => 4,
        "battery" => 5,
        "ins" | "mag" => 6,
        "vtx" => 7,
        "link" => 8,
        "log" => 9,
        _ => return 0,
    };
    index + 1
}

/// The folder number of the VTX rows.
pub const VTX_FOLDER: u8 = 8;

/// A setting's row, if `number` names one: its table index and row.
pub fn setting(number: u8) -> Option<(usize, &'static Param)> {
    let index = usize::from(number.checked_sub(SETTINGS_BASE)?);
    PARAMS.get(index).map(|p| (index, p))
}

/// Whether a setting is shown read-only (the bound link's values; dynamic power, which
/// changes no link parameter, stays writable).
pub fn read_only(param: &Param) -> bool {
    let dynamic_power = crate::settings::handles::LINK_DYNAMIC_POWER.param();
    param.name.starts_with("link.") && dynamic_power.is_none_or(|p| p.key != param.key)
}

/// The unit a name's last part implies (`…_hz` → "Hz").
fn base_unit(name: &str) -> &'static str {
    const UNITS: [(&str, &str); 9] = [
        ("_mv_per_a", "mV/A"),
        ("_hz", "Hz"),
        ("_us", "us"),
        ("_ms", "ms"),
        ("_mv", "mV"),
        ("_dps", "dps"),
        ("_deg", "deg"),
        ("_mps", "m/s"),
        ("_s", "s"),
    ];
    UNITS
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map_or("", |(_, unit)| unit)
}

/// How a real number travels as a CRSF FLOAT: the wire value is the number ×
/// 10^`power` rounded, shown with `decimals` decimals, `exponent` (0, −3, −6) written as
/// the unit so the radio shows at most three decimals yet every digit of a small gain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FloatScale {
    /// Decimals the radio shows.
    pub decimals: u8,
    /// Power of ten the shown number is in (0, −3, −6).
    pub exponent: i8,
}

const POW10: [f32; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

impl FloatScale {
    /// The scale for a row of `min..=max` and factory value `default`.
    pub fn for_range(min: f32, max: f32, default: f32) -> Self {
        let bound = min.abs().max(max.abs());
        let reference = if default != 0.0 { default.abs() } else { bound };
        let exponent: i8 = if reference >= 0.01 {
            0
        } else if reference >= 1e-3 {
            -3
        } else {
            -6
        };
        let mut decimals = 3u8;
        while decimals > 0 && bound * Self::power_of(decimals, exponent) > i32::MAX as f32 {
            decimals -= 1;
        }
        Self { decimals, exponent }
    }

    fn power_of(decimals: u8, exponent: i8) -> f32 {
        let power = usize::from(decimals) + usize::from(exponent.unsigned_abs());
        POW10.get(power).copied().unwrap_or(1e9)
    }

    fn power(self) -> f32 {
        Self::power_of(self.decimals, self.exponent)
    }

    /// The wire value of `v` (clamped into `i32`).
    pub fn to_wire(self, v: f32) -> i32 {
        let scaled = libm::roundf(v * self.power());
        if scaled >= i32::MAX as f32 {
            i32::MAX
        } else if scaled <= i32::MIN as f32 {
            i32::MIN
        } else {
            scaled as i32
        }
    }

    /// The number a wire value stands for.
    pub fn from_wire(self, raw: i32) -> f32 {
        raw as f32 / self.power()
    }

    /// The unit text: the exponent, then the base unit.
    fn unit(self, base: &str) -> Text {
        let mut text = Text::new();
        let _ = text.push_str(match self.exponent {
            -3 => "e-3",
            -6 => "e-6",
            _ => "",
        });
        let _ = text.push_str(base);
        text
    }
}

/// A step of about a tenth of `reference`'s magnitude, in wire units (at least 1).
fn step_for(reference: u32) -> u32 {
    let mut step = 1u32;
    while step.saturating_mul(100) <= reference {
        step = step.saturating_mul(10);
    }
    step
}

/// How a whole-number row travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WholeForm {
    /// CRSF UINT16.
    Uint16,
    /// CRSF FLOAT with no decimals.
    Float,
    /// Read-only text (beyond `i32`).
    Text,
}

/// The form of a whole-number row of `min..=max`.
pub fn whole_form(min: u32, max: u32) -> WholeForm {
    if max <= u32::from(u16::MAX) && max - min.min(max) <= UINT16_MAX_SPAN {
        WholeForm::Uint16
    } else if i32::try_from(max).is_ok() {
        WholeForm::Float
    } else {
        WholeForm::Text
    }
}

/// What the rows show beyond the settings.
#[derive(Debug, Clone, Copy, Default)]
pub struct View<'a> {
    /// This board drives a VTX (else the VTX folder and rows are hidden).
    pub has_vtx: bool,
    /// The row the last change named and the note its unit shows ("refused: armed").
    pub note: Option<(u8, &'a str)>,
}

impl View<'_> {
    fn unit(&self, number: u8, base: &str) -> Text {
        let mut text = Text::new();
        let _ = text.push_str(base);
        if let Some((n, note)) = self.note
            && n == number
        {
            let _ = write!(text, " ({})", Word(note));
        }
        text
    }
}

/// The description of folder or setting `number` (`None`: not one of them).
pub fn entry(number: u8, settings: &Settings, view: &View) -> Option<Vec<u8, MAX_ENTRY_LEN>> {
    let entry = if let Some(name) = number
        .checked_sub(1)
        .and_then(|i| FOLDERS.get(usize::from(i)))
    {
        let folder = Entry::folder(0, name);
        if number == VTX_FOLDER && !view.has_vtx {
            folder.hidden()
        } else {
            folder
        }
    } else {
        let (index, param) = setting(number)?;
        let value = settings.iter().nth(index).map(|(_, v)| v)?;
        let row = setting_entry(number, param, value, settings, view)?;
        if param.name.starts_with("vtx.") && !view.has_vtx {
            row.hidden()
        } else {
            row
        }
    };
    entry.finish().ok()
}

fn setting_entry(
    number: u8,
    param: &Param,
    value: Value,
    settings: &Settings,
    view: &View,
) -> Option<Entry> {
    let parent = folder_of(param.name);
    let name = param.name;
    let unit = view.unit(number, base_unit(name));
    if read_only(param) {
        return Some(Entry::info(parent, name, &value_text(param, value)?));
    }
    if name == "vtx.channel" {
        return Some(vtx_channel_entry(parent, value, settings, &unit));
    }
    Some(match (param.kind, value, param.default) {
        (Kind::Choice(names), Value::U32(v), Value::U32(d)) => Entry::selection(
            parent,
            name,
            names,
            u8::try_from(v).ok()?,
            u8::try_from(d).ok()?,
            &unit,
        ),
        (Kind::U32 { min, max }, Value::U32(v), Value::U32(d)) => match whole_form(min, max) {
            WholeForm::Uint16 => Entry::uint16(
                parent,
                name,
                u16::try_from(v).ok()?,
                u16::try_from(min).ok()?,
                u16::try_from(max).ok()?,
                u16::try_from(d).ok()?,
                &unit,
            ),
            WholeForm::Float => Entry::float(
                parent,
                name,
                i32::try_from(v).ok()?,
                (i32::try_from(min).ok()?, i32::try_from(max).ok()?),
                i32::try_from(d).ok()?,
                0,
                step_for(d.max(1)),
                &unit,
            ),
            WholeForm::Text => Entry::info(parent, name, &value_text(param, value)?),
        },
        (Kind::F32 { min, max }, Value::F32(v), Value::F32(d)) => {
            let scale = FloatScale::for_range(min, max, d);
            let reference = if d != 0.0 { d.abs() } else { max.abs() };
            let unit = view.unit(number, &scale.unit(base_unit(name)));
            Entry::float(
                parent,
                name,
                scale.to_wire(v),
                (scale.to_wire(min), scale.to_wire(max)),
                scale.to_wire(d),
                scale.decimals,
                step_for(scale.to_wire(reference).unsigned_abs()),
                &unit,
            )
        }
        _ => return None,
    })
}

/// "1 5725MHz;2 5745MHz;…" for the settings' band: the channel row shows frequencies.
/// (Numbers as `u32`, the console's one unsigned formatter: `app::console`.)
fn vtx_channel_entry(parent: u8, value: Value, settings: &Settings, unit: &str) -> Entry {
    let band = VtxChannel::from_settings(settings).band;
    let mut labels: Vec<Text, { vtx::CHANNELS as usize }> = Vec::new();
    for channel in 1..=vtx::CHANNELS {
        let mut label = String::new();
        let _ = write!(
            label,
            "{} {}MHz",
            u32::from(channel),
            u32::from(vtx::frequency_mhz(band, channel).unwrap_or(0))
        );
        let _ = labels.push(label);
    }
    let options: Vec<&str, { vtx::CHANNELS as usize }> =
        labels.iter().map(String::as_str).collect();
    let index = match value {
        Value::U32(channel) => u8::try_from(channel.saturating_sub(1)).unwrap_or(0),
        Value::F32(_) => 0,
    };
    Entry::selection(parent, "vtx.channel", &options, index, 0, unit)
}

/// A whole value as text (read-only rows): a choice's name, a number.
pub fn value_text(param: &Param, value: Value) -> Option<Text> {
    let mut text = Text::new();
    match (param.kind, value) {
        (Kind::Choice(names), Value::U32(v)) => {
            text.push_str(names.get(usize::try_from(v).ok()?)?).ok()?
        }
        (_, Value::U32(v)) if param.name.ends_with("_id") || v > i32::MAX as u32 => {
            write!(text, "{v:#010x}").ok()?
        }
        (_, Value::U32(v)) => write!(text, "{v}").ok()?,
        // Every read-only row is a whole number or a choice (no float formatting linked).
        (_, Value::F32(_)) => return None,
    }
    Some(text)
}

/// The value a radio's write of `bytes` to setting `param` means, as the row's type
/// carries it (a selection index, a big-endian u16, a big-endian i32 FLOAT); `None` for a
/// write of the wrong length or a read-only row.
pub fn written_value(param: &Param, bytes: &[u8]) -> Option<Value> {
    if read_only(param) {
        return None;
    }
    if param.name == "vtx.channel" {
        let [index] = bytes else { return None };
        return Some(Value::U32(u32::from(*index) + 1));
    }
    match (param.kind, param.default, bytes) {
        (Kind::Choice(_), _, [index]) => Some(Value::U32(u32::from(*index))),
        (Kind::U32 { min, max }, _, _) => match (whole_form(min, max), bytes) {
            (WholeForm::Uint16, [h, l]) => {
                Some(Value::U32(u32::from(u16::from_be_bytes([*h, *l]))))
            }
            (WholeForm::Float, [a, b, c, d]) => u32::try_from(i32::from_be_bytes([*a, *b, *c, *d]))
                .ok()
                .map(Value::U32),
            _ => None,
        },
        (Kind::F32 { min, max }, Value::F32(default), [a, b, c, d]) => {
            let scale = FloatScale::for_range(min, max, default);
            Some(Value::F32(
                scale.from_wire(i32::from_be_bytes([*a, *b, *c, *d])),
            ))
        }
        _ => None,
    }
}

/// The VTX frequency row's text.
pub fn vtx_frequency_text(settings: &Settings) -> Text {
    let vtx = VtxChannel::from_settings(settings);
    let mut text = Text::new();
    let _ = write!(
        text,
        "{} MHz ({} {})",
        u32::from(vtx.frequency_mhz()),
        Word(vtx.band.label()),
        u32::from(vtx.channel)
    );
    text
}
