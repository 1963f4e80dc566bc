//! The HM-10 configuration script (`module_core::hm10::at::Configurator`) fed fuzzed replies
//! from the module (or a phone, or line noise) at fuzzed times, with or without a PIN.
//!
//! Invariants: the script only ever sends AT commands that fit its buffer and switches only
//! between the two known baud rates; once done it stays done with the same outcome; and
//! with a PIN it never ends `Configured` without having sent `AT+PASS` with that PIN and
//! `AT+TYPE3` after them (issue 30, finding 5: a phone talking during the script disconnects
//! it and the script starts over — it never ends early with the PIN unset).
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::hm10::at::{
    Action, Configurator, FACTORY_BAUD, MAX_NAME_LEN, Outcome, Pin, RELAY_BAUD,
};
use taulink_fuzz::Input;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let name = String::from_utf8_lossy(input.chunk(16)).into_owned();
    let pin = input
        .bool()
        .then(|| Pin::new(input.u32() % 1_000_000))
        .flatten();
    let mut now = input.u32();
    let mut script = Configurator::new(&name, now);
    if let Some(pin) = pin {
        script = script.with_pin(pin);
    }
    let pass: Option<Vec<u8>> = pin.map(|p| [b"AT+PASS".as_slice(), &p.digits()].concat());
    let (mut pass_sent, mut bonding_sent) = (false, false);
    let mut done: Option<Outcome> = None;
    while !input.is_empty() {
        now = now.wrapping_add(u32::from(input.u16()));
        let received = input.chunk(40);
        let action = script.poll(now, received);
        if let Some(outcome) = done {
            assert_eq!(
                action,
                Action::Done(outcome),
                "a finished script acted again"
            );
            continue;
        }
        match action {
            Action::SetBaud(baud) => assert!(baud == FACTORY_BAUD || baud == RELAY_BAUD),
            Action::Send(command) => {
                assert!(command.starts_with(b"AT"));
                assert!(command.len() <= "AT+NAME".len() + MAX_NAME_LEN);
                if pass.as_deref() == Some(command) {
                    pass_sent = true;
                } else if command.starts_with(b"AT+PASS") {
                    panic!("a PIN that is not the module's: {command:?}");
                }
                if command == b"AT+TYPE3" {
                    assert!(pass_sent, "bonding before the PIN");
                    bonding_sent = true;
                }
            }
            Action::Wait { .. } => {}
            Action::Done(outcome) => {
                if let Outcome::Configured { baud } = outcome {
                    assert!(baud == FACTORY_BAUD || baud == RELAY_BAUD);
                    if pin.is_some() {
                        assert!(pass_sent && bonding_sent, "configured without the PIN set");
                    }
                }
                done = Some(outcome);
            }
        }
        assert!(script.baud() == FACTORY_BAUD || script.baud() == RELAY_BAUD);
    }
});
