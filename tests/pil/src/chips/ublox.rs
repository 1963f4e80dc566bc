//! A u-blox GNSS receiver on its UART1 (u-blox 8 / M8 Receiver Description UBX-13003221,
//! u-blox M10 Interface Description UBX-21035062): it powers up at its generation's default
//! rate (M8 9600 Bd, M10 38 400 Bd) talking NMEA (GGA and RMC once a second), takes UBX
//! frames (sync 0xB5 0x62, class, id, little-endian length, Fletcher checksum; a bad
//! checksum is dropped), answers every CFG message with ACK-ACK or ACK-NAK, and follows the
//! configuration: an M8 takes CFG-PRT (UART1 rate and protocol masks), CFG-RATE, CFG-MSG
//! (NAV-PVT per solution on UART1) and any other CFG it knows (ACKed) but NAKs CFG-VALSET;
//! an M10 takes CFG-VALSET's UART1 rate, protocol, measurement rate and NAV-PVT output keys
//! and NAKs the legacy messages. A new rate applies after the answer has left at the old
//! one, so the MCU must follow the receiver's rate changes: bytes at the wrong rate are
//! garbage on the line ([`super::uart`]).
//!
//! The solutions are flight-sitl's GPS model (`flight_sitl::gps::GpsSim`: the truth of
//! `latency_ms` earlier with its noise, as NAV-PVT bytes), at the measurement period the
//! receiver was configured to.

use flight_sitl::gps::{GpsConfig, GpsSim};

use super::uart::{Link, Received, frame_ns};

/// Which receiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Generation {
    /// u-blox 8 (NEO-M8N): legacy CFG messages, 9600 Bd out of the box.
    M8,
    /// u-blox M10: CFG-VALSET keys only, 38 400 Bd out of the box.
    M10,
}

impl Generation {
    /// UART1's rate after power-on.
    pub fn default_baud(self) -> u32 {
        match self {
            Generation::M8 => 9_600,
            Generation::M10 => 38_400,
        }
    }
}

const SYNC: [u8; 2] = [0xB5, 0x62];
const CLASS_ACK: u8 = 0x05;
const CLASS_CFG: u8 = 0x06;
const ID_PRT: u8 = 0x00;
const ID_MSG: u8 = 0x01;
const ID_RATE: u8 = 0x08;
const ID_VALSET: u8 = 0x8A;
const NAV_PVT: (u8, u8) = (0x01, 0x07);
const KEY_UART1_BAUDRATE: u32 = 0x4052_0001;
const KEY_UART1INPROT_UBX: u32 = 0x1073_0001;
const KEY_UART1OUTPROT_UBX: u32 = 0x1074_0001;
const KEY_UART1OUTPROT_NMEA: u32 = 0x1074_0002;
const KEY_RATE_MEAS: u32 = 0x3021_0001;
const KEY_MSGOUT_NAV_PVT_UART1: u32 = 0x2091_0007;
/// The NMEA sentences' period out of the box, ms.
const NMEA_PERIOD_NS: u64 = 1_000_000_000;

/// The UBX checksum (8-bit Fletcher over class, id, length and payload).
pub fn checksum(body: &[u8]) -> [u8; 2] {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in body {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    [a, b]
}

/// A UBX frame of `class`/`id` around `payload`.
pub fn ubx_frame(class: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let len = u16::try_from(payload.len())
        .unwrap_or(u16::MAX)
        .to_le_bytes();
    let mut body = vec![class, id, len[0], len[1]];
    body.extend_from_slice(payload);
    let ck = checksum(&body);
    let mut out = SYNC.to_vec();
    out.extend(body);
    out.extend(ck);
    out
}

/// An NMEA sentence with its checksum and CR LF.
fn nmea(body: &str) -> Vec<u8> {
    let ck = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("${body}*{ck:02X}\r\n").into_bytes()
}

/// The UBX frame being received.
#[derive(Debug, Clone, Default)]
struct Parser {
    buf: Vec<u8>,
}

impl Parser {
    /// One byte in; a whole frame with a good checksum out: (class, id, payload).
    fn push(&mut self, byte: u8) -> Option<(u8, u8, Vec<u8>)> {
        let at = self.buf.len();
        if at < 2 && SYNC.get(at) != Some(&byte) {
            self.buf.clear();
            if byte == 0xB5 {
                self.buf.push(byte);
            }
            return None;
        }
        self.buf.push(byte);
        let [_, _, class, id, l0, l1, ..] = self.buf.as_slice() else {
            return None;
        };
        let (class, id) = (*class, *id);
        let len = usize::from(u16::from_le_bytes([*l0, *l1]));
        if len > 1_024 {
            self.buf.clear();
            return None;
        }
        if self.buf.len() < 8 + len {
            return None;
        }
        let frame = std::mem::take(&mut self.buf);
        let body = frame.get(2..6 + len)?;
        let ck = frame.get(6 + len..8 + len)?;
        (checksum(body) == ck).then(|| (class, id, frame.get(6..6 + len).unwrap_or(&[]).to_vec()))
    }
}

/// The receiver.
pub struct Ublox {
    generation: Generation,
    baud: u32,
    in_ubx: bool,
    out_ubx: bool,
    out_nmea: bool,
    meas_ms: u16,
    /// NAV-PVT on UART1 every this many solutions (0: off).
    pvt_rate: u8,
    solutions: u64,
    /// The MCU's bytes into the receiver.
    from_mcu: Link,
    parser: Parser,
    /// What the receiver puts on its TX: (start ns, byte, rate).
    out: Vec<(u64, u8, u32)>,
    /// Its TX line is busy until then, ns.
    tx_free_ns: u64,
    /// A rate change waiting for the answer to leave: (from ns, rate).
    new_baud: Option<(u64, u32)>,
    gps: GpsSim,
    gps_config: GpsConfig,
    seed: u64,
    next_nmea_ns: u64,
}

impl core::fmt::Debug for Ublox {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Ublox")
            .field("generation", &self.generation)
            .field("baud", &self.baud)
            .field("meas_ms", &self.meas_ms)
            .field("pvt_rate", &self.pvt_rate)
            .finish()
    }
}

impl Ublox {
    /// A receiver of `generation` after power-on; its solutions are `gps_config`'s
    /// (latency, noise, dropouts), its noise from `seed`.
    pub fn new(generation: Generation, gps_config: GpsConfig, seed: u64) -> Self {
        let baud = generation.default_baud();
        let meas_ms = 1_000;
        Self {
            generation,
            baud,
            in_ubx: true,
            out_ubx: true,
            out_nmea: true,
            meas_ms,
            pvt_rate: 0,
            solutions: 0,
            from_mcu: Link::new(baud),
            parser: Parser::default(),
            out: Vec::new(),
            tx_free_ns: 0,
            new_baud: None,
            gps: GpsSim::new(
                GpsConfig {
                    period_ms: u32::from(meas_ms),
                    ..gps_config.clone()
                },
                seed,
            ),
            gps_config,
            seed,
            next_nmea_ns: NMEA_PERIOD_NS,
        }
    }

    /// UART1's rate now.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The measurement period, ms.
    pub fn meas_period_ms(&self) -> u16 {
        self.meas_ms
    }

    /// NAV-PVT is output on UART1.
    pub fn sends_nav_pvt(&self) -> bool {
        self.out_ubx && self.pvt_rate > 0
    }

    /// A byte the MCU sent, its frame starting at `start_ns` at `mcu_baud`.
    pub fn receive(&mut self, byte: u8, start_ns: u64, mcu_baud: u32) {
        self.apply_baud(start_ns);
        let got = self.from_mcu.send(byte, start_ns, mcu_baud, false);
        self.take(got);
    }

    fn take(&mut self, got: Vec<Received>) {
        for r in got {
            if r.framing_error || !self.in_ubx {
                continue;
            }
            if let Some((class, id, payload)) = self.parser.push(r.byte) {
                self.on_frame(class, id, &payload, r.at_ns);
            }
        }
    }

    fn apply_baud(&mut self, now_ns: u64) {
        if let Some((at, baud)) = self.new_baud.filter(|(at, _)| *at <= now_ns) {
            self.baud = baud;
            self.from_mcu.set_rx_baud(baud);
            self.new_baud = None;
            let _ = at;
        }
    }

    fn send(&mut self, bytes: &[u8], now_ns: u64) {
        let mut t = now_ns.max(self.tx_free_ns);
        let frame = frame_ns(self.baud);
        for &b in bytes {
            self.out.push((t, b, self.baud));
            t += frame;
        }
        self.tx_free_ns = t;
    }

    fn answer(&mut self, class: u8, id: u8, ack: bool, now_ns: u64) {
        let frame = ubx_frame(CLASS_ACK, u8::from(ack), &[class, id]);
        self.send(&frame, now_ns);
    }

    fn on_frame(&mut self, class: u8, id: u8, payload: &[u8], now_ns: u64) {
        if class != CLASS_CFG {
            return;
        }
        let ack = match (self.generation, id) {
            (Generation::M8, ID_PRT) => self.cfg_prt(payload),
            (Generation::M8, ID_RATE) => self.cfg_rate(payload),
            (Generation::M8, ID_MSG) => self.cfg_msg(payload),
            (Generation::M8, ID_VALSET) | (Generation::M10, ID_PRT | ID_RATE | ID_MSG) => None,
            (Generation::M10, ID_VALSET) => self.cfg_valset(payload),
            // Other CFG messages (NAV5, GNSS, …) are taken as they are.
            _ => Some(None),
        };
        self.answer(class, id, ack.is_some(), now_ns);
        if let Some(Some(baud)) = ack {
            // After the answer is out.
            self.new_baud = Some((self.tx_free_ns, baud));
        }
    }

    /// CFG-PRT for UART1: the new rate (if it changes) and the protocol masks.
    fn cfg_prt(&mut self, p: &[u8]) -> Option<Option<u32>> {
        if p.len() == 1 {
            // A poll: answered by ACK (the port's settings frame is not modelled).
            return Some(None);
        }
        let port = *p.first()?;
        if port != 1 || p.len() < 20 {
            return (port != 1).then_some(None);
        }
        let baud = u32::from_le_bytes(p.get(8..12)?.try_into().ok()?);
        let in_mask = u16::from_le_bytes(p.get(12..14)?.try_into().ok()?);
        let out_mask = u16::from_le_bytes(p.get(14..16)?.try_into().ok()?);
        self.in_ubx = in_mask & 1 != 0;
        self.out_ubx = out_mask & 1 != 0;
        self.out_nmea = out_mask & 2 != 0;
        Some((baud != self.baud && baud > 0).then_some(baud))
    }

    fn cfg_rate(&mut self, p: &[u8]) -> Option<Option<u32>> {
        let meas = u16::from_le_bytes(p.get(0..2)?.try_into().ok()?);
        if meas < 25 {
            return None;
        }
        self.set_meas(meas);
        Some(None)
    }

    fn cfg_msg(&mut self, p: &[u8]) -> Option<Option<u32>> {
        let (class, id) = (*p.first()?, *p.get(1)?);
        // Three bytes: the rate on the current port; eight: one per port, UART1 second.
        let rate = match p.len() {
            3 => *p.get(2)?,
            8 => *p.get(3)?,
            _ => return None,
        };
        if (class, id) == NAV_PVT {
            self.pvt_rate = rate;
        }
        Some(None)
    }

    fn cfg_valset(&mut self, p: &[u8]) -> Option<Option<u32>> {
        let mut at = 4;
        let mut baud = None;
        while at + 4 <= p.len() {
            let key = u32::from_le_bytes(p.get(at..at + 4)?.try_into().ok()?);
            // The key's size is in bits 28..30: 1 = one bit (a byte), 2 = 1 B, 3 = 2 B, 4 = 4 B.
            let size = match (key >> 28) & 0x7 {
                1 | 2 => 1,
                3 => 2,
                4 => 4,
                5 => 8,
                _ => return None,
            };
            let value = p.get(at + 4..at + 4 + size)?;
            let mut v = [0u8; 8];
            v.get_mut(..size)?.copy_from_slice(value);
            let v = u64::from_le_bytes(v);
            match key {
                KEY_UART1_BAUDRATE => baud = Some(v as u32),
                KEY_UART1INPROT_UBX => self.in_ubx = v != 0,
                KEY_UART1OUTPROT_UBX => self.out_ubx = v != 0,
                KEY_UART1OUTPROT_NMEA => self.out_nmea = v != 0,
                KEY_RATE_MEAS => self.set_meas(v as u16),
                KEY_MSGOUT_NAV_PVT_UART1 => self.pvt_rate = v as u8,
                _ => {}
            }
            at += 4 + size;
        }
        Some(baud.filter(|b| *b != self.baud && *b > 0))
    }

    fn set_meas(&mut self, meas_ms: u16) {
        if meas_ms != self.meas_ms {
            self.meas_ms = meas_ms;
            self.gps = GpsSim::new(
                GpsConfig {
                    period_ms: u32::from(meas_ms),
                    ..self.gps_config.clone()
                },
                self.seed ^ u64::from(meas_ms),
            );
        }
    }

    /// The truth at `now_ns` (scenario time `scenario_s`; NED position m, velocity m/s),
    /// every physics step: solutions and NMEA when due.
    pub fn tick(
        &mut self,
        now_ns: u64,
        scenario_s: f64,
        position_m: [f64; 3],
        velocity_mps: [f64; 3],
    ) {
        self.apply_baud(now_ns);
        let got = self.from_mcu.flush(now_ns);
        self.take(got);
        if let Some(pvt) = self
            .gps
            .step(now_ns / 1_000_000, scenario_s, position_m, velocity_mps)
        {
            self.solutions += 1;
            if self.sends_nav_pvt() && self.solutions.is_multiple_of(u64::from(self.pvt_rate)) {
                self.send(&pvt, now_ns);
            }
        }
        if now_ns >= self.next_nmea_ns {
            self.next_nmea_ns += NMEA_PERIOD_NS;
            if self.out_nmea {
                let mut s =
                    nmea("GPGGA,120000.00,4723.86452,N,00833.73564,E,1,12,0.8,488.0,M,48.0,M,,");
                s.extend(nmea(
                    "GPRMC,120000.00,A,4723.86452,N,00833.73564,E,0.0,,010125,,,A",
                ));
                self.send(&s, now_ns);
            }
        }
    }

    /// What the receiver has put on its TX since the last call: (start ns, byte, its rate).
    pub fn take_output(&mut self) -> Vec<(u64, u8, u32)> {
        std::mem::take(&mut self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of `frame` into the receiver at `baud` from `t`.
    fn feed(rx: &mut Ublox, frame: &[u8], t: u64, baud: u32) -> u64 {
        let mut t = t;
        for &b in frame {
            rx.receive(b, t, baud);
            t += frame_ns(baud);
        }
        t
    }

    fn output_frames(rx: &mut Ublox) -> Vec<(u8, u8, Vec<u8>)> {
        let mut p = Parser::default();
        rx.take_output()
            .into_iter()
            .filter_map(|(_, b, _)| p.push(b))
            .collect()
    }

    fn prt(baud: u32) -> Vec<u8> {
        let mut p = [0u8; 20];
        p[0] = 1;
        p[4..8].copy_from_slice(&0x08D0u32.to_le_bytes());
        p[8..12].copy_from_slice(&baud.to_le_bytes());
        p[12] = 1;
        p[14] = 1;
        ubx_frame(CLASS_CFG, ID_PRT, &p)
    }

    #[test]
    fn an_m8_acks_cfg_prt_at_the_old_rate_then_changes_and_naks_valset() {
        let mut rx = Ublox::new(Generation::M8, GpsConfig::default(), 1);
        assert_eq!(rx.baud(), 9_600);
        // At the wrong rate nothing is understood.
        let t = feed(&mut rx, &prt(115_200), 0, 115_200);
        rx.tick(t + 10_000_000, 0.0, [0.0; 3], [0.0; 3]);
        assert!(output_frames(&mut rx).is_empty());
        assert_eq!(rx.baud(), 9_600);
        // At its rate: ACK-ACK at 9600, then 115 200.
        let t = feed(&mut rx, &prt(115_200), 100_000_000, 9_600);
        let out = rx.take_output();
        assert!(out.iter().all(|(_, _, b)| *b == 9_600));
        let mut p = Parser::default();
        let frames: Vec<_> = out.iter().filter_map(|(_, b, _)| p.push(*b)).collect();
        assert_eq!(frames, vec![(CLASS_ACK, 1, vec![CLASS_CFG, ID_PRT])]);
        rx.tick(t + 20_000_000, 0.0, [0.0; 3], [0.0; 3]);
        assert_eq!(rx.baud(), 115_200);
        // VALSET: NAK.
        let valset = ubx_frame(CLASS_CFG, ID_VALSET, &[0, 1, 0, 0]);
        feed(&mut rx, &valset, t + 30_000_000, 115_200);
        assert_eq!(
            output_frames(&mut rx),
            vec![(CLASS_ACK, 0, vec![CLASS_CFG, ID_VALSET])]
        );
    }

    #[test]
    fn a_corrupted_frame_is_dropped() {
        let mut rx = Ublox::new(Generation::M8, GpsConfig::default(), 1);
        let mut f = prt(38_400);
        let last = f.len() - 1;
        f[last] ^= 1;
        feed(&mut rx, &f, 0, 9_600);
        assert!(output_frames(&mut rx).is_empty());
        assert_eq!(rx.baud(), 9_600);
    }

    #[test]
    fn configured_for_5hz_nav_pvt_it_sends_solutions_and_stops_nmea() {
        let mut rx = Ublox::new(Generation::M8, GpsConfig::default(), 1);
        let mut t = feed(&mut rx, &prt(9_600), 0, 9_600);
        t = feed(
            &mut rx,
            &ubx_frame(CLASS_CFG, ID_RATE, &[200, 0, 1, 0, 1, 0]),
            t,
            9_600,
        );
        t = feed(
            &mut rx,
            &ubx_frame(CLASS_CFG, ID_MSG, &[0x01, 0x07, 1]),
            t,
            9_600,
        );
        assert_eq!(rx.meas_period_ms(), 200);
        assert!(rx.sends_nav_pvt());
        rx.take_output();
        let mut pvts = 0;
        let mut all = Vec::new();
        let mut p = Parser::default();
        for ms in 0..2_000u64 {
            rx.tick(
                t + ms * 1_000_000,
                ms as f64 / 1e3,
                [1.0, 2.0, -3.0],
                [0.0; 3],
            );
            for (_, b, _) in rx.take_output() {
                all.push(b);
                if let Some((c, i, payload)) = p.push(b) {
                    assert_eq!((c, i), NAV_PVT);
                    assert_eq!(payload.len(), 92);
                    pvts += 1;
                }
            }
        }
        assert_eq!(pvts, 10, "5 Hz for 2 s");
        assert!(
            !all.windows(6).any(|w| w == b"$GPGGA"),
            "NMEA off by CFG-PRT's out mask"
        );
    }

    #[test]
    fn an_m10_takes_valset_keys_and_naks_legacy_messages() {
        let mut rx = Ublox::new(Generation::M10, GpsConfig::default(), 1);
        assert_eq!(rx.baud(), 38_400);
        let mut p = vec![0, 1, 0, 0];
        p.extend(KEY_UART1_BAUDRATE.to_le_bytes());
        p.extend(115_200u32.to_le_bytes());
        p.extend(KEY_MSGOUT_NAV_PVT_UART1.to_le_bytes());
        p.push(1);
        p.extend(KEY_RATE_MEAS.to_le_bytes());
        p.extend(100u16.to_le_bytes());
        let t = feed(&mut rx, &ubx_frame(CLASS_CFG, ID_VALSET, &p), 0, 38_400);
        assert_eq!(
            output_frames(&mut rx),
            vec![(CLASS_ACK, 1, vec![CLASS_CFG, ID_VALSET])]
        );
        rx.tick(t + 50_000_000, 0.0, [0.0; 3], [0.0; 3]);
        assert_eq!(rx.baud(), 115_200);
        assert_eq!(rx.meas_period_ms(), 100);
        assert!(rx.sends_nav_pvt());
        rx.take_output();
        feed(&mut rx, &prt(9_600), t + 60_000_000, 115_200);
        assert_eq!(
            output_frames(&mut rx),
            vec![(CLASS_ACK, 0, vec![CLASS_CFG, ID_PRT])]
        );
    }

    #[test]
    fn out_of_the_box_it_talks_nmea_once_a_second() {
        let mut rx = Ublox::new(Generation::M8, GpsConfig::default(), 1);
        rx.tick(1_000_000_000, 0.0, [0.0; 3], [0.0; 3]);
        let text: String = rx
            .take_output()
            .into_iter()
            .map(|(_, b, baud)| {
                assert_eq!(baud, 9_600);
                char::from(b)
            })
            .collect();
        assert!(text.starts_with("$GPGGA,"), "{text}");
        assert!(text.contains("\r\n$GPRMC,"));
    }
}
