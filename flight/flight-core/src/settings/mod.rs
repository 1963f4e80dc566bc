//! The flight controller's settings: its values over the schema's table of typed,
//! range-checked parameters (`telemetry::settings`: gains, costs, output type and rate, mixer,
//! thresholds — what the link, the console and the ground station name alike), whether a set
//! can run, their power-fail-safe storage in flash, and the text console that reads and
//! changes them over USB.

mod console;
pub use float_text as decimal;
mod line;
mod params;
mod store;

pub use console::{
    Command, ConsoleError, MagcalAction, Signed, Word, parse_line, write_list, write_setting,
};
pub use line::{LineAssembler, LineError};
pub use params::{MAX_PAIRS, ParamError, ParamText, Settings};
pub use store::{
    FLASH_BUFFER, LoadProblem, LoadReport, StoreError, load, load_at_boot, save, save_whole,
};
pub use store::{RECORD_MAX, crc32, crc32_words, decode as decode_record, record};
pub use telemetry::settings::{
    Change, Choice, Handle, Kind, PARAMS, Param, ParamType, Value, ValueError, handles,
};
