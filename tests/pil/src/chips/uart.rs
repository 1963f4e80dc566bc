//! A UART line between two ends (8N1: start bit low, eight data bits LSB first, stop bit
//! high; idle high), each at its own baud rate. A byte is sent as its waveform; the receiver
//! finds each start bit by its falling edge and samples the middle of its own bit times, so
//! a receiver at the sender's rate (within the ±2 % a UART tolerates over a frame) reads the
//! byte, and one at another rate reads whatever its sampling makes of the waveform —
//! other bytes, more or fewer of them, framing errors — as the silicon does. An inverting
//! stage (the module's XOR) inverts the waveform on its way.

/// What a receiver read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received {
    /// When its stop bit was sampled, ns.
    pub at_ns: u64,
    /// The byte.
    pub byte: u8,
    /// The stop bit read low.
    pub framing_error: bool,
}

/// Bit time at `baud`, ns (exact enough: kept in f64).
fn bit_ns(baud: u32) -> f64 {
    1e9 / f64::from(baud.max(1))
}

/// The time one 8N1 frame takes at `baud`, ns.
pub fn frame_ns(baud: u32) -> u64 {
    (10.0 * bit_ns(baud)).round() as u64
}

/// Whether two rates read each other's frames: within 2 % (the usual 8N1 budget of a
/// 16×-oversampling receiver, half of it per end).
pub fn compatible(a: u32, b: u32) -> bool {
    let (a, b) = (f64::from(a), f64::from(b));
    (a - b).abs() <= 0.02 * b
}

/// The receiving end of a line: edges in, bytes out.
#[derive(Debug, Clone)]
pub struct LineRx {
    baud: u32,
    /// The line's changes not yet consumed, (time, level), in time order, with the level
    /// before the first.
    edges: Vec<(u64, bool)>,
    level: bool,
    /// Where to look for the next start bit from.
    search_from: u64,
}

impl LineRx {
    /// A receiver at `baud` on an idle (high) line.
    pub fn new(baud: u32) -> Self {
        Self {
            baud,
            edges: Vec::new(),
            level: true,
            search_from: 0,
        }
    }

    /// Its rate now.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Changes its rate (between frames).
    pub fn set_baud(&mut self, baud: u32) {
        self.baud = baud;
    }

    /// The line changes to `level` at `t_ns` (in time order).
    pub fn edge(&mut self, t_ns: u64, level: bool) {
        self.edges.push((t_ns, level));
    }

    /// The level just before `t` (the edges at `t` not yet applied).
    fn level_before(&self, t: u64) -> bool {
        self.edges
            .iter()
            .take_while(|(te, _)| *te < t)
            .last()
            .map_or(self.level, |e| e.1)
    }

    fn level_at(&self, t: u64) -> bool {
        self.edges
            .iter()
            .take_while(|(te, _)| *te <= t)
            .last()
            .map_or(self.level, |e| e.1)
    }

    /// Every byte whose stop bit has been sampled by `now_ns`.
    pub fn advance(&mut self, now_ns: u64) -> Vec<Received> {
        let bit = bit_ns(self.baud);
        let mut out = Vec::new();
        loop {
            // The next falling edge at or after `search_from`.
            let mut prev = self.level_before(self.search_from);
            let mut start = None;
            for &(t, l) in &self.edges {
                if t >= self.search_from && prev && !l {
                    start = Some(t);
                    break;
                }
                prev = l;
            }
            let Some(s) = start else { break };
            let stop_at = s + (9.5 * bit).round() as u64;
            if stop_at > now_ns {
                break;
            }
            let mut byte = 0u8;
            for k in 0..8 {
                let at = s + ((1.5 + f64::from(k)) * bit).round() as u64;
                if self.level_at(at) {
                    byte |= 1 << k;
                }
            }
            let stop = self.level_at(stop_at);
            // A start bit that is high again at its middle was a glitch: no byte.
            if !self.level_at(s + (0.5 * bit).round() as u64) {
                out.push(Received {
                    at_ns: stop_at,
                    byte,
                    framing_error: !stop,
                });
            }
            self.search_from = stop_at;
        }
        // Forget what lies before the search point (keeping the level there).
        let keep_from = self.search_from.min(now_ns);
        let level = self.level_at(keep_from);
        self.edges.retain(|(t, _)| *t > keep_from);
        self.level = level;
        out
    }
}

/// The waveform of `byte` sent from `start_ns` at `baud`: the line's changes (time, level),
/// ending high after the stop bit; inverted by `invert` (high idle becomes low).
pub fn waveform(byte: u8, start_ns: u64, baud: u32, invert: bool) -> Vec<(u64, bool)> {
    let bit = bit_ns(baud);
    let mut bits = [true; 10];
    bits[0] = false;
    for (k, b) in bits.iter_mut().skip(1).take(8).enumerate() {
        *b = byte & (1 << k) != 0;
    }
    let mut out = Vec::with_capacity(10);
    let mut level = !invert;
    for (k, b) in bits.iter().enumerate() {
        let l = *b != invert;
        if l != level {
            out.push((start_ns + (k as f64 * bit).round() as u64, l));
            level = l;
        }
    }
    out
}

/// One direction of a line: a sender at `tx_baud`, a receiver at `rx_baud`, optionally an
/// inverter between. Matching rates without inversion deliver each byte straight at the end
/// of its stop bit; anything else goes through the waveform and [`LineRx`].
#[derive(Debug, Clone)]
pub struct Link {
    rx: LineRx,
    /// The sender's line ends here (after its last stop bit), ns.
    busy_until_ns: u64,
}

impl Link {
    /// A link into a receiver at `rx_baud`.
    pub fn new(rx_baud: u32) -> Self {
        Self {
            rx: LineRx::new(rx_baud),
            busy_until_ns: 0,
        }
    }

    /// The receiver's rate.
    pub fn rx_baud(&self) -> u32 {
        self.rx.baud()
    }

    /// Changes the receiver's rate.
    pub fn set_rx_baud(&mut self, baud: u32) {
        self.rx.set_baud(baud);
    }

    /// When the line is free again for the sender, ns.
    pub fn free_at_ns(&self) -> u64 {
        self.busy_until_ns
    }

    /// `byte` sent from `start_ns` (not before the line is free: queued behind the last
    /// frame) at `tx_baud`, through an inverter if `invert`; returns what the receiver has
    /// read by the end of this frame.
    pub fn send(&mut self, byte: u8, start_ns: u64, tx_baud: u32, invert: bool) -> Vec<Received> {
        let start = start_ns.max(self.busy_until_ns);
        let end = start + frame_ns(tx_baud);
        self.busy_until_ns = end;
        if !invert && compatible(tx_baud, self.rx.baud()) && self.rx.edges.is_empty() {
            self.rx.search_from = end;
            self.rx.level = true;
            return vec![Received {
                at_ns: end,
                byte,
                framing_error: false,
            }];
        }
        for (t, l) in waveform(byte, start, tx_baud, invert) {
            self.rx.edge(t, l);
        }
        self.rx.advance(end)
    }

    /// What the receiver reads by `now_ns` of what was sent (the tail of a mismatched
    /// frame).
    pub fn flush(&mut self, now_ns: u64) -> Vec<Received> {
        self.rx.advance(now_ns)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(r: &[Received]) -> Vec<u8> {
        r.iter().map(|x| x.byte).collect()
    }

    #[test]
    fn matching_rates_deliver_each_byte_at_its_stop_bit() {
        let mut link = Link::new(115_200);
        let got = link.send(0xB5, 1_000, 115_200, false);
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].byte, 0xB5);
        // 10 bits at 115 200 Bd: 86.8 µs.
        assert_eq!(got[0].at_ns, 1_000 + 86_806);
        // A second byte queues behind the first.
        let next = link.send(0x62, 1_000, 115_200, false);
        assert_eq!(next[0].at_ns, 1_000 + 2 * 86_806);
        // 1 % off is still read.
        assert_eq!(bytes(&link.send(0x55, 500_000, 116_300, false)), vec![0x55]);
    }

    #[test]
    fn the_waveform_path_reads_the_same_byte_at_the_same_rate() {
        let mut rx = LineRx::new(9_600);
        for (t, l) in waveform(0xA3, 0, 9_600, false) {
            rx.edge(t, l);
        }
        let got = rx.advance(2_000_000);
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].byte, 0xA3);
        assert!(!got[0].framing_error);
    }

    #[test]
    fn a_receiver_at_the_wrong_rate_reads_garbage() {
        // u-blox UBX sync chars at 9600 Bd into a USART at 115 200 Bd: the fast receiver
        // samples one low start bit of 104 µs as a byte of zeros with a framing error.
        let mut link = Link::new(115_200);
        let mut got = Vec::new();
        for (i, b) in [0xB5u8, 0x62].iter().enumerate() {
            got.extend(link.send(*b, i as u64 * frame_ns(9_600), 9_600, false));
        }
        got.extend(link.flush(10_000_000));
        assert!(!got.is_empty());
        assert_ne!(bytes(&got), vec![0xB5, 0x62]);
        assert!(got.iter().any(|r| r.framing_error));
        // And the other way: 115 200 Bd bytes at a 9600 Bd receiver are far fewer bytes.
        let mut slow = Link::new(9_600);
        let mut got = Vec::new();
        for i in 0..20u64 {
            got.extend(slow.send(0xB5, i * frame_ns(115_200), 115_200, false));
        }
        got.extend(slow.flush(10_000_000));
        assert!(got.len() < 5, "{got:?}");
    }

    #[test]
    fn an_inverted_line_is_not_the_byte() {
        let mut link = Link::new(400_000);
        let mut got = link.send(0xC8, 0, 400_000, true);
        got.extend(link.flush(1_000_000));
        assert_ne!(bytes(&got), vec![0xC8]);
    }
}
