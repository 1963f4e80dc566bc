//! The USB console as the simulator drives it: bytes typed at the flight controller go
//! through the same `settings::LineAssembler` (96 bytes, as the firmware's) and command
//! parser as on the board, and setting commands through the same `Settings` methods, so
//! tests see what a pilot at the console sees for `set`. Only the setting commands are
//! served; the rest (`status`, `save`, …) belong to the firmware's tasks.

use std::fmt::Write;

use flight_core::settings::{Command, LineAssembler, Settings, parse_line, write_setting};

/// The firmware console's line buffer, bytes.
pub const LINE_BUFFER: usize = 96;

/// Feeds `bytes` to a console on `settings`; returns one reply per finished line.
pub fn type_into_console(settings: &mut Settings, bytes: &[u8]) -> Vec<String> {
    let mut lines: LineAssembler<LINE_BUFFER> = LineAssembler::new();
    let mut replies = Vec::new();
    for &b in bytes {
        let Some(line) = lines.push(b) else {
            continue;
        };
        let mut out = String::new();
        let _ = match line {
            Err(e) => writeln!(out, "{e}"),
            Ok(line) => match parse_line(line.as_str()) {
                Ok(Command::Set { name, value }) => match settings.set_text(name, value) {
                    Ok(()) => write_setting(&mut out, settings, name),
                    Err(e) => writeln!(out, "{e}"),
                },
                Ok(Command::SetAll(pairs)) => match settings.set_text_pairs(pairs) {
                    Ok(()) => writeln!(out, "ok"),
                    Err(e) => writeln!(out, "{e}"),
                },
                Ok(Command::Get(name)) => write_setting(&mut out, settings, name),
                Ok(Command::Nothing) => Ok(()),
                Ok(_) => writeln!(out, "not simulated"),
                Err(e) => writeln!(out, "{e}"),
            },
        };
        replies.push(out);
    }
    replies
}
