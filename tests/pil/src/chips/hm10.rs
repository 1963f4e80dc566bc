//! The HM-10 BLE bridge (JNHuaMao HMSoft firmware, as `/work/shared/reference/protocols.md`
//! §5 and module-core's `hm10::at` describe it) on a UART, and the phone that connects to it.
//!
//! Out of the box it runs at 9600 8N1, is named "HMSoft", PIN 000000, no bonding. Not
//! connected, it takes AT commands without CR/LF — a command is what arrived before the line
//! went quiet — and answers `OK`, `OK+Set:x`, `OK+Get:x`, `OK+RESET`; `AT+BAUDx` (0 = 9600
//! … 4 = 115 200, 8 = 230 400) is kept and applies after `AT+RESET` (≈ 0.5 s of reboot, deaf
//! meanwhile). Connected it is transparent: the UART's bytes go to the phone in notifications
//! of at most 20 bytes, the phone's writes come out of its TX, and a lone `AT` drops the
//! connection (`OK+LOST` with `AT+NOTI1`). The phone connects at the time the scenario says
//! once the module is up — with `AT+TYPE3` only knowing the PIN set by `AT+PASS` (the pilot
//! typed it in from the module's label) — and `AT+NOTI1` reports `OK+CONN`. A phone the
//! module dropped connects again [`PHONE_RETRY_NS`] later: the ground station says
//! "Bluetooth disconnected" and the pilot connects again (the module's boot script drops a
//! phone that connects while it runs, module-core `hm10::at`).

use super::uart::{Link, frame_ns};

/// The rates of `AT+BAUDx`, by x.
pub const BAUDS: [u32; 9] = [
    9_600, 19_200, 38_400, 57_600, 115_200, 4_800, 2_400, 1_200, 230_400,
];
/// The line is quiet this many frame times: the command is complete.
const COMMAND_GAP_FRAMES: u64 = 3;
/// From a complete command to the first byte of its answer, ns (HMSoft answers within a few
/// ms).
const ANSWER_NS: u64 = 2_000_000;
/// `AT+RESET`: deaf this long, then up with the new settings, ns.
const REBOOT_NS: u64 = 500_000_000;
/// One BLE notification's payload (ATT MTU 23), and the connection interval a phone picks.
pub const NOTIFY_BYTES: usize = 20;
/// Connection interval, ns: one notification per event each way (a conservative phone).
pub const CONNECTION_INTERVAL_NS: u64 = 20_000_000;

/// A dropped phone tries again this much later, ns (the pilot's second click on "connect").
pub const PHONE_RETRY_NS: u64 = 2_000_000_000;

/// The settings HMSoft keeps across resets.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Config {
    /// `AT+BAUDx` index.
    pub baud_index: u8,
    /// BLE name.
    pub name: String,
    /// `AT+NOTI1`: report connections on the UART.
    pub notify: bool,
    /// Pairing PIN.
    pub pin: u32,
    /// `AT+TYPEx`: 0 no PIN, 1 PIN, 2 PIN + bond, 3 PIN + bond required.
    pub auth_type: u8,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            baud_index: 0,
            name: "HMSoft".into(),
            notify: false,
            pin: 0,
            auth_type: 0,
        }
    }
}

/// The bridge and its phone.
#[derive(Debug, Clone)]
pub struct Hm10 {
    /// What it runs with now.
    active: Config,
    /// What it will run with after a reset.
    stored: Config,
    baud: u32,
    from_mcu: Link,
    command: Vec<u8>,
    last_byte_ns: u64,
    /// Deaf until then (booting), ns.
    up_at_ns: u64,
    connected: bool,
    /// The phone tries to connect from then on, ns.
    phone_at_ns: Option<u64>,
    /// The PIN the phone knows (None: the pilot gave it none).
    phone_pin: Option<u32>,
    /// What the MCU sent that the phone has not been notified of yet.
    to_phone: Vec<u8>,
    next_event_ns: u64,
    /// What the phone received, with the notification's time.
    phone_rx: Vec<(u64, Vec<u8>)>,
    /// What the phone still has to write.
    phone_tx: Vec<u8>,
    /// What the bridge puts on its TX: (start ns, byte, rate).
    out: Vec<(u64, u8, u32)>,
    tx_free_ns: u64,
    /// The rate the reboot in progress brings.
    pending_baud: Option<u32>,
}

impl Hm10 {
    /// A bridge powered at `now_ns` with `config` in its flash (`Config::default()` for a
    /// new one).
    pub fn new(config: Config, now_ns: u64) -> Self {
        let baud = rate(config.baud_index);
        Self {
            active: config.clone(),
            stored: config,
            baud,
            from_mcu: Link::new(baud),
            command: Vec::new(),
            last_byte_ns: 0,
            up_at_ns: now_ns,
            connected: false,
            phone_at_ns: None,
            phone_pin: None,
            to_phone: Vec::new(),
            next_event_ns: 0,
            phone_rx: Vec::new(),
            phone_tx: Vec::new(),
            out: Vec::new(),
            tx_free_ns: 0,
            pending_baud: None,
        }
    }

    /// Its UART rate now.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The settings in use.
    pub fn config(&self) -> &Config {
        &self.active
    }

    /// A phone is connected.
    pub fn connected(&self) -> bool {
        self.connected
    }

    /// The phone tries to connect from `at_ns`, knowing `pin` (if any).
    pub fn phone_connects(&mut self, at_ns: u64, pin: Option<u32>) {
        self.phone_at_ns = Some(at_ns);
        self.phone_pin = pin;
    }

    /// The phone writes `bytes` (sent in notifications as the connection allows).
    pub fn phone_write(&mut self, bytes: &[u8]) {
        self.phone_tx.extend_from_slice(bytes);
    }

    /// What the phone received since the last call, per notification with its time.
    pub fn take_phone_rx(&mut self) -> Vec<(u64, Vec<u8>)> {
        std::mem::take(&mut self.phone_rx)
    }

    /// What the bridge put on its TX since the last call: (start ns, byte, its rate).
    pub fn take_output(&mut self) -> Vec<(u64, u8, u32)> {
        std::mem::take(&mut self.out)
    }

    /// A byte the MCU sent, its frame starting at `start_ns` at `mcu_baud`.
    pub fn receive(&mut self, byte: u8, start_ns: u64, mcu_baud: u32) {
        let got = self.from_mcu.send(byte, start_ns, mcu_baud, false);
        self.absorb(got);
    }

    fn absorb(&mut self, got: Vec<super::uart::Received>) {
        for r in got {
            if r.at_ns < self.up_at_ns || r.framing_error {
                continue;
            }
            if self.connected {
                self.to_phone.push(r.byte);
            }
            // Commands are listened for connected too: a lone AT drops the link.
            self.command.push(r.byte);
            self.last_byte_ns = r.at_ns;
        }
    }

    fn send(&mut self, text: &[u8], now_ns: u64) {
        let mut t = now_ns.max(self.tx_free_ns);
        for &b in text {
            self.out.push((t, b, self.baud));
            t += frame_ns(self.baud);
        }
        self.tx_free_ns = t;
    }

    /// Brings the bridge to `now_ns`: commands that ended, the reboot, the phone's
    /// connection and its notifications both ways.
    pub fn tick(&mut self, now_ns: u64) {
        let got = self.from_mcu.flush(now_ns);
        self.absorb(got);
        if now_ns >= self.up_at_ns
            && let Some(baud) = self.pending_baud.take()
        {
            self.baud = baud;
            self.from_mcu.set_rx_baud(baud);
        }
        let gap = COMMAND_GAP_FRAMES * frame_ns(self.baud);
        if !self.command.is_empty() && now_ns >= self.last_byte_ns + gap {
            let command = std::mem::take(&mut self.command);
            self.on_command(&command, self.last_byte_ns + gap);
        }
        if now_ns < self.up_at_ns {
            return;
        }
        if !self.connected
            && self.phone_at_ns.is_some_and(|t| now_ns >= t)
            && (self.active.auth_type == 0 || self.phone_pin == Some(self.active.pin))
        {
            self.connected = true;
            self.next_event_ns = now_ns;
            if self.active.notify {
                self.send(b"OK+CONN", now_ns);
            }
        }
        while self.connected && now_ns >= self.next_event_ns {
            let t = self.next_event_ns;
            self.next_event_ns += CONNECTION_INTERVAL_NS;
            if !self.to_phone.is_empty() {
                let n = self.to_phone.len().min(NOTIFY_BYTES);
                let chunk: Vec<u8> = self.to_phone.drain(..n).collect();
                self.phone_rx.push((t, chunk));
            }
            if !self.phone_tx.is_empty() {
                let n = self.phone_tx.len().min(NOTIFY_BYTES);
                let chunk: Vec<u8> = self.phone_tx.drain(..n).collect();
                self.send(&chunk, t);
            }
        }
    }

    fn on_command(&mut self, command: &[u8], at_ns: u64) {
        let t = at_ns + ANSWER_NS;
        if self.connected {
            // Transparent; only a lone AT is taken, and it drops the connection.
            if command == b"AT" {
                self.connected = false;
                self.phone_at_ns = Some(t + PHONE_RETRY_NS);
                if self.active.notify {
                    self.send(b"OK+LOST", t);
                }
            }
            return;
        }
        let Some(rest) = command.strip_prefix(b"AT") else {
            return;
        };
        let text = String::from_utf8_lossy(rest).into_owned();
        let answer = match text.as_str() {
            "" => "OK".to_owned(),
            "+RESET" => {
                self.reboot(t);
                "OK+RESET".to_owned()
            }
            "+RENEW" => {
                self.stored = Config::default();
                self.reboot(t);
                "OK+RENEW".to_owned()
            }
            "+BAUD?" => format!("OK+Get:{}", self.stored.baud_index),
            "+NAME?" => format!("OK+NAME:{}", self.active.name),
            "+PASS?" => format!("OK+Get:{:06}", self.active.pin),
            "+VERS?" | "+VERR?" => "HMSoft V540".to_owned(),
            _ => match self.set(&text) {
                Some(value) => format!("OK+Set:{value}"),
                None => return,
            },
        };
        self.send(answer.as_bytes(), t);
    }

    /// `AT+BAUDx`, `AT+NAMEx`, `AT+NOTIx`, `AT+PASSx`, `AT+TYPEx`: the value set.
    fn set(&mut self, text: &str) -> Option<String> {
        let (key, value) = ["+BAUD", "+NAME", "+NOTI", "+PASS", "+TYPE"]
            .into_iter()
            .find_map(|k| text.strip_prefix(k).map(|v| (k, v)))?;
        let digit = || value.parse::<u8>().ok();
        match key {
            "+BAUD" => {
                let x = digit().filter(|x| usize::from(*x) < BAUDS.len())?;
                self.stored.baud_index = x;
            }
            "+NAME" if !value.is_empty() && value.len() <= 12 => {
                self.stored.name = value.to_owned();
                self.active.name = value.to_owned();
            }
            "+NOTI" => {
                let on = digit().filter(|x| *x <= 1)? == 1;
                self.stored.notify = on;
                self.active.notify = on;
            }
            "+PASS" if value.len() == 6 => {
                let pin = value.parse().ok()?;
                self.stored.pin = pin;
                self.active.pin = pin;
            }
            "+TYPE" => {
                let x = digit().filter(|x| *x <= 3)?;
                self.stored.auth_type = x;
                self.active.auth_type = x;
            }
            _ => return None,
        }
        Some(value.to_owned())
    }

    fn reboot(&mut self, now_ns: u64) {
        self.connected = false;
        self.active = self.stored.clone();
        self.up_at_ns = now_ns + REBOOT_NS;
        // The answer leaves at the old rate; the new one applies from the reboot.
        self.pending_baud = Some(rate(self.active.baud_index));
    }
}

fn rate(index: u8) -> u32 {
    BAUDS.get(usize::from(index)).copied().unwrap_or(9_600)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `text` from the MCU at `baud` from `t`; returns when its last byte ended.
    fn type_in(h: &mut Hm10, text: &[u8], t: u64, baud: u32) -> u64 {
        let mut t = t;
        for &b in text {
            h.receive(b, t, baud);
            t += frame_ns(baud);
        }
        t
    }

    /// What the bridge answered by `until`.
    fn answer(h: &mut Hm10, until: u64) -> String {
        let mut t = until.saturating_sub(50_000_000);
        while t <= until {
            h.tick(t);
            t += 1_000_000;
        }
        h.take_output()
            .into_iter()
            .map(|(_, b, _)| char::from(b))
            .collect()
    }

    #[test]
    fn factory_rate_commands_answers_and_the_baud_after_a_reset() {
        let mut h = Hm10::new(Config::default(), 0);
        // At 115 200 Bd a factory module understands nothing.
        let t = type_in(&mut h, b"AT", 0, 115_200);
        assert_eq!(answer(&mut h, t + 40_000_000), "");
        let t = type_in(&mut h, b"AT", 100_000_000, 9_600);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK");
        let t = type_in(&mut h, b"AT+NAMETauLink", 200_000_000, 9_600);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK+Set:TauLink");
        let t = type_in(&mut h, b"AT+BAUD4", 300_000_000, 9_600);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK+Set:4");
        assert_eq!(h.baud(), 9_600, "only after a reset");
        let t = type_in(&mut h, b"AT+RESET", 400_000_000, 9_600);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK+RESET");
        // Deaf while rebooting, then at 115 200.
        let t = type_in(&mut h, b"AT", t + 100_000_000, 115_200);
        assert_eq!(answer(&mut h, t + 40_000_000), "");
        let t = type_in(&mut h, b"AT", 1_500_000_000, 115_200);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK");
        assert_eq!(h.baud(), 115_200);
        assert_eq!(h.config().name, "TauLink");
    }

    #[test]
    fn a_bonded_module_takes_only_a_phone_that_knows_the_pin() {
        let config = Config {
            notify: true,
            pin: 123_456,
            auth_type: 3,
            ..Config::default()
        };
        let mut h = Hm10::new(config.clone(), 0);
        h.phone_connects(10_000_000, Some(654_321));
        answer(&mut h, 100_000_000);
        assert!(!h.connected());
        let mut h = Hm10::new(config, 0);
        h.phone_connects(10_000_000, Some(123_456));
        assert_eq!(answer(&mut h, 100_000_000), "OK+CONN");
        assert!(h.connected());
        // Transparent both ways, 20 bytes per connection event.
        let t = type_in(&mut h, &[0x55; 30], 100_000_000, 9_600);
        answer(&mut h, t + 100_000_000);
        let rx = h.take_phone_rx();
        assert_eq!(
            rx.iter().map(|(_, c)| c.len()).collect::<Vec<_>>(),
            vec![20, 10]
        );
        h.phone_write(b"hello");
        assert_eq!(answer(&mut h, t + 200_000_000), "hello");
        // A lone AT while connected drops the phone; the pilot connects again 2 s later.
        let t = type_in(&mut h, b"AT", t + 300_000_000, 9_600);
        assert_eq!(answer(&mut h, t + 40_000_000), "OK+LOST");
        assert!(!h.connected());
        answer(&mut h, t + PHONE_RETRY_NS);
        assert!(!h.connected(), "not before the retry");
        assert_eq!(answer(&mut h, t + PHONE_RETRY_NS + 10_000_000), "OK+CONN");
        assert!(h.connected());
    }
}
