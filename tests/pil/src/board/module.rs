//! The TauLink module (nRF52840 on a nice!nano-class board). Every pin is named once, in
//! [`ModulePins`], from `hardware/taulink-module/README.md` and
//! `taulink-module/module-fw/src/firmware/board.rs` — the same facts.
//!
//! | what | pins | model |
//! |---|---|---|
//! | RFM22B | SPIM (SCK P0.17, MOSI P0.20, MISO P0.22), nSEL P0.24, nIRQ P0.11, SDN P1.00 (10 k pull-down) | [`Rfm22b`] |
//! | PPM in (JR pin 1) | P1.04 | the handset's PPM edges |
//! | JR pin 5 | UARTE0 TX P0.06, RX P0.08, buffer OE P0.09, XOR P0.10 | [`JrLine`] |
//! | HM-10 | UARTE1 TX P1.11 → its RXD, its TXD → RX P1.13 | [`Hm10`] |
//! | bind button | P1.15 to GND (internal pull-up) | released |
//! | radio battery (JR pin 3) | P0.02 = AIN0, 100 k / 22 k | the handset's pack |
//! | status LED | P0.15, active high | recorded |
//!
//! The RFM22B is the only SPI device, so whichever SPIM the image drives its pins with
//! reaches it (the anomaly-198 fix may move it between SPIM instances).

use std::collections::HashMap;

use super::{MISO_FLOATING, Outbox, Trace};
use crate::chips::handset::{CRSF_BAUD, JrLine};
use crate::chips::hm10::Hm10;
use crate::chips::rfm22b::Rfm22b;
use crate::chips::uart::{Link, Received, frame_ns};
use crate::wire::{Drive, I2cReply, I2cStep, Outside, Pin, Pull};

const P0: u8 = 0;
const P1: u8 = 1;

/// Where everything is on the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModulePins {
    /// RFM22B nSEL.
    pub radio_nsel: Pin,
    /// RFM22B nIRQ.
    pub radio_nirq: Pin,
    /// RFM22B SDN (high = shutdown).
    pub radio_sdn: Pin,
    /// PPM input.
    pub ppm_in: Pin,
    /// The JR line's UART (the SoC model's numbering: 1 = UARTE0).
    pub jr_uart: u8,
    /// Buffer output enable (high: the module drives the wire).
    pub jr_driver_enable: Pin,
    /// XOR control (high: inverted).
    pub jr_invert: Pin,
    /// The HM-10's UART (2 = UARTE1).
    pub hm10_uart: u8,
    /// Bind button, to GND.
    pub bind_button: Pin,
    /// Radio battery sense.
    pub battery: Pin,
    /// Status LED, active high.
    pub status_led: Pin,
}

/// The module's pins.
pub const PINS: ModulePins = ModulePins {
    radio_nsel: Pin::new(P0, 24),
    radio_nirq: Pin::new(P0, 11),
    radio_sdn: Pin::new(P1, 0),
    ppm_in: Pin::new(P1, 4),
    jr_uart: 1,
    jr_driver_enable: Pin::new(P0, 9),
    jr_invert: Pin::new(P0, 10),
    hm10_uart: 2,
    bind_button: Pin::new(P1, 15),
    battery: Pin::new(P0, 2),
    status_led: Pin::new(P0, 15),
};

/// JR pin 3 → P0.02: 100 k over 22 k.
pub const BATTERY_DIVIDER: f64 = 122.0 / 22.0;

/// The module board with its chips and the handset and phone around it.
pub struct ModuleBoard {
    /// The radio.
    pub radio: Rfm22b,
    /// The HM-10 and its phone.
    pub hm10: Hm10,
    /// The JR pin 5 wire.
    pub jr: JrLine,
    /// The status LED.
    pub led: Trace,
    /// What the handset read from the module on the JR line: (time ns, byte).
    pub handset_rx: Vec<(u64, u8)>,
    outbox: Outbox,
    drives: HashMap<Pin, Drive>,
    uart_baud: HashMap<u8, u32>,
    hm10_link: Link,
    /// The handset's pack, V.
    pub radio_battery_v: f64,
    /// The bind button is held.
    pub button_pressed: bool,
}

impl ModuleBoard {
    /// The board at power-on with its radio and an HM-10 that has `hm10` in its flash.
    pub fn new(radio: Rfm22b, hm10: Hm10) -> Self {
        Self {
            radio,
            hm10,
            jr: JrLine::new(CRSF_BAUD),
            led: Trace::default(),
            handset_rx: Vec::new(),
            outbox: Outbox::default(),
            drives: HashMap::new(),
            uart_baud: HashMap::new(),
            hm10_link: Link::new(9_600),
            radio_battery_v: 7.4,
            button_pressed: false,
        }
    }

    /// The inputs waiting for the MCU.
    pub fn outbox(&mut self) -> &mut Outbox {
        &mut self.outbox
    }

    /// The MCU's UART `uart` runs at `baud`.
    pub fn set_uart_baud(&mut self, uart: u8, baud: u32) {
        self.uart_baud.insert(uart, baud);
        if uart == PINS.jr_uart {
            self.jr.set_module_baud(baud);
        }
    }

    fn baud(&self, uart: u8) -> u32 {
        self.uart_baud.get(&uart).copied().unwrap_or(115_200)
    }

    /// nIRQ's changes go to the MCU.
    pub fn forward_radio(&mut self) {
        for (t, level) in self.radio.take_nirq_edges() {
            self.outbox.pin(PINS.radio_nirq, level, t);
        }
    }

    /// PPM edges from the handset.
    pub fn ppm(&mut self, edges: &[(u64, bool)]) {
        for &(t, level) in edges {
            self.outbox.pin(PINS.ppm_in, level, t);
        }
    }

    /// A CRSF frame from the handset, its first byte from `start_ns`.
    pub fn crsf_from_handset(&mut self, frame: &[u8], start_ns: u64) {
        let mut t = start_ns;
        for &b in frame {
            let got = self.jr.from_handset(b, t);
            self.queue_rx(PINS.jr_uart, got);
            t += frame_ns(CRSF_BAUD);
        }
    }

    fn queue_rx(&mut self, uart: u8, got: Vec<Received>) {
        for r in got {
            self.outbox.uart(uart, r.byte, r.at_ns);
        }
    }

    /// The HM-10 and the JR line brought to `now_ns`; their bytes go to the MCU.
    pub fn tick(&mut self, now_ns: u64) {
        self.hm10.tick(now_ns);
        let mcu = self.baud(PINS.hm10_uart);
        self.hm10_link.set_rx_baud(mcu);
        for (start, byte, baud) in self.hm10.take_output() {
            let got = self.hm10_link.send(byte, start, baud, false);
            self.queue_rx(PINS.hm10_uart, got);
        }
        let tail = self.hm10_link.flush(now_ns);
        self.queue_rx(PINS.hm10_uart, tail);
        let (module, handset) = self.jr.flush(now_ns);
        self.queue_rx(PINS.jr_uart, module);
        self.handset_rx
            .extend(handset.into_iter().map(|r| (r.at_ns, r.byte)));
    }

    fn level_out(drive: Drive) -> bool {
        match drive {
            Drive::High => true,
            Drive::Low => false,
            Drive::Released(pull) => pull == Pull::Up,
        }
    }
}

impl Outside for ModuleBoard {
    fn pin_driven(&mut self, pin: Pin, drive: Drive, now_ns: u64) {
        self.drives.insert(pin, drive);
        if pin == PINS.radio_nsel {
            self.radio.nsel(drive == Drive::Low);
            if drive != Drive::Low {
                self.forward_radio();
            }
        } else if pin == PINS.radio_sdn {
            // Released: the board's 10 k pull-down keeps the radio on.
            self.radio.sdn(drive == Drive::High);
        } else if pin == PINS.jr_invert {
            self.jr.invert = Self::level_out(drive);
        } else if pin == PINS.jr_driver_enable {
            self.jr.driving = drive == Drive::High;
        } else if pin == PINS.status_led {
            self.led.set(now_ns, drive == Drive::High);
        }
    }

    fn pin_level(&mut self, pin: Pin, _now_ns: u64) -> Option<bool> {
        // The button to GND; everything dynamic (nIRQ, PPM) comes queued.
        (pin == PINS.bind_button && self.button_pressed).then_some(false)
    }

    fn spi_byte(&mut self, _bus: u8, mosi: u8, _now_ns: u64) -> u8 {
        self.radio.byte(mosi).unwrap_or(MISO_FLOATING)
    }

    fn i2c_step(&mut self, _bus: u8, step: I2cStep, _now_ns: u64) -> I2cReply {
        match step {
            I2cStep::Address { .. } | I2cStep::Write(_) => I2cReply::Nack,
            I2cStep::Read { .. } => I2cReply::Data(0xFF),
            I2cStep::Start | I2cStep::Stop => I2cReply::Ack,
        }
    }

    fn uart_sent(&mut self, uart: u8, byte: u8, now_ns: u64) {
        let baud = self.baud(uart);
        let start = now_ns.saturating_sub(frame_ns(baud));
        if uart == PINS.hm10_uart {
            self.hm10.receive(byte, start, baud);
        } else if uart == PINS.jr_uart {
            let (handset, echo) = self.jr.from_module(byte, start, baud);
            self.handset_rx
                .extend(handset.into_iter().map(|r| (r.at_ns, r.byte)));
            self.queue_rx(PINS.jr_uart, echo);
        }
    }

    fn analog_volts(&mut self, pin: Pin, _now_ns: u64) -> f32 {
        if pin == PINS.battery {
            (self.radio_battery_v / BATTERY_DIVIDER) as f32
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::Input;
    use crate::chips::hm10::Config;
    use si4432_sim::{RadioConfig, Simulation};

    fn board() -> (Simulation, ModuleBoard) {
        let sim = Simulation::new(1);
        let radio = Rfm22b::new(sim.medium().add_radio(RadioConfig::default()));
        (
            sim,
            ModuleBoard::new(radio, Hm10::new(Config::default(), 0)),
        )
    }

    #[test]
    fn the_radio_answers_on_any_spim_while_nsel_is_low_and_sdn_shuts_it_down() {
        let (_sim, mut b) = board();
        assert_eq!(b.spi_byte(4, 0x00, 0), MISO_FLOATING);
        b.pin_driven(PINS.radio_nsel, Drive::Low, 0);
        b.spi_byte(4, 0x00, 0);
        assert_eq!(b.spi_byte(4, 0x00, 0), 0x08, "Si4432 device type");
        b.pin_driven(PINS.radio_nsel, Drive::High, 0);
        b.pin_driven(PINS.radio_sdn, Drive::High, 0);
        b.pin_driven(PINS.radio_nsel, Drive::Low, 0);
        assert_eq!(b.spi_byte(1, 0x00, 0), MISO_FLOATING, "shut down");
    }

    #[test]
    fn crsf_reaches_uarte0_through_the_xor_and_the_reply_needs_the_buffer() {
        let (_sim, mut b) = board();
        b.set_uart_baud(PINS.jr_uart, 399_994);
        b.crsf_from_handset(&[0xEE, 0x18, 0x16], 1_000);
        let got: Vec<u8> = b
            .outbox()
            .take()
            .into_iter()
            .filter_map(|i| match i {
                Input::Uart { uart: 1, byte, .. } => Some(byte),
                _ => None,
            })
            .collect();
        assert_eq!(got, vec![0xEE, 0x18, 0x16]);
        b.uart_sent(PINS.jr_uart, 0xEA, 100_000);
        assert!(
            b.handset_rx.is_empty(),
            "buffer off: the wire stays the handset's"
        );
        b.pin_driven(PINS.jr_driver_enable, Drive::High, 100_000);
        b.uart_sent(PINS.jr_uart, 0xEA, 200_000);
        assert_eq!(b.handset_rx.len(), 1);
        assert_eq!(b.handset_rx[0].1, 0xEA);
        // And the module hears itself.
        assert!(
            b.outbox()
                .take()
                .iter()
                .any(|i| matches!(i, Input::Uart { byte: 0xEA, .. }))
        );
    }

    #[test]
    fn the_hm10_answers_the_module_at_its_factory_rate() {
        let (_sim, mut b) = board();
        b.set_uart_baud(PINS.hm10_uart, 9_600);
        let mut t = 1_000_000;
        for &c in b"AT" {
            t += frame_ns(9_600);
            b.uart_sent(PINS.hm10_uart, c, t);
        }
        for k in 0..40 {
            b.tick(t + k * 1_000_000);
        }
        let got: Vec<u8> = b
            .outbox()
            .take()
            .into_iter()
            .filter_map(|i| match i {
                Input::Uart { uart: 2, byte, .. } => Some(byte),
                _ => None,
            })
            .collect();
        assert_eq!(got, b"OK");
    }
}
