//! Boot-time configuration of the HM-10 over its UART (JNHuaMao HM-10 datasheet, HMSoft
//! firmware AT command set), sans-IO.
//!
//! HMSoft takes AT commands without CR/LF and answers `OK`, `OK+Set:x`; it ships at 9600 Bd
//! and keeps `AT+BAUD4` (115 200 Bd) across power cycles. So the script first listens at
//! 115 200 Bd, then probes at 115 200; if that is silent it probes at the factory 9600 and
//! sets `AT+BAUD4` there. In both cases it sets the name and `AT+NOTI1` (connection
//! notifications for the relay), with a PIN ([`Configurator::with_pin`]) also `AT+PASS` and
//! `AT+TYPE3` (pairing needs the PIN, and the phone is bonded: the factory setting lets any
//! phone in range connect and talk to the module), and sends `AT+RESET`, after which the
//! settings apply; a last `AT` at 115 200 Bd checks that they did.
//!
//! A phone connected while the script runs — traffic in the listening window (a phone still
//! connected across a module reset) or an `OK+CONN` at any point — is disconnected (a lone
//! `AT` does that while connected) and the script starts over from the probe, at most
//! [`MAX_DISCONNECTS`] times: the PIN is set before any phone is served (issue 30, finding
//! 5: the script used to end there, leaving a factory HM-10 open). The relay opens only on
//! [`Outcome::Configured`].

use heapless::Vec;

/// Factory baud rate of HMSoft firmware.
pub const FACTORY_BAUD: u32 = 9_600;
/// The rate we configure (`AT+BAUD4`).
pub const RELAY_BAUD: u32 = 115_200;
/// Longest BLE name HMSoft accepts.
pub const MAX_NAME_LEN: usize = 12;

/// Time allowed for one reply; HMSoft answers within a few ms at either rate.
const REPLY_TIMEOUT_MS: u32 = 300;
/// Tries per command before giving up on it.
const TRIES: u8 = 2;
/// Listening before the first `AT`.
const LISTEN_MS: u32 = 500;
/// `AT+RESET` reboots the module; it needs ≈ 0.5 s before it takes commands again.
const REBOOT_MS: u32 = 1_000;
/// Phones the script disconnects before it gives up ([`Outcome::Failed`] at
/// [`Stage::Disconnect`]): a phone that reconnects at once, again and again.
pub const MAX_DISCONNECTS: u8 = 3;

/// A 6-digit HM-10 pairing PIN (000000–999999).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pin(u32);

impl Pin {
    /// The PIN `value`, or `None` above 999 999.
    pub const fn new(value: u32) -> Option<Self> {
        if value <= 999_999 {
            Some(Self(value))
        } else {
            None
        }
    }

    /// The PIN as a number.
    pub const fn value(self) -> u32 {
        self.0
    }

    /// The module's factory PIN: six digits (100 000 … 999 999, so never the HM-10's
    /// 000000 and no leading zero to get wrong) from a one-way mix of the chip's unique ID
    /// (the nRF52840's FICR DEVICEID, injected), so no two modules share one and none is
    /// public. Printed on the module's label / read with the radio's device tool.
    pub const fn factory(unique_id: u64) -> Self {
        // SplitMix64's finaliser: every ID bit moves about half the output bits.
        let mut z = unique_id.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Self(100_000 + (z % 900_000) as u32)
    }

    /// The six ASCII digits `AT+PASS` takes, leading zeros included.
    pub fn digits(self) -> [u8; 6] {
        let mut out = [b'0'; 6];
        let mut v = self.0;
        for d in out.iter_mut().rev() {
            *d = b'0' + (v % 10) as u8;
            v /= 10;
        }
        out
    }
}

/// How the configuration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// Configured; the UART now runs at `baud`.
    Configured {
        /// UART rate to use from now on.
        baud: u32,
    },
    /// No answer at 115 200 or 9600 Bd: no HM-10 fitted (or a clone that wants CR/LF).
    NoModule,
    /// A command was refused or unanswered after the module had answered `AT`.
    Failed {
        /// The stage that failed.
        stage: Stage,
    },
}

/// One step of the script.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// Listening for traffic before the first command.
    Listen,
    /// `AT` to a connected phone's module: it drops the phone.
    Disconnect,
    /// `AT` at 115 200 Bd.
    ProbeFast,
    /// `AT` at 9600 Bd.
    ProbeFactory,
    /// `AT+NAME…`.
    Name,
    /// `AT+NOTI1`.
    Notifications,
    /// `AT+PASS` with the PIN (only with a PIN).
    Pin,
    /// `AT+TYPE3`: PIN authentication and bonding (only with a PIN).
    Bonding,
    /// `AT+BAUD4` (only on the factory-rate path).
    Baud,
    /// `AT+RESET`.
    Reset,
    /// Waiting for the reboot.
    Reboot,
    /// `AT` at the final rate: the new settings took effect.
    Verify,
}

/// What the firmware must do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action<'a> {
    /// Re-open the UART at this rate, then call `poll` again.
    SetBaud(u32),
    /// Write these bytes, then call `poll` again.
    Send(&'a [u8]),
    /// Feed received bytes (or nothing) to `poll` no later than `until_ms`.
    Wait {
        /// Deadline, ms on the caller's clock.
        until_ms: u32,
    },
    /// Finished.
    Done(Outcome),
}

/// The configuration script.
#[derive(Debug)]
pub struct Configurator {
    name: Vec<u8, MAX_NAME_LEN>,
    pin: Option<Pin>,
    stage: Stage,
    /// The factory-rate path (needs `AT+BAUD4`).
    factory: bool,
    baud: u32,
    baud_pending: bool,
    send_pending: bool,
    tries_left: u8,
    /// Phones disconnected so far.
    disconnects: u8,
    deadline_ms: u32,
    reply: Vec<u8, 32>,
    command: Vec<u8, 24>,
    outcome: Option<Outcome>,
}

fn reached(now_ms: u32, deadline_ms: u32) -> bool {
    // Wrapping compare: the deadline is reached once now is at most half the range past it.
    now_ms.wrapping_sub(deadline_ms) < u32::MAX / 2
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    !needle.is_empty() && haystack.windows(needle.len()).any(|w| w == needle)
}

impl Configurator {
    /// A script that will name the module `name` (cut to 12 bytes), starting at `now_ms`.
    pub fn new(name: &str, now_ms: u32) -> Self {
        let mut stored = Vec::new();
        for &byte in name.as_bytes().iter().take(MAX_NAME_LEN) {
            let _ = stored.push(byte);
        }
        Self {
            name: stored,
            pin: None,
            stage: Stage::Listen,
            factory: false,
            baud: RELAY_BAUD,
            baud_pending: true,
            send_pending: false,
            tries_left: TRIES,
            disconnects: 0,
            deadline_ms: now_ms.wrapping_add(LISTEN_MS),
            reply: Vec::new(),
            command: Vec::new(),
            outcome: None,
        }
    }

    /// Also sets the pairing PIN and requires PIN authentication with bonding
    /// (`AT+PASS`, `AT+TYPE3`), so only the owner's phone can connect.
    pub fn with_pin(mut self, pin: Pin) -> Self {
        self.pin = Some(pin);
        self
    }

    /// The PIN the script sets, if any.
    pub fn pin(&self) -> Option<Pin> {
        self.pin
    }

    /// The UART rate the script currently expects.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Advances the script with the bytes received since the last call.
    pub fn poll(&mut self, now_ms: u32, received: &[u8]) -> Action<'_> {
        if let Some(outcome) = self.outcome {
            return Action::Done(outcome);
        }
        for &byte in received {
            if self.reply.push(byte).is_err() {
                // Keep the newest bytes: the reply we wait for is at the end.
                self.reply.remove(0);
                let _ = self.reply.push(byte);
            }
        }
        if contains(&self.reply, b"OK+CONN")
            || (self.stage == Stage::Listen && !self.reply.is_empty())
        {
            return self.disconnect(now_ms);
        }
        if core::mem::take(&mut self.baud_pending) {
            return Action::SetBaud(self.baud);
        }
        if core::mem::take(&mut self.send_pending) {
            self.reply.clear();
            self.deadline_ms = now_ms.wrapping_add(REPLY_TIMEOUT_MS);
            return Action::Send(&self.command);
        }
        if self.reply_complete() {
            return self.advance(now_ms);
        }
        if !reached(now_ms, self.deadline_ms) {
            return Action::Wait {
                until_ms: self.deadline_ms,
            };
        }
        match self.stage {
            // A phone dropped without a word still lets the script go on.
            Stage::Listen | Stage::Reboot | Stage::Disconnect => self.advance(now_ms),
            _ if self.tries_left > 1 => {
                self.tries_left -= 1;
                self.send_pending = true;
                self.poll(now_ms, &[])
            }
            Stage::ProbeFast => {
                self.factory = true;
                self.baud = FACTORY_BAUD;
                self.baud_pending = true;
                self.enter(Stage::ProbeFactory);
                self.poll(now_ms, &[])
            }
            Stage::ProbeFactory => self.finish(Outcome::NoModule),
            stage => self.finish(Outcome::Failed { stage }),
        }
    }

    fn reply_complete(&self) -> bool {
        let expected: &[u8] = match self.stage {
            Stage::Listen | Stage::Reboot => return false,
            Stage::ProbeFast | Stage::ProbeFactory | Stage::Verify | Stage::Disconnect => b"OK",
            Stage::Name | Stage::Notifications | Stage::Pin | Stage::Bonding | Stage::Baud => {
                b"OK+Set"
            }
            Stage::Reset => b"OK+RESET",
        };
        contains(&self.reply, expected)
    }

    fn advance(&mut self, now_ms: u32) -> Action<'_> {
        let next = match self.stage {
            Stage::Disconnect if self.factory => Stage::ProbeFactory,
            Stage::Listen | Stage::Disconnect => Stage::ProbeFast,
            Stage::ProbeFast | Stage::ProbeFactory => Stage::Name,
            Stage::Name => Stage::Notifications,
            Stage::Notifications if self.pin.is_some() => Stage::Pin,
            Stage::Pin => Stage::Bonding,
            Stage::Notifications | Stage::Bonding if self.factory => Stage::Baud,
            Stage::Notifications | Stage::Bonding | Stage::Baud => Stage::Reset,
            Stage::Reset => {
                self.stage = Stage::Reboot;
                self.deadline_ms = now_ms.wrapping_add(REBOOT_MS);
                if self.factory {
                    self.baud = RELAY_BAUD;
                    return Action::SetBaud(self.baud);
                }
                return Action::Wait {
                    until_ms: self.deadline_ms,
                };
            }
            Stage::Reboot => Stage::Verify,
            Stage::Verify => return self.finish(Outcome::Configured { baud: self.baud }),
        };
        self.enter(next);
        self.poll(now_ms, &[])
    }

    fn enter(&mut self, stage: Stage) {
        self.stage = stage;
        self.tries_left = TRIES;
        self.send_pending = true;
        self.command.clear();
        let pin = self.pin.map(Pin::digits).unwrap_or([b'0'; 6]);
        let parts: [&[u8]; 2] = match stage {
            Stage::ProbeFast | Stage::ProbeFactory | Stage::Verify | Stage::Disconnect => {
                [b"AT", b""]
            }
            Stage::Name => [b"AT+NAME", &self.name],
            Stage::Notifications => [b"AT+NOTI1", b""],
            Stage::Pin => [b"AT+PASS", &pin],
            Stage::Bonding => [b"AT+TYPE3", b""],
            Stage::Baud => [b"AT+BAUD4", b""],
            Stage::Reset => [b"AT+RESET", b""],
            Stage::Listen | Stage::Reboot => [b"", b""],
        };
        for part in parts {
            // 8 + 12 bytes fit the 24-byte command buffer.
            let _ = self.command.extend_from_slice(part);
        }
    }

    /// A phone is connected: a lone `AT` drops it, then the script starts over from the
    /// probe at the rate it heard the phone on; after [`MAX_DISCONNECTS`] it gives up.
    fn disconnect(&mut self, now_ms: u32) -> Action<'_> {
        if self.disconnects >= MAX_DISCONNECTS {
            return self.finish(Outcome::Failed {
                stage: Stage::Disconnect,
            });
        }
        self.disconnects += 1;
        self.reply.clear();
        self.enter(Stage::Disconnect);
        self.poll(now_ms, &[])
    }

    fn finish(&mut self, outcome: Outcome) -> Action<'_> {
        self.outcome = Some(outcome);
        Action::Done(outcome)
    }
}

#[cfg(test)]
#[path = "at_tests.rs"]
mod tests;
