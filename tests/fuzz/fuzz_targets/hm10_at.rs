//! The HM-10 configuration script (`module_core::hm10::at::Configurator`) fed fuzzed replies
//! from the module (or a phone, or line noise) at fuzzed times.
//!
//! Invariants: the script only ever sends AT commands that fit its buffer and switches only
//! between the two known baud rates; `OK+CONN` in what it receives ends it at once with the
//! phone connected (a lone `AT` would disconnect the phone); once done it stays done with
//! the same outcome.
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::hm10::at::{
    Action, Configurator, FACTORY_BAUD, MAX_NAME_LEN, Outcome, RELAY_BAUD,
};
use taulink_fuzz::Input;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let name = String::from_utf8_lossy(input.chunk(16)).into_owned();
    let mut now = input.u32();
    let mut script = Configurator::new(&name, now);
    let mut done: Option<Outcome> = None;
    while !input.is_empty() {
        now = now.wrapping_add(u32::from(input.u16()));
        let received = input.chunk(40);
        let phone = received.windows(7).any(|w| w == b"OK+CONN");
        let action = script.poll(now, received);
        if let Some(outcome) = done {
            assert_eq!(
                action,
                Action::Done(outcome),
                "a finished script acted again"
            );
            continue;
        }
        if phone {
            assert!(
                matches!(action, Action::Done(Outcome::PhoneConnected { .. })),
                "OK+CONN did not stop the script: {action:?}"
            );
        }
        match action {
            Action::SetBaud(baud) => assert!(baud == FACTORY_BAUD || baud == RELAY_BAUD),
            Action::Send(command) => {
                assert!(command.starts_with(b"AT"));
                assert!(command.len() <= "AT+NAME".len() + MAX_NAME_LEN);
            }
            Action::Wait { .. } => {}
            Action::Done(outcome) => {
                if let Outcome::Configured { baud } | Outcome::PhoneConnected { baud } = outcome {
                    assert!(baud == FACTORY_BAUD || baud == RELAY_BAUD);
                }
                done = Some(outcome);
            }
        }
        assert!(script.baud() == FACTORY_BAUD || script.baud() == RELAY_BAUD);
    }
});
