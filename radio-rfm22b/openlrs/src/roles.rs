//! The role loops: the RX and TX state machines ([`rx`](super::rx), [`tx`](super::tx))
//! driven over a [`Radio`]. Each `*_step` does one wait-and-react cycle, so a test harness
//! or a firmware task can run them; `run_*` loop forever (`run_*_steps` handing the
//! application each step's events at once).
//!
//! Cancel-safety: a step dropped at an `.await` leaves the chip wherever it was (listening,
//! sending, half-programmed) and the state machine consistent; call `rx_start` / `tx_start`
//! again before the next step. Errors are returned as they come, never retried silently.

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use super::bind::BindData;
use super::modem::Purpose;
use super::radio::{Clock, Error, Radio};
use super::random::{SCAN_CHANNELS, choose_channels_per_rssi};
use super::rx::{Command, Output, Receiver};
use super::tx::{BIND_LISTEN_US, BindBeacon, Received, Transmitter};

/// How long the RX waits when its state machine has no deadline (bind mode forever).
const IDLE_WAIT_US: u64 = 1_000_000;
/// The TX stops listening for the reply this long before its next packet is due, to
/// leave time to retune and load the FIFO.
const REPLY_MARGIN_US: u64 = 500;

/// What the receiver reports to the application.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxEvent {
    /// New bind data: persist it.
    Bound(BindData),
    /// New channel values (10-bit, see [`super::channels::bits_to_us`]).
    Channels {
        /// The values.
        channels_bits: heapless::Vec<u16, { super::channels::MAX_CHANNELS }>,
        /// Store them as failsafe values (once per TX button press).
        save_failsafe: bool,
        /// When the packet was taken from the radio (the telemetry reply goes out before
        /// the event is delivered, so "now" in the handler is later).
        received_at_us: u64,
    },
    /// Serial bytes for the RX UART.
    Serial(heapless::Vec<u8, 8>),
    /// The link has been lost for the failsafe delay: apply the failsafe values.
    FailsafeStarted,
}

async fn apply<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    rx: &Receiver,
    command: Option<Command>,
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    match command {
        Some(Command::ListenBind) => {
            let data = rx
                .bind_data()
                .copied()
                .unwrap_or_else(|| BindData::defaults(radio.version(), radio.band()));
            radio.configure(&data, Purpose::Bind).await?;
        }
        Some(Command::StartLink(data)) => {
            radio.configure(&data, Purpose::Link).await?;
            radio.tune(&data, 0).await?;
        }
        Some(Command::Hop(index)) => {
            if let Some(data) = rx.bind_data().copied() {
                radio.tune(&data, index).await?;
            }
        }
        None => {}
    }
    // Every path ends listening again (a reception leaves the chip in READY).
    radio.listen().await
}

/// Boots the receiver: bind window or link, radio configured and listening.
pub async fn rx_start<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    rx: &mut Receiver,
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    let now = radio.now_us();
    let command = rx.start(now);
    apply(radio, rx, Some(command)).await
}

/// One receiver cycle: wait for a packet or the next deadline, then react.
///
/// When failsafe starts, the event is delivered first and then the chip is probed: a module
/// that is gone returns `Error::Radio(radio_rfm22b::Error::NotAnSi4432 { .. })` instead of
/// leaving the receiver listening to nothing.
pub async fn rx_step<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    rx: &mut Receiver,
    on_event: &mut impl FnMut(RxEvent),
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    let now = radio.now_us();
    let deadline = rx.next_deadline_us().unwrap_or(now + IDLE_WAIT_US);
    match radio.receive_until(deadline).await? {
        Some(packet) => {
            rx.set_afc(packet.afc);
            let reception = rx.on_packet(packet.at_us, &packet.bytes);
            if let Some(reply) = &reception.reply {
                radio.transmit(reply).await?;
            }
            match reception.output {
                Output::Bound(data) => on_event(RxEvent::Bound(data)),
                Output::Channels {
                    channels_bits,
                    save_failsafe,
                } => {
                    on_event(RxEvent::Channels {
                        channels_bits,
                        save_failsafe,
                        received_at_us: packet.at_us,
                    });
                }
                Output::Serial(bytes) => on_event(RxEvent::Serial(bytes)),
                Output::Nothing | Output::BindRefused(_) | Output::Unknown(_) => {}
            }
            apply(radio, rx, reception.command).await
        }
        None => {
            let now = radio.now_us();
            let tick = rx.poll(now);
            if tick.sample_rssi {
                let rssi = radio.rssi().await?;
                rx.on_rssi_sample(rssi);
            }
            if tick.failsafe_started {
                on_event(RxEvent::FailsafeStarted);
                // Writes to a module that fell off the bus succeed silently, so a lost link
                // and a lost chip look alike; tell them apart once, after failsafe is out.
                radio.probe().await?;
            }
            if tick.command.is_some() {
                apply(radio, rx, tick.command).await?;
            }
            Ok(())
        }
    }
}

/// Runs the receiver forever (returns only on a radio error, e.g. `NotAnSi4432` at start
/// or at failsafe when no module answers).
pub async fn run_receiver<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    rx: &mut Receiver,
    mut on_event: impl FnMut(RxEvent),
) -> Error<SPI::Error, IRQ::Error>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    if let Err(e) = rx_start(radio, rx).await {
        return e;
    }
    loop {
        if let Err(e) = rx_step(radio, rx, &mut on_event).await {
            return e;
        }
    }
}

/// Events one [`rx_step`] can report (a packet's output, then failsafe).
pub const RX_STEP_EVENTS: usize = 4;

/// Runs the receiver forever like [`run_receiver`], but hands each step's events to
/// `on_step(now_us, rx, events)` together, once per step, with the receiver to read — for an
/// application that takes them under a lock (TauLink's flight firmware and simulator). A
/// step waits at most one hop cycle. Returns only on a radio error (the events of the step
/// that failed are not delivered).
pub async fn run_receiver_steps<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    rx: &mut Receiver,
    mut on_step: impl FnMut(u64, &mut Receiver, &[RxEvent]),
) -> Error<SPI::Error, IRQ::Error>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    if let Err(e) = rx_start(radio, rx).await {
        return e;
    }
    loop {
        let mut events: heapless::Vec<RxEvent, RX_STEP_EVENTS> = heapless::Vec::new();
        let step = rx_step(radio, rx, &mut |event| {
            let _ = events.push(event);
        })
        .await;
        if let Err(e) = step {
            return e;
        }
        let now = radio.now_us();
        on_step(now, rx, &events);
    }
}

/// Bind mode of the TX: sends the bind packet every 200 ms and listens 50 ms after each,
/// until an RX answers `'B'` (`true`) or `until_us` passes (`false`).
pub async fn tx_bind<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    data: &BindData,
    until_us: u64,
) -> Result<bool, Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    radio.configure(data, Purpose::Bind).await?;
    let mut beacon = BindBeacon::new(data, radio.now_us());
    loop {
        let now = radio.now_us();
        if now >= until_us {
            return Ok(false);
        }
        if let Some(packet) = beacon.poll(now).copied() {
            radio.transmit(&packet).await?;
            radio.listen().await?;
            let listen_until = (radio.now_us() + u64::from(BIND_LISTEN_US)).min(until_us);
            while let Some(reply) = radio.receive_until(listen_until).await? {
                if beacon.on_packet(&reply.bytes) {
                    return Ok(true);
                }
                radio.listen().await?;
            }
        }
        let next = beacon.next_deadline_us().unwrap_or(until_us).min(until_us);
        radio.delay_until(next).await;
    }
}

/// What the transmitter reports to the application.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TxEvent {
    /// A downlink frame was processed; `rssi` is the TX's own reading of the reply.
    Downlink {
        /// What it carried.
        received: Received,
        /// Raw RSSI of the reply at the TX.
        rssi: u8,
    },
    /// No reply arrived for a packet that expected one (OpenLRSng beeps here).
    ReplyMissed,
}

/// Starts the link: programs the link configuration. Call once after binding.
pub async fn tx_start<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    tx: &Transmitter,
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    radio.configure(tx.bind_data(), Purpose::Link).await
}

/// One transmitter cycle: wait for the next slot, send, and collect the reply.
/// `before_send` runs right before each packet is built (set channels, queue serial).
pub async fn tx_step<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    tx: &mut Transmitter,
    before_send: &mut impl FnMut(&mut Transmitter),
    on_event: &mut impl FnMut(TxEvent),
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    radio.delay_until(tx.next_deadline_us()).await;
    before_send(tx);
    let now = radio.now_us();
    let Some(send) = tx.poll(now) else {
        return Ok(());
    };
    let data = *tx.bind_data();
    radio.tune(&data, send.hop_index).await?;
    radio.transmit(&send.packet).await?;
    tx.on_sent();
    if send.expect_reply {
        radio.listen().await?;
        let until = tx.next_deadline_us().saturating_sub(REPLY_MARGIN_US);
        match radio.receive_until(until).await? {
            Some(reply) => {
                let received = tx.on_downlink(&reply.bytes);
                on_event(TxEvent::Downlink {
                    received,
                    rssi: reply.rssi,
                });
            }
            None => on_event(TxEvent::ReplyMissed),
        }
    }
    Ok(())
}

/// Events one [`tx_step`] can report.
pub const TX_STEP_EVENTS: usize = 2;

/// Runs the transmitter forever: [`tx_start`], then [`tx_step`] with `before_send` right
/// before each packet and `on_step(now_us, tx, events)` after each step with that step's
/// events — the transmitter's counterpart of [`run_receiver_steps`] (TauLink's module
/// firmware and simulator). Returns only on a radio error.
pub async fn run_transmitter_steps<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    tx: &mut Transmitter,
    mut before_send: impl FnMut(&mut Transmitter),
    mut on_step: impl FnMut(u64, &Transmitter, &[TxEvent]),
) -> Error<SPI::Error, IRQ::Error>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    if let Err(e) = tx_start(radio, tx).await {
        return e;
    }
    loop {
        let mut events: heapless::Vec<TxEvent, TX_STEP_EVENTS> = heapless::Vec::new();
        let step = tx_step(radio, tx, &mut before_send, &mut |event| {
            let _ = events.push(event);
        })
        .await;
        if let Err(e) = step {
            return e;
        }
        let now = radio.now_us();
        on_step(now, tx, &events);
    }
}

/// RSSI samples are taken this often while dwelling on a channel during a scan.
const SCAN_SAMPLE_US: u64 = 250;

/// The TX's adaptive channel selection (long button press): listens `dwell_us` on every
/// channel 1..254 of the link's band plan, keeps the maximum RSSI of each, and lets
/// [`choose_channels_per_rssi`] replace the hop list with the quietest, well-spread channels.
/// OpenLRSng dwells 500 ms (about two minutes in all). Unlike upstream, which tunes through
/// `hopchannel[ch]` and so measures the wrong frequencies, this tunes each channel itself.
pub async fn scan_hop_channels<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    data: &mut BindData,
    dwell_us: u32,
    max_frequency_hz: u32,
) -> Result<(), Error<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    radio.configure(data, Purpose::Link).await?;
    radio.listen().await?;
    let mut max_rssi = [255u8; SCAN_CHANNELS];
    for (channel, slot) in (1..=u8::MAX).zip(max_rssi.iter_mut()) {
        let frequency_hz = u64::from(data.rf_frequency_hz)
            + u64::from(channel) * u64::from(data.rf_channel_spacing) * 10_000;
        if frequency_hz > u64::from(max_frequency_hz) {
            continue; // stays 255: never picked
        }
        radio.tune_channel_number(channel).await?;
        let until = radio.now_us() + u64::from(dwell_us);
        let mut loudest = 0;
        loop {
            let next_sample = radio.now_us() + SCAN_SAMPLE_US;
            radio.delay_until(next_sample).await;
            loudest = loudest.max(radio.rssi().await?);
            if radio.now_us() >= until {
                break;
            }
        }
        *slot = loudest;
    }
    choose_channels_per_rssi(data, &max_rssi, max_frequency_hz);
    Ok(())
}
