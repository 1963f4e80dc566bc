//! The module core's side of the air link (`telemetry::link`): link parameters from the
//! settings, and [`AirLink`], the [`LinkPort`] the core talks to. The firmware's link task
//! runs the link's master (transmitter role) or follower (receiver role) loop and, from the
//! loop's hook, hands the state machine to [`AirLink::on_master_slot`] /
//! [`AirLink::on_follower_step`], which exchange channels, telemetry records and statistics.
//!
//! In the transmitter role the master sends the handset's channels only while they are
//! fresh: when no channels came from the handset for the input timeout (setting
//! `input_timeout_ms`), every uplink carries the link's input-lost flag and the follower
//! flies its failsafe at once (`telemetry::link::core::Master::set_input_lost`). Freshness
//! is taken at slot starts on the link clock, so it lags the input by less than a slot.
//!
//! Both roles run the link's dynamic transmit power (`telemetry::link::power`) from the
//! other end's reports, capped by the settings' TX power; the loop writes the step the state
//! machine is given into the radio between slots, and the statistics carry it to the handset.
//!
//! Records travel in the link's telemetry stream as `telemetry::framing` frames
//! (`crate::records`); a record that does not fit the stream now waits in a bounded queue.

pub mod openlrs;

use telemetry::channels::{CHANNEL_CENTER, ChannelFormat};
use telemetry::link::LinkParams;
use telemetry::link::RateMode;
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, Master};
use telemetry::link::master::uplink_latch_offset_us;
use telemetry::link::power::{PowerControl, PowerInput};
#[cfg(test)]
use telemetry::link::rate::TX_LEAD_US;
#[cfg(test)]
use telemetry::link::rate::{PLL_SETTLE_US, TX_SETUP_US};
use telemetry::link::stream::{StreamReceiver, StreamSender};

use crate::channels::ChannelFrame;
use crate::hm10::RecordQueue;
use crate::hm10::relay::MAX_RECORD_LEN;
use crate::ports::{AirSchedule, LinkPort, LinkStats};
use crate::records::{self, MAX_STREAM_FRAME_LEN, Splitter, to_stream};
use crate::settings::Settings;

/// The master counts the link as up while a downlink arrived within this time.
pub const CONNECTED_TIMEOUT_US: u64 = 500_000;
/// Records from the phone waiting for room in the uplink stream.
const UPLINK_RECORDS: usize = 8;
/// Records received over the air waiting for the core.
const RECEIVED_RECORDS: usize = 16;

/// The bound link's parameters (`None` while unbound, or bound without a key while the
/// unauthenticated setting is off): the settings' band, rate mode and telemetry ratio, 16
/// channels.
pub fn link_params(settings: &Settings) -> Option<LinkParams> {
    // A link without an agreed key runs only by the explicit setting (spec §12.1).
    let runnable = settings.link_key.is_some() || settings.plain;
    (settings.bind_id != 0 && runnable).then(|| LinkParams {
        bind_id: settings.bind_id,
        band: settings.band,
        rate: settings.rate,
        // 16 channels; at F700 in its stick format (as the bind offered them).
        format: telemetry::link::bind::format_for(settings.rate, ChannelFormat::Full16),
        telemetry_ratio: settings.telemetry_ratio,
    })
}

/// The key of the link the module runs with `settings` under radio model `model` (model
/// match): in the transmitter role the module's key for that link's bind ID
/// (`LinkKey::for_link`: each model's link its own), in the receiver role the key the master
/// handed over; `None` without one (not bound, or bound unauthenticated).
pub fn link_key(settings: &Settings, model: Option<u8>) -> Option<telemetry::link::LinkKey> {
    let key = settings.link_key?;
    match settings.role {
        crate::settings::Role::Receiver => Some(key),
        crate::settings::Role::Transmitter => {
            let params = link_params(settings)?;
            let params = model.map_or(params, |m| params.for_model(m));
            Some(key.for_link(params.bind_id))
        }
    }
}

/// Parameters for a new bind: the settings' band, rate and telemetry ratio with a fresh ID
/// from `random`.
pub fn new_bind_params(settings: &Settings, random: u32) -> LinkParams {
    LinkParams::new(
        random,
        settings.band,
        settings.rate,
        ChannelFormat::Full16,
        settings.telemetry_ratio,
    )
}

/// The link as the core sees it; filled and drained by the link loop's hook.
#[derive(Debug)]
pub struct AirLink {
    channels: Option<ChannelFrame>,
    /// Channels arrived since the last master slot.
    input_fresh: bool,
    /// Slot start (link clock) at which the newest channels were first seen.
    last_input_us: Option<u64>,
    input_timeout_us: u64,
    input_lost: bool,
    input_losses: u32,
    uplink: RecordQueue<512, UPLINK_RECORDS>,
    received: RecordQueue<1024, RECEIVED_RECORDS>,
    received_channels: Option<ChannelFrame>,
    splitter: Splitter,
    stats: LinkStats,
    bind_requested: bool,
    follower_updates: u32,
    rejected_records: u32,
    /// OpenLRSng: when the last downlink frame arrived.
    last_downlink_us: Option<u64>,
    /// OpenLRSng: the receiver's last link report (RSSI dBm, LQ %).
    openlrs_remote: Option<(i16, u8)>,
    /// Dynamic transmit power (the core sets its limits from the settings).
    power: PowerControl,
}

impl Default for AirLink {
    fn default() -> Self {
        Self::new()
    }
}

impl AirLink {
    /// A link with nothing exchanged yet.
    pub const fn new() -> Self {
        Self {
            channels: None,
            input_fresh: false,
            last_input_us: None,
            input_timeout_us: crate::settings::DEFAULT_INPUT_TIMEOUT_MS as u64 * 1_000,
            // Nothing from the handset yet: no channels are flown.
            input_lost: true,
            input_losses: 0,
            uplink: RecordQueue::new(MAX_RECORD_LEN),
            received: RecordQueue::new(MAX_RECORD_LEN),
            received_channels: None,
            splitter: Splitter::new(),
            stats: LinkStats {
                connected: false,
                rssi_dbm: 0,
                link_quality_percent: 0,
                remote_rssi_dbm: 0,
                remote_link_quality_percent: None,
                rate_code: 0,
                schedule: None,
                tag_failures: 0,
                tx_power_step: None,
            },
            bind_requested: false,
            follower_updates: 0,
            rejected_records: 0,
            last_downlink_us: None,
            openlrs_remote: None,
            power: PowerControl::new(telemetry::link::power::MAX_STEP, true),
        }
    }

    /// For the link task: a bind was asked for since the last call.
    pub fn take_bind_request(&mut self) -> bool {
        core::mem::take(&mut self.bind_requested)
    }

    /// Whether the handset's channels are stale (none yet, or none for the input timeout):
    /// the uplinks then tell the follower to fly its failsafe.
    pub fn input_lost(&self) -> bool {
        self.input_lost
    }

    /// Times the handset input was lost after it had been delivering channels.
    pub fn input_losses(&self) -> u32 {
        self.input_losses
    }

    /// Telemetry frames from the air that were corrupt or too long.
    pub fn dropped_frames(&self) -> u32 {
        self.splitter.dropped()
    }

    /// Records for the air refused because their CRC failed (a phone's damaged frame that
    /// still decoded as COBS).
    pub fn rejected_records(&self) -> u32 {
        self.rejected_records
    }

    /// Records dropped because a queue was full (to the air, from the air).
    pub fn dropped_records(&self) -> (u32, u32) {
        (
            self.uplink.dropped().records,
            self.received.dropped().records,
        )
    }

    /// Transmitter role, at the start of every slot (`now_us` = slot start on the link
    /// clock, which is the firmware's µs clock): channels and queued records in, received
    /// records and statistics out.
    pub fn on_master_slot(&mut self, now_us: u64, master: &mut Master) {
        self.update_input(now_us);
        master.set_input_lost(self.input_lost);
        if let Some(channels) = self.channels.filter(|_| !self.input_lost) {
            let mut values = [CHANNEL_CENTER; telemetry::channels::MAX_CHANNELS];
            for (slot, value) in values.iter_mut().zip(channels.as_slice()) {
                *slot = *value;
            }
            master.set_channels(&values);
        }
        self.exchange_records(&mut master.uplink_stream, &mut master.downlink_stream);
        let remote = master.remote_report();
        let rate = master.params().rate;
        let connected = master
            .last_downlink_us()
            .is_some_and(|t| now_us.saturating_sub(t) < CONNECTED_TIMEOUT_US);
        let (ratio, report) = (master.params().telemetry_ratio, master.remote_report_at());
        // Up for the power once a downlink came: at long telemetry ratios the downlinks are
        // further apart than `connected`'s timeout, and the power's own rule (no report for
        // three telemetry cycles) says when they stopped.
        let heard = master.last_downlink_us().is_some();
        let step = self.power_step(now_us, (rate, ratio), heard, report);
        master.set_tx_power(step);
        self.stats = LinkStats {
            connected,
            tx_power_step: Some(step),
            rssi_dbm: master.downlink_rssi_dbm().unwrap_or(0),
            link_quality_percent: master.downlink_lq(),
            remote_rssi_dbm: remote.map_or(0, |r| i16::from(r.rssi_dbm)),
            remote_link_quality_percent: remote.map(|r| r.lq_percent),
            rate_code: rate.code(),
            tag_failures: master.counters().tag_failures,
            schedule: Some(AirSchedule {
                period_us: rate.slot_us(),
                // When the channels of the first uplink of this telemetry cycle are latched:
                // the instant the handset's frame must have arrived by. The cycle's first
                // slot is always an uplink, so a radio asked for every other slot (the CRSF
                // line's minimum period) lands on uplinks only, never on the downlink hole.
                phase_us: (now_us + u64::from(uplink_latch_offset_us(rate))).saturating_sub(
                    u64::from(master.slot() % u32::from(master.params().telemetry_ratio.max(1)))
                        * u64::from(rate.slot_us()),
                ),
            }),
        };
    }

    /// Receiver role, after every follower step: new channels and received records out,
    /// queued records in, statistics (connected = not in failsafe).
    pub fn on_follower_step(&mut self, now_us: u64, follower: &mut Follower) {
        if follower.updates() != self.follower_updates {
            self.follower_updates = follower.updates();
            let count = follower.params().format.count();
            let output = follower.output();
            self.received_channels = Some(ChannelFrame::from_ticks(
                output.get(..count).unwrap_or(output),
            ));
        }
        self.exchange_records(&mut follower.downlink_stream, &mut follower.uplink_stream);
        let remote = follower.remote_report();
        let params = *follower.params();
        let link = (params.rate, params.telemetry_ratio);
        // On the master's grid, failsafe or not (a master whose handset input stopped
        // still hears us): the link is up.
        let tracking = follower.sync_state() == SyncState::Tracking;
        let step = self.power_step(now_us, link, tracking, follower.remote_report_at());
        follower.set_tx_power(step);
        self.stats = LinkStats {
            connected: !follower.in_failsafe(),
            tx_power_step: Some(step),
            rssi_dbm: follower.uplink_rssi_dbm().unwrap_or(0),
            link_quality_percent: follower.uplink_lq(),
            remote_rssi_dbm: remote.map_or(0, |r| i16::from(r.rssi_dbm)),
            remote_link_quality_percent: remote.map(|r| r.lq_percent),
            rate_code: follower.params().rate.code(),
            schedule: None,
            tag_failures: follower.counters().tag_failures,
        };
    }

    /// The power step from now: the other end's `report` (with its arrival time) on a link of
    /// `rate` with one report per telemetry cycle of `ratio` slots.
    fn power_step(
        &mut self,
        now_us: u64,
        (rate, ratio): (RateMode, u8),
        connected: bool,
        report: Option<(telemetry::frame::LinkReport, u64)>,
    ) -> u8 {
        self.power.update(&PowerInput {
            now_us,
            rate,
            connected,
            report,
            report_period_us: rate.slot_us().saturating_mul(u32::from(ratio.max(1))),
        })
    }

    /// Input freshness at the slot starting at `now_us`.
    fn update_input(&mut self, now_us: u64) {
        if core::mem::take(&mut self.input_fresh) {
            self.last_input_us = Some(now_us);
        }
        let lost = self
            .last_input_us
            .is_none_or(|t| now_us.saturating_sub(t) >= self.input_timeout_us);
        if lost && !self.input_lost {
            self.input_losses = self.input_losses.saturating_add(1);
        }
        self.input_lost = lost;
    }

    /// Either role's stream exchange: queued records into the link's stream while a whole
    /// frame fits, then everything received split into records.
    fn exchange_records<const T: usize, const R: usize>(
        &mut self,
        send: &mut StreamSender<T>,
        receive: &mut StreamReceiver<R>,
    ) {
        while send.free() >= MAX_STREAM_FRAME_LEN {
            let mut frame = [0u8; MAX_STREAM_FRAME_LEN];
            let Some(stream) = self.pop_uplink_frame(&mut frame) else {
                break;
            };
            send.write(stream);
        }
        self.read_stream(|buf| receive.read(buf));
    }

    /// The next queued record as a stream frame; a record that fails its check is dropped.
    fn pop_uplink_frame<'o>(&mut self, frame: &'o mut [u8]) -> Option<&'o [u8]> {
        let mut record = [0u8; MAX_RECORD_LEN];
        loop {
            let len = self.uplink.pop_into(&mut record).ok()??;
            let record = record.get(..len)?;
            // A damaged record is counted and the next one tried; checked before `frame` is
            // lent out, so only the record that is sent borrows it.
            if records::payload(record).is_err() {
                self.rejected_records = self.rejected_records.saturating_add(1);
                continue;
            }
            return match to_stream(record, frame) {
                Ok(stream) => Some(stream),
                // Only a frame buffer shorter than MAX_STREAM_FRAME_LEN gets here.
                Err(_) => {
                    self.rejected_records = self.rejected_records.saturating_add(1);
                    None
                }
            };
        }
    }

    fn read_stream(&mut self, mut read: impl FnMut(&mut [u8]) -> usize) {
        let mut buf = [0u8; 64];
        let mut record = [0u8; MAX_RECORD_LEN];
        loop {
            let n = read(&mut buf);
            // `read` fills at most `buf`, so the range exists; none read ends the loop.
            let Some(bytes) = buf.get(..n).filter(|b| !b.is_empty()) else {
                break;
            };
            for &byte in bytes {
                if let Some(whole) = self.splitter.push(byte, &mut record) {
                    self.received.push(whole);
                }
            }
        }
    }
}

impl LinkPort for AirLink {
    fn send_channels(&mut self, channels: &ChannelFrame) {
        self.channels = Some(*channels);
        self.input_fresh = true;
    }

    fn set_input_timeout_ms(&mut self, timeout_ms: u16) {
        self.input_timeout_us = u64::from(timeout_ms) * 1_000;
    }

    fn set_tx_power(&mut self, max_step: u8, dynamic: bool) {
        self.power.configure(max_step, dynamic);
    }

    fn can_send_record(&self) -> bool {
        self.uplink.len() < UPLINK_RECORDS
    }

    fn send_record(&mut self, record: &[u8]) {
        self.uplink.push(record);
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }

    fn start_bind(&mut self) {
        self.bind_requested = true;
    }

    fn on_link_stopped(&mut self) {
        self.stats = LinkStats {
            rate_code: self.stats.rate_code,
            tag_failures: self.stats.tag_failures,
            ..LinkStats::default()
        };
        self.received_channels = None;
        self.last_downlink_us = None;
        self.openlrs_remote = None;
    }

    fn take_received_record(&mut self, out: &mut [u8]) -> Option<usize> {
        self.received.pop_into(out).ok().flatten()
    }

    fn take_received_channels(&mut self) -> Option<ChannelFrame> {
        self.received_channels.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_names_the_latch_of_the_telemetry_cycles_first_slot() {
        use telemetry::link::RateMode;
        use telemetry::link::core::Step;
        let params = LinkParams::new(
            7,
            telemetry::link::Band::Mhz433,
            RateMode::F700,
            ChannelFormat::Full16,
            8,
        );
        let mut master = Master::new(params);
        let mut buf = [0u8; 64];
        // Slots 0, 1 and 2 (uplinks) go out; the hook then runs for slot 3 at 100 ms.
        for _ in 0..3 {
            assert!(matches!(master.plan(0, &mut buf), Step::Transmit { .. }));
            master.on_sent();
        }
        let mut link = AirLink::new();
        link.on_master_slot(100_000, &mut master);
        let schedule = link.stats().schedule.unwrap();
        assert_eq!(schedule.period_us, 1_428);
        // F700 latches 310 µs into its slot (30 µs lead, 80 µs set-up, 200 µs PLL, the
        // transmitter on): three slots back.
        assert_eq!(schedule.phase_us, 100_000 + 310 - 3 * 1_428);
    }

    #[test]
    fn settings_map_to_link_parameters() {
        let mut settings = Settings::default();
        assert_eq!(link_params(&settings), None, "unbound");
        settings.bind_id = 0x1234_5678;
        assert_eq!(
            link_params(&settings),
            None,
            "bound without a key, plain off"
        );
        settings.link_key = Some(telemetry::link::LinkKey::from_bytes([1; 16]));
        settings.band = telemetry::link::Band::Mhz868;
        settings.telemetry_ratio = 8;
        for rate in telemetry::link::RateMode::ALL {
            settings.rate = rate;
            let params = link_params(&settings).unwrap();
            assert_eq!(params.bind_id, 0x1234_5678);
            assert_eq!(params.rate, rate);
            assert_eq!(params.band, telemetry::link::Band::Mhz868);
            let format = if rate == telemetry::link::RateMode::F700 {
                ChannelFormat::Sticks16
            } else {
                ChannelFormat::Full16
            };
            assert_eq!(params.format, format);
            assert_eq!(new_bind_params(&settings, 1).format, format);
            assert_eq!(params.telemetry_ratio, 8);
            let fresh = new_bind_params(&settings, 0xCAFE);
            assert_eq!((fresh.bind_id, fresh.rate), (0xCAFE, rate));
            assert_eq!(fresh.telemetry_ratio, 8);
        }
    }

    #[test]
    fn records_wait_for_room_and_bind_requests_are_taken_once() {
        let mut link = AirLink::new();
        for _ in 0..UPLINK_RECORDS {
            assert!(link.can_send_record());
            link.send_record(&[1, 2, 3]);
        }
        assert!(!link.can_send_record());
        let mut master = Master::new(
            link_params(&Settings {
                bind_id: 9,
                plain: true,
                ..Settings::default()
            })
            .unwrap(),
        );
        link.on_master_slot(0, &mut master);
        // Three bytes are no record (no valid CRC): refused and counted, nothing sent.
        assert_eq!(link.rejected_records(), UPLINK_RECORDS as u32);
        assert_eq!(master.uplink_stream.pending(), 0);
        assert!(link.can_send_record());
        let mut record = [0u8; MAX_RECORD_LEN];
        let len = crate::records::with_crc(&[7, 7, 7], &mut record)
            .unwrap()
            .len();
        link.send_record(&record[..len]);
        link.on_master_slot(4_000, &mut master);
        // COBS(7 7 7 crc crc) + 0x00.
        assert_eq!(master.uplink_stream.pending(), len + 2);
        let stats = link.stats();
        assert!(!stats.connected);
        assert_eq!(stats.schedule.unwrap().period_us, 20_000);
        assert_eq!(
            stats.schedule.unwrap().phase_us,
            4_000 + u64::from(TX_LEAD_US + TX_SETUP_US + PLL_SETTLE_US)
        );
        link.start_bind();
        assert!(link.take_bind_request());
        assert!(!link.take_bind_request());
        link.on_link_stopped();
        assert_eq!(link.stats().schedule, None);
    }

    #[test]
    fn channels_are_flown_only_while_the_handset_delivers_them() {
        let mut link = AirLink::new();
        link.set_input_timeout_ms(100);
        let mut master = Master::new(
            link_params(&Settings {
                bind_id: 9,
                plain: true,
                ..Settings::default()
            })
            .unwrap(),
        );
        link.on_master_slot(0, &mut master);
        assert!(master.input_lost(), "nothing from the handset yet");
        link.send_channels(&ChannelFrame::from_ticks(&[1500; 8]));
        link.on_master_slot(20_000, &mut master);
        assert!(!master.input_lost());
        // Fresh as of the slot that saw them: lost exactly one timeout later.
        link.on_master_slot(119_999, &mut master);
        assert!(!link.input_lost());
        link.on_master_slot(120_000, &mut master);
        assert!(master.input_lost() && link.input_lost());
        assert_eq!(link.input_losses(), 1);
        link.send_channels(&ChannelFrame::from_ticks(&[1500; 8]));
        link.on_master_slot(140_000, &mut master);
        assert!(!master.input_lost());
        assert_eq!(link.input_losses(), 1);
    }
}
