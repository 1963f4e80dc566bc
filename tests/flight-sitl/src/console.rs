//! The USB console adapter as the simulator drives it: bytes typed at the flight controller
//! go through the firmware's line assembler (`settings::LineAssembler`, 96 bytes, as the
//! firmware's console task) into the application's own console
//! (`FlightApp::on_console_input`), exactly the calls the firmware task makes.

use flight_app::app::FlightApp;
use flight_app::settings::LineAssembler;

/// The firmware console's line buffer, bytes.
pub const LINE_BUFFER: usize = 96;

/// Feeds `bytes` to the console of `app`; returns one reply per finished line.
pub fn type_into_console(app: &mut FlightApp, bytes: &[u8]) -> Vec<String> {
    let mut lines: LineAssembler<LINE_BUFFER> = LineAssembler::new();
    let mut replies = Vec::new();
    for &b in bytes {
        let Some(line) = lines.push(b) else {
            continue;
        };
        let mut out = String::new();
        // Writing into a String cannot fail.
        let _ = app.on_console_input(line.as_ref().map(|l| l.as_str()), &mut out);
        replies.push(out);
    }
    replies
}
