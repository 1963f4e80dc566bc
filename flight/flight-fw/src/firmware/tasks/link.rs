//! Owns the RFM22B and runs the TauLink follower on it (`telemetry::link`). After every slot:
//! the channels become the loop's `LinkInput` (sticks, arm and mode switches; "up" only while
//! the link is out of failsafe), setting changes from the module are applied (disarmed only)
//! and echoed, and one telemetry message goes down when the stream is empty (attitude,
//! battery, link statistics, flight mode, arm/failsafe state, identification results; state
//! changes out of turn).
//!
//! Binding: for `BIND_WINDOW_US` after boot the follower listens for a bind offer (start the
//! module's bind, then power the flight controller). A bind is stored in the settings
//! (`link.*`) and saved, so later boots find the same module; a never-bound controller uses
//! the compiled-in link (`DEFAULT_BIND_ID`).

use core::sync::atomic::Ordering;

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::battery::BatteryStatus;
use flight_core::pipeline::{ChannelMap, store_link, stored_link};
use flight_core::report::{LinkSeen, Reporter, Snapshot, apply_setting, sysid_messages};
use flight_core::supervisor::FlightMode;
use radio_rfm22b::Rfm22b;
use telemetry::channels::{ChannelFormat, FailsafeValues};
use telemetry::link::core::Follower;
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};
use telemetry::link::{Band, LinkParams, RateMode};
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SettingChange, SysIdResult, encode_message,
};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;
use crate::firmware::link_radio::{EmbassyClock, LinkRadio};
use crate::firmware::signals::{
    ARMED, BATTERY, FLIGHT_STATE, LINK_INPUT, SAVE_REQUEST, SETTINGS, SETTINGS_CHANGED, SYSID,
};
use radio_rfm22b::TxPower;

/// How long the follower listens for a bind offer after boot.
const BIND_WINDOW_US: u64 = 3_000_000;
/// The link used when nobody binds (both ends built with it).
const DEFAULT_BIND_ID: u32 = 0x7A11_0001;
/// The follower declares failsafe after this long without a valid packet.
const FAILSAFE_US: u64 = 500_000;
/// Telemetry message period, µs.
const REPORT_PERIOD_US: u64 = 20_000;

/// What the hooks keep between slots.
struct FlightHooks {
    map: ChannelMap,
    reporter: Reporter,
    reader: MessageReader,
    pending_change: Option<SettingChange>,
    echo: Option<SettingChange>,
    last_report_us: u64,
    last_state: Option<(bool, bool, FlightMode)>,
    failsafes: u16,
    was_failsafe: bool,
    /// Identification results (roll, pitch, yaw) still to send.
    sysid: heapless::Deque<SysIdResult, 3>,
}

impl FlightHooks {
    fn new() -> Self {
        Self {
            map: ChannelMap::default(),
            reporter: Reporter::new(),
            reader: MessageReader::new(),
            pending_change: None,
            echo: None,
            last_report_us: 0,
            last_state: None,
            failsafes: 0,
            was_failsafe: false,
            sysid: heapless::Deque::new(),
        }
    }

    /// Applies a change from the module while disarmed; echoes the resulting value.
    fn apply_pending(&mut self) {
        let Some(change) = self.pending_change else {
            return;
        };
        let Ok(mut guard) = SETTINGS.try_lock() else {
            return; // console or storage busy: next slot
        };
        self.pending_change = None;
        let Some((settings, _)) = guard.as_mut() else {
            return;
        };
        if ARMED.load(Ordering::Relaxed) {
            self.echo = flight_core::report::setting_report(settings, change.id);
            return;
        }
        let (result, echo) = apply_setting(settings, change);
        if result.is_ok() {
            SETTINGS_CHANGED.signal(());
        }
        self.echo = echo;
    }

    fn report(&mut self, follower: &mut Follower) {
        let stream = &mut follower.downlink_stream;
        if stream.pending() > 0 || stream.free() < FRAMED_MAX_BYTES {
            return; // one message in flight at most: stale telemetry helps nobody
        }
        let Some((out, arming_blockers)) = FLIGHT_STATE.lock(|c| c.get()) else {
            return;
        };
        let counters = follower.counters();
        let snap = Snapshot {
            out,
            battery: BATTERY.try_get().map(|b: BatteryStatus| b),
            link: LinkSeen {
                rssi_dbm: follower
                    .uplink_rssi_dbm()
                    .map_or(0, |r| i8::try_from(r).unwrap_or(i8::MIN)),
                lq_percent: follower.uplink_lq(),
                downlink: follower.remote_report().map(|r| (r.rssi_dbm, r.lq_percent)),
                rate_mode: follower.params().rate.code(),
                received: counters.received,
                missed: counters.missed,
                failsafes: self.failsafes,
            },
            arming_blockers,
            sysid: self.sysid.front().copied(),
        };
        let state = (out.armed, out.failsafe, out.mode);
        let message = if let Some(c) = self.echo.take() {
            Message::SettingChange(c)
        } else if let Some(r) = self.sysid.pop_front() {
            Message::SysIdResult(r)
        } else if self.last_state != Some(state) {
            self.last_state = Some(state);
            flight_core::report::Reporter::state(&snap)
        } else {
            self.reporter.next(&snap)
        };
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        if let Ok(n) = encode_message(&message, &mut buf) {
            follower
                .downlink_stream
                .write(buf.get(..n).unwrap_or_default());
        }
    }
}

impl FollowerHooks for FlightHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        check_in(Watched::Link);
        let failsafe = follower.in_failsafe();
        if failsafe && !self.was_failsafe {
            self.failsafes = self.failsafes.saturating_add(1);
        }
        self.was_failsafe = failsafe;
        let input = self.map.link_input(follower.output(), !failsafe);
        LINK_INPUT.lock(|c| c.set(input));
        let mut buf = [0u8; 32];
        loop {
            let n = follower.uplink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for b in buf.iter().take(n) {
                if let Some(Decoded::Message(Message::SettingChange(c))) = self.reader.push(*b) {
                    self.pending_change = Some(c);
                }
            }
        }
        self.apply_pending();
        if let Some(id) = SYSID.try_take() {
            self.sysid.clear();
            for r in sysid_messages(&id) {
                // Capacity 3 after the clear: cannot fail.
                let _ = self.sysid.push_back(r);
            }
        }
        if now_us.saturating_sub(self.last_report_us) >= REPORT_PERIOD_US {
            self.last_report_us = now_us;
            self.report(follower);
        }
    }
}

/// Checks in while a bounded wait (the bind window) runs.
async fn keep_alive() -> core::convert::Infallible {
    loop {
        check_in(Watched::Link);
        Timer::after(Duration::from_millis(50)).await;
    }
}

#[embassy_executor::task]
pub async fn link_task(radio: Radio) {
    let Radio { spi, nsel, nirq } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, nsel);
    // SDN is tied low on these boards: software reset only.
    let mut radio = LinkRadio::new(Rfm22b::new_without_sdn(device, nirq, Delay), TxPower::MAX);
    let mut clock = EmbassyClock;
    let mut hooks = FlightHooks::new();
    let stored = SETTINGS
        .lock()
        .await
        .as_ref()
        .and_then(|(live, _)| stored_link(live));
    let mut params = stored.unwrap_or_else(|| {
        LinkParams::new(
            DEFAULT_BIND_ID,
            Band::Mhz433,
            RateMode::F250,
            ChannelFormat::Full16,
            4,
        )
    });
    let mut bind_window = true;
    loop {
        check_in(Watched::Link);
        if bind_window {
            let bind = bind_follower(&mut radio, &mut clock, params.band, BIND_WINDOW_US);
            match select(bind, keep_alive()).await {
                Either::First(Ok(Some(offered))) => {
                    info!("bound to link {:08x}", offered.bind_id);
                    params = offered;
                    if let Some((live, _)) = SETTINGS.lock().await.as_mut()
                        && store_link(live, &offered).is_ok()
                    {
                        // Saved now, while still disarmed at boot.
                        SAVE_REQUEST.signal(());
                    }
                    bind_window = false;
                }
                Either::First(Ok(None)) => bind_window = false,
                Either::First(Err(e)) => {
                    warn!("radio: {}", e);
                    let _ = select(Timer::after(Duration::from_secs(1)), keep_alive()).await;
                    continue;
                }
            }
        }
        let mut follower = Follower::new(params, FailsafeValues::default(), FAILSAFE_US);
        let Err(e) = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        // The radio failed (unplugged, bus fault): failsafe the loop and retry in a second.
        warn!("link stopped: {}", e);
        LINK_INPUT.lock(|c| {
            let mut input = c.get();
            input.up = false;
            c.set(input);
        });
        let _ = select(Timer::after(Duration::from_secs(1)), keep_alive()).await;
    }
}
