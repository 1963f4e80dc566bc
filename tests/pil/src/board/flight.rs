//! The flight controller boards: BrushedSparky and Sparky2 (STM32F405RG). Every pin is named
//! once, in [`FlightPins`], from `hardware/brushedsparky/README.md` (its pin table covers
//! both boards) and `flight/flight-fw/src/firmware/board.rs` — the same facts.
//!
//! | what | pins | chip |
//! |---|---|---|
//! | MPU-9250 | SPI1 (PA5/PA6/PA7), CS PC4, INT PC5 | [`Mpu9250`], mounted "top, 180°": chip x aft, y right, z up |
//! | MS5611 | I2C1, SCL PB8, SDA PB9, 10 k pull-ups | [`Ms5611`] at 0x77 |
//! | RFM22B | SPI3 (PC10/PC11/PC12), nSEL PA15, nIRQ PB7 (BrushedSparky) / PD2 (Sparky2), SDN tied to GND | [`Rfm22b`] |
//! | M25P16 | SPI3, CS PB3 (Sparky2; unconnected on the BrushedSparky) | [`M25p16`] |
//! | u-blox | USART1, TX PA9 / RX PA10 (Sparky2's Main port) | [`Ublox`] |
//! | motors 1–4 | TIM3 CH3 PB0, CH4 PB1, TIM9 CH2 PA3, CH1 PA2 | [`PulseMeter`] → quad-sim |
//! | LEDs (active low) | PB4 error/alarm, PB5 heartbeat, PB6 RF/link | recorded |
//! | buzzer | PC8 (FET, active high) | recorded |
//! | battery | PC3 = VBAT × 10 k / (10 k + 10 k), current PC2 (≈ 50 mV/A) | from the world |

use std::collections::HashMap;

use flight_app::outputs::{Command, Protocol};

use super::{MISO_FLOATING, Outbox, Trace};
use crate::chips::m25p16::M25p16;
use crate::chips::motors::PulseMeter;
use crate::chips::mpu9250::{Measurement, Mpu9250};
use crate::chips::ms5611::Ms5611;
use crate::chips::rfm22b::Rfm22b;
use crate::chips::uart::{Link, frame_ns};
use crate::chips::ublox::Ublox;
use crate::wire::{Drive, I2cReply, I2cStep, Outside, Pin};

const A: u8 = 0;
const B: u8 = 1;
const C: u8 = 2;
const D: u8 = 3;

/// Which board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlightBoardKind {
    /// BrushedSparky rev 0x22 (the default image).
    BrushedSparky,
    /// Sparky2 (`--features sparky2`).
    Sparky2,
}

impl FlightBoardKind {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            FlightBoardKind::BrushedSparky => "brushedsparky",
            FlightBoardKind::Sparky2 => "sparky2",
        }
    }
}

/// Where everything is on one board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlightPins {
    /// SPI controller of the IMU (SPI1).
    pub imu_spi: u8,
    /// MPU-9250 chip select.
    pub imu_cs: Pin,
    /// MPU-9250 INT (data ready).
    pub imu_int: Pin,
    /// I²C controller of the baro (I2C1).
    pub baro_i2c: u8,
    /// SCL.
    pub scl: Pin,
    /// SDA.
    pub sda: Pin,
    /// SPI controller of the radio (SPI3), shared with the flash.
    pub radio_spi: u8,
    /// RFM22B nSEL.
    pub radio_nsel: Pin,
    /// RFM22B nIRQ.
    pub radio_nirq: Pin,
    /// M25P16 chip select (None: not fitted).
    pub flash_cs: Option<Pin>,
    /// The GPS UART (None: no GPS port).
    pub gps_uart: Option<u8>,
    /// Motor outputs 1–4.
    pub motors: [Pin; 4],
    /// LEDs, active low: error/alarm, heartbeat, RF/link.
    pub leds: [Pin; 3],
    /// The buzzer FET.
    pub buzzer: Pin,
    /// Battery voltage through the divider.
    pub battery: Pin,
    /// Battery current sense.
    pub current: Pin,
}

impl FlightPins {
    /// The pins of `kind`.
    pub const fn of(kind: FlightBoardKind) -> Self {
        let sparky2 = matches!(kind, FlightBoardKind::Sparky2);
        Self {
            imu_spi: 1,
            imu_cs: Pin::new(C, 4),
            imu_int: Pin::new(C, 5),
            baro_i2c: 1,
            scl: Pin::new(B, 8),
            sda: Pin::new(B, 9),
            radio_spi: 3,
            radio_nsel: Pin::new(A, 15),
            // BrushedSparky rev 0x22 moved nIRQ to PB7 (PD2 carries S.Bus there).
            radio_nirq: if sparky2 {
                Pin::new(D, 2)
            } else {
                Pin::new(B, 7)
            },
            flash_cs: if sparky2 { Some(Pin::new(B, 3)) } else { None },
            gps_uart: if sparky2 { Some(1) } else { None },
            motors: [
                Pin::new(B, 0),
                Pin::new(B, 1),
                Pin::new(A, 3),
                Pin::new(A, 2),
            ],
            leds: [Pin::new(B, 4), Pin::new(B, 5), Pin::new(B, 6)],
            buzzer: Pin::new(C, 8),
            battery: Pin::new(C, 3),
            current: Pin::new(C, 2),
        }
    }
}

/// VBAT → PC3: 10 k over 10 k.
pub const BATTERY_DIVIDER: f64 = 2.0;
/// ZXCT1009 current sense into PC2, V per A.
pub const CURRENT_V_PER_A: f64 = 0.05;

/// The MPU-9250's mounting: body FRD from the chip's axes is (−x, y, −z) ("top, 180°",
/// flight-fw's `imu_to_body`); the inverse is the same map.
pub fn body_to_chip(v: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = v;
    [-x, y, -z]
}

/// A flight controller board with its chips.
pub struct FlightBoard {
    /// Which board.
    pub kind: FlightBoardKind,
    /// Its pins.
    pub pins: FlightPins,
    /// The IMU.
    pub mpu: Mpu9250,
    /// The barometer.
    pub baro: Ms5611,
    /// The radio.
    pub radio: Rfm22b,
    /// The data flash (Sparky2).
    pub flash: Option<M25p16>,
    /// The GPS receiver (Sparky2, when the scenario flies one).
    pub gps: Option<Ublox>,
    /// The output protocol the motors are read with.
    pub protocol: Protocol,
    motors: [PulseMeter; 4],
    /// LEDs as driven (high = pin high = LED off, active low).
    pub leds: [Trace; 3],
    /// The buzzer.
    pub buzzer: Trace,
    outbox: Outbox,
    drives: HashMap<Pin, Drive>,
    uart_baud: HashMap<u8, u32>,
    gps_link: Link,
    /// Battery volts and amps now.
    battery_v: f64,
    current_a: f64,
    /// SPI reads of the IMU fail (an injected bus fault): MISO floats.
    pub imu_read_error: bool,
    /// INT's rising edges (data-ready), for the loop's timing.
    pub int_rises: Vec<u64>,
    int_high: bool,
    /// The RFM22B's nSEL was ever driven low.
    pub radio_selected: bool,
}

impl FlightBoard {
    /// `kind` at power-on (virtual `now_ns`), its radio `radio`, motors read as `protocol`,
    /// the chips' oscillators off by the given ppm (MPU-9250, AK8963).
    pub fn new(
        kind: FlightBoardKind,
        radio: Rfm22b,
        protocol: Protocol,
        now_ns: u64,
        imu_ppm: (f64, f64),
    ) -> Self {
        let pins = FlightPins::of(kind);
        Self {
            kind,
            pins,
            mpu: Mpu9250::new(now_ns, imu_ppm.0, imu_ppm.1),
            baro: Ms5611::new(),
            radio,
            flash: pins.flash_cs.map(|_| M25p16::new()),
            gps: None,
            protocol,
            motors: Default::default(),
            leds: Default::default(),
            buzzer: Trace::default(),
            outbox: Outbox::default(),
            drives: HashMap::new(),
            uart_baud: HashMap::new(),
            gps_link: Link::new(115_200),
            battery_v: 0.0,
            current_a: 0.0,
            imu_read_error: false,
            int_rises: Vec::new(),
            int_high: false,
            radio_selected: false,
        }
    }

    /// The board's supply comes up at `now_ns` (a power cycle): the chips start over (the
    /// MPU-9250's start-up, the baro's and flash's power-on state, the radio's POR); the
    /// GPS receiver keeps its configuration only in its battery-backed RAM, which this
    /// model does not have.
    pub fn power_on(&mut self, now_ns: u64, imu_ppm: (f64, f64)) {
        self.mpu = Mpu9250::new(now_ns, imu_ppm.0, imu_ppm.1);
        self.baro = Ms5611::new();
        self.flash = self.pins.flash_cs.map(|_| M25p16::new());
        self.radio.power_on();
        self.int_high = false;
    }

    /// The board loses power at `now_ns`: every output falls (the motors' FET gates and
    /// ESC inputs have pull-downs).
    pub fn power_off(&mut self, now_ns: u64) {
        for m in &mut self.motors {
            m.power_lost(now_ns);
        }
        self.buzzer.set(now_ns, false);
    }

    /// The inputs waiting for the MCU.
    pub fn outbox(&mut self) -> &mut Outbox {
        &mut self.outbox
    }

    /// The MCU's UART `uart` runs at `baud` (the co-simulation reads it off the SoC model).
    pub fn set_uart_baud(&mut self, uart: u8, baud: u32) {
        self.uart_baud.insert(uart, baud);
    }

    fn baud(&self, uart: u8) -> u32 {
        self.uart_baud.get(&uart).copied().unwrap_or(115_200)
    }

    /// The IMU's next sample instant (the world steps the physics to it).
    pub fn next_imu_sample_ns(&self) -> Option<u64> {
        self.mpu.next_sample_ns()
    }

    /// The IMU's sample with the truth in body axes (specific force m/s², rate °/s, field µT,
    /// temperature °C); its data-ready edges go to the MCU.
    pub fn imu_sample(
        &mut self,
        accel_mps2: [f64; 3],
        gyro_dps: [f64; 3],
        mag_ut: [f64; 3],
        temp_c: f64,
    ) {
        self.mpu.schedule_sample(Measurement {
            accel_mps2: body_to_chip(accel_mps2),
            gyro_dps: body_to_chip(gyro_dps),
            mag_ut: body_to_chip(mag_ut),
            temp_c,
        });
        self.forward_int();
    }

    fn forward_int(&mut self) {
        for (t, level) in self.mpu.take_int_edges() {
            if level && !self.int_high {
                self.int_rises.push(t);
            }
            self.int_high = level;
            self.outbox.pin(self.pins.imu_int, level, t);
        }
    }

    /// The truth at `now_ns` for the slow chips: baro (pressure Pa, die °C), battery (V, A).
    pub fn environment(
        &mut self,
        now_ns: u64,
        pressure_pa: f64,
        temp_c: f64,
        battery_v: f64,
        current_a: f64,
    ) {
        self.baro.set_truth(now_ns, pressure_pa, temp_c);
        self.battery_v = battery_v;
        self.current_a = current_a;
    }

    /// The GPS receiver's tick (its solutions and NMEA), and its bytes onto the MCU's RX.
    pub fn gps_tick(
        &mut self,
        now_ns: u64,
        scenario_s: f64,
        position_m: [f64; 3],
        velocity_mps: [f64; 3],
    ) {
        let (Some(gps), Some(uart)) = (self.gps.as_mut(), self.pins.gps_uart) else {
            return;
        };
        gps.tick(now_ns, scenario_s, position_m, velocity_mps);
        let out = gps.take_output();
        let mcu_baud = self.uart_baud.get(&uart).copied().unwrap_or(115_200);
        self.gps_link.set_rx_baud(mcu_baud);
        for (start, byte, baud) in out {
            for r in self.gps_link.send(byte, start, baud, false) {
                self.outbox.uart(uart, r.byte, r.at_ns);
            }
        }
        for r in self.gps_link.flush(now_ns) {
            self.outbox.uart(uart, r.byte, r.at_ns);
        }
    }

    /// nIRQ's changes since the last call go to the MCU (after the medium moved).
    pub fn forward_radio(&mut self) {
        for (t, level) in self.radio.take_nirq_edges() {
            self.outbox.pin(self.pins.radio_nirq, level, t);
        }
    }

    /// What each motor makes of its pin at `now_ns`.
    pub fn motor_commands(&self, now_ns: u64) -> [Command; 4] {
        std::array::from_fn(|i| {
            self.motors
                .get(i)
                .map_or(Command::Stopped, |m| m.command(&self.protocol, now_ns))
        })
    }

    /// Complete pulses of the motors since the last call: (start ns, width ns, motor).
    pub fn take_motor_pulses(&mut self) -> Vec<(u64, u64, usize)> {
        let mut v: Vec<(u64, u64, usize)> = self
            .motors
            .iter_mut()
            .enumerate()
            .flat_map(|(i, m)| {
                m.take_starts();
                m.take_pulses().into_iter().map(move |(s, w)| (s, w, i))
            })
            .collect();
        v.sort_unstable();
        v
    }

    /// Data-ready rises since the last call.
    pub fn take_int_rises(&mut self) -> Vec<u64> {
        std::mem::take(&mut self.int_rises)
    }

    /// The last complete pulse width of each motor, ns (None: none yet).
    pub fn motor_pulses(&self) -> [Option<u64>; 4] {
        std::array::from_fn(|i| self.motors.get(i).and_then(|m| m.last_pulse()).map(|p| p.0))
    }

    fn level_out(drive: Drive) -> bool {
        match drive {
            Drive::High => true,
            Drive::Low => false,
            Drive::Released(pull) => pull != crate::wire::Pull::Down,
        }
    }

    /// SCL or SDA as the bus carries it: low if the MCU or a chip pulls it, else the
    /// board's pull-up.
    fn i2c_line(&self, pin: Pin) -> bool {
        let mcu_low = self.drives.get(&pin) == Some(&Drive::Low);
        let chip_low = pin == self.pins.sda && self.baro.holds_sda();
        !(mcu_low || chip_low)
    }
}

impl Outside for FlightBoard {
    fn pin_driven(&mut self, pin: Pin, drive: Drive, now_ns: u64) {
        self.drives.insert(pin, drive);
        let p = self.pins;
        let low = drive == Drive::Low;
        if pin == p.imu_cs {
            if low {
                self.mpu.select(now_ns);
            } else {
                self.mpu.deselect();
                // A read may have cleared a latched data-ready.
                self.forward_int();
            }
        } else if pin == p.radio_nsel {
            self.radio_selected |= low;
            self.radio.nsel(low);
            if !low {
                self.forward_radio();
            }
        } else if Some(pin) == p.flash_cs {
            if let Some(f) = self.flash.as_mut() {
                f.select(low);
            }
        } else if pin == p.scl {
            let level = self.i2c_line(p.scl);
            self.baro.scl(level);
        } else if pin == p.sda {
            let level = self.i2c_line(p.sda);
            self.baro.sda(level);
        } else if let Some(i) = p.motors.iter().position(|m| *m == pin) {
            // The FET gates and ESC inputs have pull-downs: a released pin is low.
            if let Some(m) = self.motors.get_mut(i) {
                m.edge(now_ns, drive == Drive::High);
            }
        } else if let Some(i) = p.leds.iter().position(|l| *l == pin) {
            if let Some(l) = self.leds.get_mut(i) {
                l.set(now_ns, Self::level_out(drive));
            }
        } else if pin == p.buzzer {
            self.buzzer.set(now_ns, drive == Drive::High);
        }
    }

    fn pin_level(&mut self, pin: Pin, _now_ns: u64) -> Option<bool> {
        let p = self.pins;
        if pin == p.scl || pin == p.sda {
            // 10 k pull-ups on the board; the baro may hold SDA.
            return Some(self.i2c_line(pin));
        }
        // INT and nIRQ are conveyed by queued levels (their exact times).
        None
    }

    fn spi_byte(&mut self, bus: u8, mosi: u8, now_ns: u64) -> u8 {
        let p = self.pins;
        if bus == p.imu_spi {
            let miso = self.mpu.byte(mosi, now_ns);
            self.forward_int();
            if self.imu_read_error {
                return MISO_FLOATING;
            }
            return miso.unwrap_or(MISO_FLOATING);
        }
        if bus == p.radio_spi {
            let radio = self.radio.byte(mosi);
            let flash = self.flash.as_mut().and_then(|f| f.byte(mosi));
            // Two drivers at once fight; the low bits win (wired-AND of the contention).
            return match (radio, flash) {
                (Some(a), Some(b)) => a & b,
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => MISO_FLOATING,
            };
        }
        MISO_FLOATING
    }

    fn i2c_step(&mut self, bus: u8, step: I2cStep, now_ns: u64) -> I2cReply {
        if bus != self.pins.baro_i2c {
            return match step {
                I2cStep::Address { .. } | I2cStep::Write(_) => I2cReply::Nack,
                I2cStep::Read { .. } => I2cReply::Data(0xFF),
                _ => I2cReply::Ack,
            };
        }
        self.baro.step(step, now_ns)
    }

    fn uart_sent(&mut self, uart: u8, byte: u8, now_ns: u64) {
        if Some(uart) != self.pins.gps_uart {
            return;
        }
        let baud = self.baud(uart);
        if let Some(gps) = self.gps.as_mut() {
            gps.receive(byte, now_ns.saturating_sub(frame_ns(baud)), baud);
        }
    }

    fn analog_volts(&mut self, pin: Pin, _now_ns: u64) -> f32 {
        if pin == self.pins.battery {
            (self.battery_v / BATTERY_DIVIDER) as f32
        } else if pin == self.pins.current {
            (self.current_a * CURRENT_V_PER_A) as f32
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::Input;
    use si4432_sim::{RadioConfig, Simulation};

    fn board(kind: FlightBoardKind) -> FlightBoard {
        let sim = Simulation::new(1);
        let radio = Rfm22b::new(sim.medium().add_radio(RadioConfig::default()));
        FlightBoard::new(
            kind,
            radio,
            Protocol::Brushed {
                frequency_hz: 32_000,
            },
            0,
            (0.0, 0.0),
        )
    }

    #[test]
    fn the_two_boards_differ_in_nirq_flash_and_gps() {
        let b = FlightPins::of(FlightBoardKind::BrushedSparky);
        let s = FlightPins::of(FlightBoardKind::Sparky2);
        assert_eq!(
            (b.radio_nirq, s.radio_nirq),
            (Pin::new(1, 7), Pin::new(3, 2))
        );
        assert_eq!((b.flash_cs, s.flash_cs), (None, Some(Pin::new(1, 3))));
        assert_eq!((b.gps_uart, s.gps_uart), (None, Some(1)));
        assert_eq!(b.motors, s.motors);
    }

    #[test]
    fn the_imu_answers_on_spi1_only_while_pc4_is_low() {
        let mut b = board(FlightBoardKind::BrushedSparky);
        let t = crate::chips::mpu9250::START_UP_NS;
        let cs = b.pins.imu_cs;
        assert_eq!(b.spi_byte(1, 0x80 | 0x75, t), MISO_FLOATING);
        b.pin_driven(cs, Drive::Low, t);
        b.spi_byte(1, 0x80 | 0x75, t);
        assert_eq!(b.spi_byte(1, 0, t), 0x71, "WHO_AM_I");
        b.pin_driven(cs, Drive::High, t);
        // SPI3 carries the radio, not the IMU.
        b.pin_driven(cs, Drive::Low, t);
        assert_eq!(b.spi_byte(3, 0x75, t), MISO_FLOATING);
    }

    #[test]
    fn data_ready_reaches_pc5_with_the_sample_time_and_the_mounting_flips_x_and_z() {
        let mut b = board(FlightBoardKind::BrushedSparky);
        let t = crate::chips::mpu9250::START_UP_NS;
        let cs = b.pins.imu_cs;
        let write = |b: &mut FlightBoard, r: u8, v: u8| {
            b.pin_driven(cs, Drive::Low, t);
            b.spi_byte(1, r, t);
            b.spi_byte(1, v, t);
            b.pin_driven(cs, Drive::High, t);
        };
        write(&mut b, 0x1A, 0x01);
        write(&mut b, 0x38, 0x01);
        write(&mut b, 0x1C, 0x00);
        let due = b.next_imu_sample_ns().unwrap();
        // Level on the ground: body specific force −1 g on z, i.e. +1 g on the chip's z.
        b.imu_sample([0.5, 0.0, -9.806_65], [10.0, 0.0, 0.0], [0.0; 3], 25.0);
        let inputs = b.outbox().take();
        assert_eq!(
            inputs[0],
            Input::Pin {
                pin: Pin::new(2, 5),
                level: true,
                at_ns: due
            }
        );
        b.pin_driven(cs, Drive::Low, due);
        b.spi_byte(1, 0x80 | 0x3B, due);
        let bytes: Vec<u8> = (0..6).map(|_| b.spi_byte(1, 0, due)).collect();
        b.pin_driven(cs, Drive::High, due);
        let ax = i16::from_be_bytes([bytes[0], bytes[1]]);
        let az = i16::from_be_bytes([bytes[4], bytes[5]]);
        assert!(ax < 0, "body forward is the chip's −x: {ax}");
        assert_eq!(az, 16_384, "+1 g on the chip's z");
        assert_eq!(b.int_rises, vec![due]);
    }

    #[test]
    fn a_stuck_baro_holds_sda_until_the_firmware_clocks_pb8() {
        let mut b = board(FlightBoardKind::BrushedSparky);
        let (scl, sda) = (b.pins.scl, b.pins.sda);
        b.baro.hold_sda_low(9);
        assert_eq!(b.pin_level(sda, 0), Some(false));
        assert_eq!(b.i2c_step(1, I2cStep::Start, 0), I2cReply::Stuck);
        // The recovery: PB8 as open-drain GPIO, nine pulses, then a STOP by hand on PB9.
        for k in 0..9 {
            b.pin_driven(scl, Drive::Low, k * 10);
            b.pin_driven(scl, Drive::Released(crate::wire::Pull::None), k * 10 + 5);
        }
        assert_eq!(b.pin_level(sda, 100), Some(true));
        b.pin_driven(sda, Drive::Low, 200);
        b.pin_driven(sda, Drive::Released(crate::wire::Pull::None), 210);
        assert_eq!(b.i2c_step(1, I2cStep::Start, 300), I2cReply::Ack);
        assert_eq!(
            b.i2c_step(
                1,
                I2cStep::Address {
                    addr: 0x77,
                    read: false
                },
                300
            ),
            I2cReply::Ack
        );
    }

    #[test]
    fn motors_and_the_battery_divider() {
        let mut b = board(FlightBoardKind::BrushedSparky);
        let m1 = b.pins.motors[0];
        for k in 0..10u64 {
            b.pin_driven(m1, Drive::High, k * 31_250);
            b.pin_driven(m1, Drive::Low, k * 31_250 + 15_625);
        }
        match b.motor_commands(320_000)[0] {
            Command::Throttle(x) => assert!((x - 0.5).abs() < 1e-3),
            c => panic!("{c:?}"),
        }
        assert_eq!(b.motor_commands(320_000)[1], Command::Stopped);
        b.environment(0, 101_325.0, 25.0, 4.15, 0.0);
        assert!((b.analog_volts(b.pins.battery, 0) - 2.075).abs() < 1e-6);
    }
}
