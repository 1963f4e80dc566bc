//! The application side of both link ends in the SITL: the module's master hooks (pilot
//! channels up, setting changes up, telemetry decoded) and the flight side's follower hooks
//! (channels and failsafe out to the flight task, telemetry reports down, setting changes
//! applied and echoed) — what the firmware's link task does, on shared host state.

use std::cell::RefCell;
use std::rc::Rc;

use flight_core::report::{LinkSeen, Reporter, Snapshot, apply_setting};
use flight_core::settings::Settings;
use flight_core::supervisor::FlightMode;
use telemetry::channels::Channels;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::FollowerHooks;
use telemetry::link::master::MasterHooks;
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SettingChange, SysIdResult, encode_message,
};

/// The module's clock reads virtual time plus this (the ends count from different epochs).
pub(crate) const MODULE_CLOCK_OFFSET_US: u64 = 1_000_000;

/// What the two link ends share with the flight task.
#[derive(Default)]
pub(crate) struct LinkState {
    /// Channels the pilot's transmitter sends (master side).
    pub(crate) tx: Option<Channels>,
    /// Channels the follower outputs.
    pub(crate) rx: Option<Channels>,
    /// The follower is in failsafe.
    pub(crate) failsafe: bool,
    /// The flight side's latest state, for its telemetry reports.
    pub(crate) snapshot: Option<Snapshot>,
    /// Messages the module decoded from the downlink stream, with the time (s).
    pub(crate) module_rx: Vec<(f64, Message)>,
    /// Setting changes the module is to send up.
    pub(crate) uplink: Vec<SettingChange>,
    /// The flight side's settings (changes from the module land here).
    pub(crate) settings: Settings,
    /// Identification results waiting for the downlink.
    pub(crate) sysid: Vec<SysIdResult>,
}

pub(crate) type Shared = Rc<RefCell<LinkState>>;

/// Bytes of stream room one framed message needs.
const MESSAGE_ROOM: usize = FRAMED_MAX_BYTES;

fn send(stream: &mut impl FnMut(&[u8]) -> usize, free: usize, m: &Message) -> bool {
    let mut buf = [0u8; FRAMED_MAX_BYTES];
    match encode_message(m, &mut buf) {
        Ok(n) if n <= free => stream(buf.get(..n).unwrap_or(&[])) == n,
        _ => false,
    }
}

pub(crate) struct ModuleSide {
    pub(crate) shared: Shared,
    pub(crate) reader: MessageReader,
}

impl MasterHooks for ModuleSide {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let mut s = self.shared.borrow_mut();
        if let Some(ch) = s.tx {
            master.set_channels(&ch);
        }
        if let Some(change) = s.uplink.first().copied() {
            let free = master.uplink_stream.free();
            if send(
                &mut |b| master.uplink_stream.write(b),
                free,
                &Message::SettingChange(change),
            ) {
                s.uplink.remove(0);
            }
        }
        let mut buf = [0u8; 64];
        loop {
            let n = master.downlink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for b in buf.iter().take(n) {
                if let Some(Decoded::Message(m)) = self.reader.push(*b) {
                    s.module_rx
                        .push(((now_us - MODULE_CLOCK_OFFSET_US) as f64 * 1e-6, m));
                }
            }
        }
    }
}

pub(crate) struct FlightSide {
    shared: Shared,
    reporter: Reporter,
    reader: MessageReader,
    echo: Vec<SettingChange>,
    last_report_us: u64,
    last_state: Option<(bool, bool, FlightMode)>,
}

impl FlightSide {
    /// Hooks on `shared`, nothing reported yet.
    pub(crate) fn new(shared: Shared) -> Self {
        Self {
            shared,
            reporter: Reporter::new(),
            reader: MessageReader::new(),
            echo: Vec::new(),
            last_report_us: 0,
            last_state: None,
        }
    }
}

/// Telemetry report period on the flight side, µs.
const REPORT_PERIOD_US: u64 = 20_000;

impl FollowerHooks for FlightSide {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let mut s = self.shared.borrow_mut();
        s.rx = Some(*follower.output());
        s.failsafe = follower.in_failsafe();
        let mut buf = [0u8; 64];
        loop {
            let n = follower.uplink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for b in buf.iter().take(n) {
                if let Some(Decoded::Message(Message::SettingChange(c))) = self.reader.push(*b) {
                    let (_, echo) = apply_setting(&mut s.settings, c);
                    self.echo.extend(echo);
                }
            }
        }
        if now_us.saturating_sub(self.last_report_us) < REPORT_PERIOD_US {
            return;
        }
        let Some(mut snap) = s.snapshot else {
            return;
        };
        snap.sysid = s.sysid.first().copied();
        let counters = follower.counters();
        snap.link = LinkSeen {
            rssi_dbm: follower
                .uplink_rssi_dbm()
                .map_or(0, |r| i8::try_from(r).unwrap_or(i8::MIN)),
            lq_percent: follower.uplink_lq(),
            downlink: follower.remote_report().map(|r| (r.rssi_dbm, r.lq_percent)),
            rate_mode: follower.params().rate.code(),
            received: counters.received,
            missed: counters.missed,
            failsafes: 0,
        };
        // Keep at most one message queued: the stream is reliable, so anything more only
        // adds latency (stale attitude) when the downlink slows.
        let free = follower.downlink_stream.free();
        if free < MESSAGE_ROOM || follower.downlink_stream.pending() > 0 {
            return;
        }
        self.last_report_us = now_us;
        let state = (snap.out.armed, snap.out.failsafe, snap.out.mode);
        let m = if let Some(c) = self.echo.first().copied() {
            self.echo.remove(0);
            Message::SettingChange(c)
        } else if let Some(r) = snap.sysid {
            s.sysid.remove(0);
            Message::SysIdResult(r)
        } else if self.last_state != Some(state) {
            // A state change goes out of turn.
            self.last_state = Some(state);
            Reporter::state(&snap)
        } else {
            self.reporter.next(&snap)
        };
        send(&mut |b| follower.downlink_stream.write(b), free, &m);
    }
}
