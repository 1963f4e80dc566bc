//! The flight controller's settings: a table of typed, range-checked parameters (gains,
//! costs, output type and rate, mixer, thresholds), their power-fail-safe storage in flash,
//! and the text console that reads and changes them over USB.

mod console;
pub use float_text as decimal;
mod handle;
mod line;
mod params;
mod store;

pub use console::{Command, ConsoleError, MagcalAction, parse_line, write_list, write_setting};
pub use handle::{Change, Handle, ParamType};
pub use line::{LineAssembler, LineError};
pub use params::{
    COUNT, Choice, Kind, LOG_PROFILES, MAX_PAIRS, MODES, PARAMS, Param, ParamError, Settings,
    Value, handles,
};
pub use store::{
    FLASH_BUFFER, LoadProblem, LoadReport, StoreError, load, load_at_boot, save, save_whole,
};
