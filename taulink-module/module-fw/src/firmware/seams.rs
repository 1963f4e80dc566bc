//! SEAMS: where code from other branches plugs into this firmware. Nothing here pretends to
//! be finished; each item says what is missing and who delivers it.
//!
//! * Link (telemetry::link over radio-rfm22b, branches `link` and `radio-driver`): a link
//!   task will take [`LINK_CHANNELS`], drain [`LinkSeam::take_uplink_record`], publish
//!   [`LINK_STATS`], act on [`BIND_REQUEST`] and feed received records to
//!   `App::on_link_record` / `App::on_link_channels`. Until then the radio task only probes
//!   the chip, the stats say "not connected" and nothing goes on air.
//! * Handset codecs (telemetry::handset, branch `handset-protocols`): the CRSF decoder will
//!   consume [`HandsetSeam::on_jr_bytes`] and call `App::on_handset_channels`; the CRSF,
//!   S.Port and FrSky-D encoders will fill the frames [`HandsetSeam::next_jr_frame`] hands to
//!   the JR-line task. Until then that queue stays empty and the line only listens.

use core::cell::Cell;
use core::sync::atomic::AtomicBool;

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use module_core::channels::Channels;
use module_core::hm10::RecordQueue;
use module_core::ports::{HandsetOutput, LinkPort, LinkStats};

/// Latest channels for the link task (transmitter role).
pub static LINK_CHANNELS: Signal<CriticalSectionRawMutex, Channels> = Signal::new();
/// Statistics the link task publishes.
pub static LINK_STATS: Mutex<CriticalSectionRawMutex, Cell<LinkStats>> =
    Mutex::new(Cell::new(LinkStats {
        connected: false,
        rssi_dbm: 0,
        link_quality_percent: 0,
    }));
/// Set by a long press; the link task starts binding and clears it.
pub static BIND_REQUEST: AtomicBool = AtomicBool::new(false);

/// Records from the phone waiting for the link (4 × 64 bytes).
const UPLINK_RECORDS: usize = 4;

/// The core's view of the link.
pub struct LinkSeam {
    uplink: RecordQueue<256, UPLINK_RECORDS>,
}

impl LinkSeam {
    /// An idle link seam.
    pub const fn new() -> Self {
        Self {
            uplink: RecordQueue::new(64),
        }
    }

    /// For the link task: the next record for the other end.
    #[expect(dead_code, reason = "SEAM: the link task (branch `link`) will call it")]
    pub fn take_uplink_record(&mut self, out: &mut [u8]) -> Option<usize> {
        self.uplink.pop_into(out).ok().flatten()
    }
}

impl LinkPort for LinkSeam {
    fn send_channels(&mut self, channels: &Channels) {
        LINK_CHANNELS.signal(*channels);
    }

    fn can_send_record(&self) -> bool {
        self.uplink.len() < UPLINK_RECORDS
    }

    fn send_record(&mut self, record: &[u8]) {
        self.uplink.push(record);
    }

    fn stats(&self) -> LinkStats {
        LINK_STATS.lock(Cell::get)
    }

    fn start_bind(&mut self) {
        BIND_REQUEST.store(true, core::sync::atomic::Ordering::Relaxed);
    }
}

/// The core's view of the handset codecs.
pub struct HandsetSeam {
    /// Link statistics last handed over (what LINK_STATISTICS / RSSI frames will carry).
    pub latest_stats: LinkStats,
    /// Telemetry records received with no encoder to take them yet.
    pub records_unencoded: u32,
    /// Bytes received on the JR line with no decoder to take them yet.
    pub jr_bytes_undecoded: u32,
}

impl HandsetSeam {
    /// An empty seam.
    pub const fn new() -> Self {
        Self {
            latest_stats: LinkStats {
                connected: false,
                rssi_dbm: 0,
                link_quality_percent: 0,
            },
            records_unencoded: 0,
            jr_bytes_undecoded: 0,
        }
    }

    /// Bytes from the radio on the JR line (CRSF). Counted only: the decoder is missing.
    pub fn on_jr_bytes(&mut self, bytes: &[u8]) {
        self.jr_bytes_undecoded = self
            .jr_bytes_undecoded
            .saturating_add(u32::try_from(bytes.len()).unwrap_or(u32::MAX));
    }

    /// The next frame for the JR line. Always `None`: the encoders are missing.
    pub fn next_jr_frame(&mut self, _out: &mut [u8]) -> Option<usize> {
        None
    }
}

impl HandsetOutput for HandsetSeam {
    fn on_telemetry(&mut self, _record: &[u8]) {
        self.records_unencoded = self.records_unencoded.saturating_add(1);
    }

    fn on_link_stats(&mut self, stats: &LinkStats, _now_ms: u32) {
        self.latest_stats = *stats;
    }
}
