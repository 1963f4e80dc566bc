use super::*;

/// An HMSoft module as §5 describes it: answers only at its own rate, no CR/LF.
struct FakeHm10 {
    baud: u32,
    name: Vec<u8, 32>,
    notify: bool,
    pin: Option<std::vec::Vec<u8>>,
    auth_type: u8,
    /// Baud rate set by AT+BAUD4, applied at reset.
    next_baud: u32,
    answers_name: bool,
    reply: std::vec::Vec<u8>,
    /// Bytes the module sends unprompted at the start (phone traffic, notifications).
    unprompted: std::vec::Vec<u8>,
}

impl FakeHm10 {
    fn new(baud: u32) -> Self {
        Self {
            baud,
            name: Vec::new(),
            notify: false,
            pin: None,
            auth_type: 0,
            next_baud: baud,
            answers_name: true,
            reply: std::vec::Vec::new(),
            unprompted: std::vec::Vec::new(),
        }
    }

    fn write(&mut self, uart_baud: u32, bytes: &[u8]) {
        if uart_baud != self.baud {
            return; // garbage to the module
        }
        let reply: std::vec::Vec<u8> = match bytes {
            b"AT" => b"OK".to_vec(),
            b"AT+NOTI1" => {
                self.notify = true;
                b"OK+Set:1".to_vec()
            }
            b"AT+BAUD4" => {
                self.next_baud = 115_200;
                b"OK+Set:4".to_vec()
            }
            b"AT+RESET" => {
                self.baud = self.next_baud;
                b"OK+RESET".to_vec()
            }
            b"AT+TYPE3" => {
                self.auth_type = 3;
                b"OK+Set:3".to_vec()
            }
            _ if bytes.starts_with(b"AT+PASS") && bytes.len() == 13 => {
                self.pin = Some(bytes[7..].to_vec());
                [b"OK+Set:".as_slice(), &bytes[7..]].concat()
            }
            _ if bytes.starts_with(b"AT+NAME") && self.answers_name => {
                self.name = Vec::from_slice(&bytes[7..]).unwrap();
                [b"OK+Set:".as_slice(), &bytes[7..]].concat()
            }
            _ => return,
        };
        // The reply leaves at the module's old rate (before a reset applies a new one).
        self.reply = reply;
    }
}

/// Runs the script against the fake; returns the outcome and every (baud, command) sent.
fn run(
    module: &mut FakeHm10,
    script: &mut Configurator,
) -> (Outcome, std::vec::Vec<(u32, std::vec::Vec<u8>)>) {
    let mut now = 0u32;
    let mut uart_baud = 0u32;
    let mut sent = std::vec::Vec::new();
    let mut received = core::mem::take(&mut module.unprompted);
    for _ in 0..200 {
        let action = script.poll(now, &received);
        received.clear();
        match action {
            Action::Done(outcome) => return (outcome, sent),
            Action::SetBaud(baud) => uart_baud = baud,
            Action::Send(bytes) => {
                sent.push((uart_baud, bytes.to_vec()));
                module.write(uart_baud, bytes);
            }
            Action::Wait { until_ms } => {
                if module.reply.is_empty() {
                    now = until_ms;
                } else {
                    now += 5;
                    received = core::mem::take(&mut module.reply);
                }
            }
        }
    }
    panic!("script did not finish");
}

fn commands(sent: &[(u32, std::vec::Vec<u8>)]) -> std::vec::Vec<(u32, &str)> {
    sent.iter()
        .map(|(baud, bytes)| (*baud, core::str::from_utf8(bytes).unwrap()))
        .collect()
}

#[test]
fn factory_module_is_moved_to_115200() {
    let mut module = FakeHm10::new(9_600);
    let mut script = Configurator::new("TauLink", 0);
    let (outcome, sent) = run(&mut module, &mut script);
    assert_eq!(outcome, Outcome::Configured { baud: 115_200 });
    assert_eq!(
        commands(&sent),
        [
            (115_200, "AT"),
            (115_200, "AT"),
            (9_600, "AT"),
            (9_600, "AT+NAMETauLink"),
            (9_600, "AT+NOTI1"),
            (9_600, "AT+BAUD4"),
            (9_600, "AT+RESET"),
            (115_200, "AT"),
        ]
    );
    assert_eq!(module.baud, 115_200);
    assert_eq!(&module.name[..], b"TauLink");
    assert!(module.notify);
}

#[test]
fn configured_module_keeps_its_rate() {
    let mut module = FakeHm10::new(115_200);
    let mut script = Configurator::new("TauLink-with-a-long-name", 0);
    let (outcome, sent) = run(&mut module, &mut script);
    assert_eq!(outcome, Outcome::Configured { baud: 115_200 });
    assert_eq!(
        commands(&sent),
        [
            (115_200, "AT"),
            (115_200, "AT+NAMETauLink-with"),
            (115_200, "AT+NOTI1"),
            (115_200, "AT+RESET"),
            (115_200, "AT"),
        ]
    );
}

#[test]
fn no_module_gives_up_after_both_rates() {
    let mut module = FakeHm10::new(38_400);
    let mut script = Configurator::new("TauLink", 0);
    let (outcome, sent) = run(&mut module, &mut script);
    assert_eq!(outcome, Outcome::NoModule);
    assert_eq!(sent.len(), 4, "two tries at each rate");
}

/// Issue 30, finding 5: a phone talking in the listening window (or an `OK+CONN`) ended the
/// script before `AT+PASS`/`AT+TYPE3`, and a factory HM-10 stayed open to any phone. The
/// phone is now disconnected (a lone `AT`) and the PIN set before anything is relayed.
#[test]
fn a_connected_phone_is_dropped_and_the_pin_is_set_all_the_same() {
    for unprompted in [b"OK+CONN".to_vec(), vec![0x02, 0x14, 0x00]] {
        let mut module = FakeHm10::new(115_200);
        module.unprompted = unprompted;
        let mut script = Configurator::new("TauLink", 0).with_pin(Pin::new(246_810).unwrap());
        let (outcome, sent) = run(&mut module, &mut script);
        assert_eq!(outcome, Outcome::Configured { baud: 115_200 }, "{sent:?}");
        assert_eq!(
            sent.first().map(|(_, c)| c.as_slice()),
            Some(b"AT".as_slice())
        );
        assert_eq!(module.pin.as_deref(), Some(b"246810".as_slice()));
        assert_eq!(module.auth_type, 3, "PIN authentication with bonding");
    }
}

#[test]
fn a_connection_mid_script_is_dropped_and_the_script_starts_over() {
    let mut script = Configurator::new("TauLink", 0);
    assert_eq!(script.poll(0, &[]), Action::SetBaud(115_200));
    assert_eq!(script.poll(0, &[]), Action::Wait { until_ms: 500 });
    assert_eq!(script.poll(500, &[]), Action::Send(b"AT"));
    assert_eq!(script.poll(510, b"OK"), Action::Send(b"AT+NAMETauLink"));
    assert_eq!(script.poll(520, b"OK+CONN"), Action::Send(b"AT"), "dropped");
    assert_eq!(
        script.poll(530, b"OK+LOST"),
        Action::Send(b"AT"),
        "probed again"
    );
    assert_eq!(script.poll(540, b"OK"), Action::Send(b"AT+NAMETauLink"));
    // A phone that keeps coming back: after three drops the script gives up (no relay).
    let mut script = Configurator::new("TauLink", 0);
    let mut now = 0;
    let mut last = script.poll(now, &[]);
    for _ in 0..20 {
        now += 10;
        last = script.poll(now, b"OK+CONN");
        if matches!(last, Action::Done(_)) {
            break;
        }
    }
    assert_eq!(
        last,
        Action::Done(Outcome::Failed {
            stage: Stage::Disconnect
        })
    );
}

#[test]
fn a_module_that_ignores_baud4_fails_verification() {
    let mut module = FakeHm10::new(9_600);
    let mut script = Configurator::new("TauLink", 0);
    // A clone that answers AT+BAUD4 but keeps 9600 after the reset.
    let mut sent = std::vec::Vec::new();
    let mut now = 0u32;
    let mut uart_baud = 0;
    let mut received = std::vec::Vec::new();
    let outcome = loop {
        let action = script.poll(now, &received);
        received.clear();
        match action {
            Action::Done(outcome) => break outcome,
            Action::SetBaud(baud) => uart_baud = baud,
            Action::Send(bytes) => {
                sent.push(bytes.to_vec());
                module.write(uart_baud, bytes);
                module.next_baud = 9_600;
            }
            Action::Wait { until_ms } => {
                if module.reply.is_empty() {
                    now = until_ms;
                } else {
                    now += 5;
                    received = core::mem::take(&mut module.reply);
                }
            }
        }
    };
    assert_eq!(
        outcome,
        Outcome::Failed {
            stage: Stage::Verify
        }
    );
    assert_eq!(sent.last().unwrap(), b"AT");
}

#[test]
fn a_refused_command_fails_its_stage() {
    let mut module = FakeHm10::new(115_200);
    module.answers_name = false;
    let mut script = Configurator::new("TauLink", 0);
    let (outcome, _) = run(&mut module, &mut script);
    assert_eq!(outcome, Outcome::Failed { stage: Stage::Name });
}

#[test]
fn deadlines_survive_the_millisecond_wrap() {
    let start = u32::MAX - 100;
    let mut script = Configurator::new("TauLink", start);
    assert_eq!(script.poll(start, &[]), Action::SetBaud(115_200));
    let until = start.wrapping_add(500);
    assert_eq!(
        script.poll(start + 50, &[]),
        Action::Wait { until_ms: until }
    );
    assert_eq!(script.poll(until, &[]), Action::Send(b"AT"));
}

proptest::proptest! {
    /// Whatever the module answers (garbage, partial replies, notifications), the script
    /// ends within a bounded number of steps, and what it sends right after an `OK+CONN` is
    /// the lone `AT` that drops the phone.
    #[test]
    fn any_replies_end_the_script(
        replies in proptest::collection::vec(proptest::collection::vec(proptest::prelude::any::<u8>(), 0..12), 0..40),
        connect_at in proptest::option::of(0usize..40),
    ) {
        let mut script = Configurator::new("TauLink", 1_000);
        let mut now = 1_000u32;
        let mut replies = replies.into_iter().enumerate();
        let mut connected = false;
        let mut pending: std::vec::Vec<u8> = std::vec::Vec::new();
        let mut finished = None;
        for _ in 0..500 {
            match script.poll(now, &pending) {
                Action::Done(outcome) => {
                    finished = Some(outcome);
                    break;
                }
                Action::Send(command) => {
                    if connected {
                        proptest::prop_assert_eq!(command, b"AT".as_slice(), "the phone dropped first");
                        connected = false;
                    }
                }
                Action::SetBaud(baud) => proptest::prop_assert!(baud == 9_600 || baud == 115_200),
                Action::Wait { until_ms } => {
                    now = until_ms;
                }
            }
            pending.clear();
            if let Some((index, bytes)) = replies.next() {
                pending = bytes;
                if connect_at == Some(index) {
                    pending.extend_from_slice(b"OK+CONN");
                    connected = true;
                }
            }
        }
        let outcome = finished.expect("script must finish");
        // A phone that connected was dropped: the script went on or gave up, never served
        // it unconfigured.
        if connected {
            proptest::prop_assert!(
                matches!(outcome, Outcome::Configured { .. } | Outcome::Failed { .. } | Outcome::NoModule),
                "{:?}", outcome
            );
        }
    }
}

#[test]
fn a_pin_sets_pass_and_bonding_on_both_paths() {
    assert_eq!(Pin::new(1_000_000), None);
    for baud in [FACTORY_BAUD, RELAY_BAUD] {
        let mut module = FakeHm10::new(baud);
        let mut script = Configurator::new("TauLink", 0).with_pin(Pin::new(4_207).unwrap());
        let (outcome, sent) = run(&mut module, &mut script);
        assert_eq!(
            outcome,
            Outcome::Configured { baud: RELAY_BAUD },
            "{sent:?}"
        );
        assert_eq!(module.pin.as_deref(), Some(b"004207".as_slice()));
        assert_eq!(module.auth_type, 3, "PIN authentication with bonding");
        assert!(module.notify);
        assert_eq!(module.baud, RELAY_BAUD);
    }
}

#[test]
fn without_a_pin_the_factory_pairing_is_left_alone() {
    let mut module = FakeHm10::new(RELAY_BAUD);
    let mut script = Configurator::new("TauLink", 0);
    let (outcome, sent) = run(&mut module, &mut script);
    assert_eq!(outcome, Outcome::Configured { baud: RELAY_BAUD });
    assert!(
        sent.iter()
            .all(|(_, c)| !c.starts_with(b"AT+PASS") && !c.starts_with(b"AT+TYPE"))
    );
    assert_eq!(module.auth_type, 0);
}
