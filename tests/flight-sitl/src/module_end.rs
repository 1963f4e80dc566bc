//! The module end of the SITL's link: the master's hooks (pilot channels up, scripted
//! setting changes up, telemetry decoded). A stand-in for the module's application until
//! `module_core::App` runs here on virtual chips; the flight end is the flight firmware's
//! own application (`flight_core::app::FlightApp`, see `world`).

use std::cell::RefCell;
use std::rc::Rc;

use telemetry::channels::Channels;
use telemetry::link::core::Master;
use telemetry::link::master::MasterHooks;
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SettingChange, encode_message,
};

/// The module's clock reads virtual time plus this (the ends count from different epochs).
pub(crate) const MODULE_CLOCK_OFFSET_US: u64 = 1_000_000;

/// What the module end shares with the pilot (the world's flight task).
#[derive(Default)]
pub(crate) struct LinkState {
    /// Channels the pilot's transmitter sends (master side).
    pub(crate) tx: Option<Channels>,
    /// Messages the module decoded from the downlink stream, with the time (s).
    pub(crate) module_rx: Vec<(f64, Message)>,
    /// Setting changes the module is to send up.
    pub(crate) uplink: Vec<SettingChange>,
}

pub(crate) type Shared = Rc<RefCell<LinkState>>;

fn send(stream: &mut impl FnMut(&[u8]) -> usize, free: usize, m: &Message) -> bool {
    let mut buf = [0u8; FRAMED_MAX_BYTES];
    match encode_message(m, &mut buf) {
        Ok(n) if n <= free => stream(buf.get(..n).unwrap_or(&[])) == n,
        _ => false,
    }
}

pub(crate) struct ModuleSide {
    pub(crate) shared: Shared,
    pub(crate) reader: MessageReader,
}

impl MasterHooks for ModuleSide {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let mut s = self.shared.borrow_mut();
        if let Some(ch) = s.tx {
            master.set_channels(&ch);
        }
        if let Some(change) = s.uplink.first().copied() {
            let free = master.uplink_stream.free();
            if send(
                &mut |b| master.uplink_stream.write(b),
                free,
                &Message::SettingChange(change),
            ) {
                s.uplink.remove(0);
            }
        }
        let mut buf = [0u8; 64];
        loop {
            let n = master.downlink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for b in buf.iter().take(n) {
                if let Some(Decoded::Message(m)) = self.reader.push(*b) {
                    s.module_rx
                        .push(((now_us - MODULE_CLOCK_OFFSET_US) as f64 * 1e-6, m));
                }
            }
        }
    }
}
