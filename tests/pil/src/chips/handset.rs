//! The EdgeTX handset in the JR bay, as taulink-sim's and flight-sitl's handsets play it:
//!
//! - **PPM** on JR pin 1: 8 channels in 22.5 ms frames, each channel a 300 µs low pulse
//!   (EdgeTX's default negative polarity) followed by the line high until the next falling
//!   edge, the channel's width from the pilot's sticks at the frame's first edge
//!   (`module_core::channels::ticks_to_us`), the sync gap filling the frame;
//! - **CRSF** on JR pin 5 at 400 kBd, non-inverted, half duplex: an RC_CHANNELS frame every
//!   4 ms (EdgeTX's 250 Hz), answered by the module in the gap. The line runs through the
//!   module's XOR (P0.10: 1 = inverted) to its UARTE RX and from its UARTE TX through the XOR
//!   and a tri-state buffer (P0.09: 1 = driving) back onto the wire, so a wrong polarity or
//!   a buffer left off shows as garbage or silence at the other end ([`JrLine`]); the module
//!   hears its own transmission on the line too.

use flight_sitl::scenario::PilotInput;
use module_core::channels::ticks_to_us;
use taulink_handset::crsf::channels::RcChannels;
use telemetry::channels::Channels;

use super::Edge;
use super::uart::{Link, Received};

/// PPM frame period, ns (flight-sitl's handset: 22.5 ms).
pub const PPM_FRAME_NS: u64 = 22_500_000;
/// Channels in a PPM frame.
pub const PPM_CHANNELS: usize = 8;
/// The low pulse that opens each channel, ns.
pub const PPM_PULSE_NS: u64 = 300_000;
/// CRSF: EdgeTX's channel frame period, ns (250 Hz).
pub const CRSF_PERIOD_NS: u64 = 4_000_000;
/// CRSF on the JR bay: 400 kBd.
pub const CRSF_BAUD: u32 = 400_000;

/// The channels the pilot's sticks and switches make (flight-sitl's transmitter).
pub fn channels(input: &PilotInput) -> Channels {
    flight_sitl::world::transmitter(input)
}

/// The PPM line's edges for one frame starting at `start_ns`: a falling edge and its rise
/// 300 µs later at each channel boundary, the last one closing channel 8 (the sync gap runs
/// to the next frame).
pub fn ppm_frame(start_ns: u64, ch: &Channels) -> Vec<Edge> {
    let mut edges = Vec::with_capacity(2 * (PPM_CHANNELS + 1));
    let mut t = start_ns;
    for i in 0..=PPM_CHANNELS {
        edges.push((t, false));
        edges.push((t + PPM_PULSE_NS, true));
        if let Some(v) = ch.get(i).filter(|_| i < PPM_CHANNELS) {
            t += u64::from(ticks_to_us(*v)) * 1_000;
        }
    }
    edges
}

/// The RC_CHANNELS frame EdgeTX sends for `ch`, as bytes on the line.
pub fn crsf_channels(ch: &Channels) -> Vec<u8> {
    let mut buf = [0u8; 64];
    RcChannels { ticks: *ch }
        .to_frame()
        .encode(&mut buf)
        .map(<[u8]>::to_vec)
        .unwrap_or_default()
}

/// The JR pin 5 wire between the handset and the module's UARTE behind its XOR and
/// buffer.
#[derive(Debug, Clone)]
pub struct JrLine {
    /// P0.10: the XOR inverts.
    pub invert: bool,
    /// P0.09: the buffer drives the wire.
    pub driving: bool,
    /// Handset → module UARTE RX.
    to_module: Link,
    /// Module UARTE TX → handset's receiver (EdgeTX at 400 kBd).
    to_handset: Link,
    /// Module UARTE TX → the wire → module UARTE RX (its own echo).
    echo: Link,
}

impl JrLine {
    /// The wire with the module's pins at reset (non-inverting, buffer off) and its UARTE
    /// receiving at `module_baud`.
    pub fn new(module_baud: u32) -> Self {
        Self {
            invert: false,
            driving: false,
            to_module: Link::new(module_baud),
            to_handset: Link::new(CRSF_BAUD),
            echo: Link::new(module_baud),
        }
    }

    /// The module's UARTE rate changed.
    pub fn set_module_baud(&mut self, baud: u32) {
        self.to_module.set_rx_baud(baud);
        self.echo.set_rx_baud(baud);
    }

    /// A byte the handset sends from `start_ns`: what the module's UARTE RX reads.
    pub fn from_handset(&mut self, byte: u8, start_ns: u64) -> Vec<Received> {
        self.to_module.send(byte, start_ns, CRSF_BAUD, self.invert)
    }

    /// A byte the module's UARTE sent from `start_ns` at `module_baud`: what the handset
    /// reads (nothing with the buffer off) and what the module's own RX reads back.
    pub fn from_module(
        &mut self,
        byte: u8,
        start_ns: u64,
        module_baud: u32,
    ) -> (Vec<Received>, Vec<Received>) {
        if !self.driving {
            return (Vec::new(), Vec::new());
        }
        // Through the XOR on the way out; the handset reads the wire as it is, the
        // module's RX through the XOR again.
        let handset = self
            .to_handset
            .send(byte, start_ns, module_baud, self.invert);
        let echo = self.echo.send(byte, start_ns, module_baud, false);
        (handset, echo)
    }

    /// The tails of frames sent at a mismatched rate, read by `now_ns`: (module, handset).
    pub fn flush(&mut self, now_ns: u64) -> (Vec<Received>, Vec<Received>) {
        let mut module = self.to_module.flush(now_ns);
        module.extend(self.echo.flush(now_ns));
        (module, self.to_handset.flush(now_ns))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::channels::CHANNEL_CENTER;

    #[test]
    fn a_ppm_frame_is_nine_falling_edges_the_channels_apart() {
        let input = PilotInput {
            throttle: 1.0,
            ..PilotInput::default()
        };
        let ch = channels(&input);
        let edges = ppm_frame(1_000_000, &ch);
        let falls: Vec<u64> = edges.iter().filter(|e| !e.1).map(|e| e.0).collect();
        assert_eq!(falls.len(), 9);
        for (i, w) in falls.windows(2).enumerate() {
            assert_eq!(w[1] - w[0], u64::from(ticks_to_us(ch[i])) * 1_000);
        }
        // Each pulse is 300 µs low.
        assert!(
            edges
                .chunks(2)
                .all(|p| p[1].0 - p[0].0 == PPM_PULSE_NS && p[1].1)
        );
        // The frame fits its 22.5 ms with a sync gap.
        assert!(falls[8] - falls[0] < PPM_FRAME_NS - 2_500_000);
    }

    #[test]
    fn crsf_goes_through_when_not_inverted_and_the_reply_only_with_the_buffer_on() {
        let ch = [CHANNEL_CENTER; 16];
        let frame = crsf_channels(&ch);
        assert_eq!(frame[0], 0xEE, "EdgeTX addresses the module");
        assert_eq!(frame.len(), 26);
        let mut line = JrLine::new(399_994);
        let got: Vec<u8> = frame
            .iter()
            .enumerate()
            .flat_map(|(i, &b)| line.from_handset(b, i as u64 * 25_000))
            .map(|r| r.byte)
            .collect();
        assert_eq!(got, frame);
        // Inverted by the XOR: garbage.
        line.invert = true;
        let mut got: Vec<u8> = frame
            .iter()
            .enumerate()
            .flat_map(|(i, &b)| line.from_handset(b, 10_000_000 + i as u64 * 25_000))
            .map(|r| r.byte)
            .collect();
        got.extend(line.flush(20_000_000).0.into_iter().map(|r| r.byte));
        assert_ne!(got, frame);
        line.invert = false;
        assert_eq!(
            line.from_module(0xC8, 30_000_000, 399_994),
            (vec![], vec![])
        );
        line.driving = true;
        let (handset, echo) = line.from_module(0xC8, 31_000_000, 399_994);
        assert_eq!(
            handset.iter().map(|r| r.byte).collect::<Vec<_>>(),
            vec![0xC8]
        );
        assert_eq!(echo.iter().map(|r| r.byte).collect::<Vec<_>>(), vec![0xC8]);
    }
}
