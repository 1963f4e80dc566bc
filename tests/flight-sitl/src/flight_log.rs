//! The flight log as the simulated board keeps it: each boot's `FlightApp` log entries,
//! drained after every loop as the firmware's logging task drains them, encoded with the
//! flight core's own `logging::Encoder` into one ULog file per boot. What `--log FILE.ulg`
//! writes, and what the tests read back with `taulink_ulog::Reader` and pyulog.

use flight_app::app::FlightApp;
use flight_app::logging::{Encoder, MIN_BUFFER};
use taulink_ulog::Writer;

/// The `ver_hw` of a simulated board's logs.
pub const SITL_BOARD: &str = "flight-sitl";

/// One boot's log file, growing.
#[derive(Debug, Clone)]
pub struct LogFile {
    encoder: Encoder,
    bytes: Vec<u8>,
}

impl LogFile {
    /// A log starting at the board's `start_us`.
    pub fn new(start_us: u64) -> Self {
        Self {
            encoder: Encoder::new(start_us, SITL_BOARD),
            bytes: Vec::new(),
        }
    }

    /// Moves every waiting entry of `app` into the file.
    pub fn drain(&mut self, app: &mut FlightApp) {
        let mut buf = [0u8; MIN_BUFFER];
        loop {
            let mut w = Writer::new(&mut buf);
            let settings = app.settings().clone();
            let more = self
                .encoder
                .feed(&mut w, &settings, || app.take_log_entry());
            self.bytes.extend_from_slice(w.written());
            if !more {
                return;
            }
        }
    }

    /// The file's bytes so far.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The file's bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }
}
