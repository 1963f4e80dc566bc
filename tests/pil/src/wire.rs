//! The boundary between a microcontroller model and its board.
//!
//! A SoC model (STM32F405, nRF52840) calls [`Outside`] as the firmware drives its pins and
//! peripherals; the board (which chip is on which pin) implements it and routes each call to
//! the chip models. Inputs travel the other way as timestamped events the board queues on
//! the SoC model before it runs past them (`drive_input`, `uart_receive` on each model), so
//! an edge keeps its exact time whatever the co-simulation step.

/// A GPIO pin: port (0 = GPIOA / P0, 1 = GPIOB / P1, …) and its number in the port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Pin {
    /// Port index: 0 = A (STM32) or P0 (nRF), 1 = B or P1, …
    pub port: u8,
    /// Pin number within the port.
    pub pin: u8,
}

impl Pin {
    /// Port `port`, pin `pin`.
    pub const fn new(port: u8, pin: u8) -> Self {
        Self { port, pin }
    }
}

/// How the microcontroller holds a pin, as the board sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drive {
    /// Driven low (push-pull or open-drain).
    Low,
    /// Driven high (push-pull).
    High,
    /// Not driven by the chip: input, analog, open-drain released, or a peripheral's input;
    /// with the chip's internal pull, if any.
    Released(Pull),
}

/// An internal pull resistor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pull {
    /// None.
    None,
    /// To the supply.
    Up,
    /// To ground.
    Down,
}

/// One step of an I²C transaction, as the controller puts it on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum I2cStep {
    /// START or repeated START.
    Start,
    /// The address byte: 7-bit address and the read bit. The board answers whether a
    /// target acknowledged.
    Address {
        /// 7-bit address.
        addr: u8,
        /// Read (true) or write.
        read: bool,
    },
    /// A data byte written; the board answers whether the target acknowledged.
    Write(u8),
    /// A data byte read; `ack` is what the controller answers after it (false before a STOP).
    Read {
        /// The controller's acknowledge of this byte.
        ack: bool,
    },
    /// STOP.
    Stop,
}

/// What the board answers to an [`I2cStep`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum I2cReply {
    /// Acknowledged (address or written byte), or the step needs no answer.
    Ack,
    /// Not acknowledged.
    Nack,
    /// The byte a target sent.
    Data(u8),
    /// The bus is held: SDA or SCL low by a target (a stuck bus). The controller sees
    /// the bus busy or loses arbitration, as its model decides.
    Stuck,
}

/// The board around one microcontroller: what its pins and peripherals reach.
pub trait Outside {
    /// A pin's drive changed at `now_ns` (GPIO output, a peripheral taking or leaving the
    /// pin, an open-drain release).
    fn pin_driven(&mut self, pin: Pin, drive: Drive, now_ns: u64);

    /// The level the board puts on an input `pin` now (chips' outputs, pull-ups on the
    /// board); `None` when nothing drives it (the chip's own pull then decides).
    fn pin_level(&mut self, pin: Pin, now_ns: u64) -> Option<bool>;

    /// One full-duplex byte on SPI controller `bus` (1 = SPI1 / SPIM0, …; the SoC model's
    /// numbering), clocked at `now_ns`: the byte MISO carried back.
    fn spi_byte(&mut self, bus: u8, mosi: u8, now_ns: u64) -> u8;

    /// One step of an I²C transaction on controller `bus`.
    fn i2c_step(&mut self, bus: u8, step: I2cStep, now_ns: u64) -> I2cReply;

    /// A byte the UART `uart` finished sending at `now_ns`.
    fn uart_sent(&mut self, uart: u8, byte: u8, now_ns: u64);

    /// The voltage on an analog input `pin`, volts.
    fn analog_volts(&mut self, pin: Pin, now_ns: u64) -> f32;
}
