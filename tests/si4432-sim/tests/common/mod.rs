//! Raw register access for the integration tests, written from the datasheet (SPI: first
//! byte = address | 0x80 for a write; bursts auto-increment except at 0x7F). Deliberately no
//! driver: these tests pin the chip model, not a driver.
#![allow(dead_code)]

use embedded_hal::spi::{Operation, SpiDevice};

/// Burst write starting at `address`.
pub fn write(spi: &mut impl SpiDevice, address: u8, data: &[u8]) {
    spi.transaction(&mut [Operation::Write(&[address | 0x80]), Operation::Write(data)])
        .unwrap();
}

/// Single register read.
pub fn read(spi: &mut impl SpiDevice, address: u8) -> u8 {
    let mut buf = [0u8];
    spi.transaction(&mut [
        Operation::Write(&[address & 0x7F]),
        Operation::Read(&mut buf),
    ])
    .unwrap();
    buf[0]
}

/// Burst read of `n` bytes starting at `address`.
pub fn read_n(spi: &mut impl SpiDevice, address: u8, n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; n];
    spi.transaction(&mut [
        Operation::Write(&[address & 0x7F]),
        Operation::Read(&mut buf),
    ])
    .unwrap();
    buf
}

/// Burst-read 0x03/0x04 (clears both).
pub fn status(spi: &mut impl SpiDevice) -> (u8, u8) {
    let s = read_n(spi, 0x03, 2);
    (s[0], s[1])
}

/// Tau Labs 57 600 bit/s profile (the data-rate table of `flight/PiOS/Common/pios_rfm22b.c`), 430
/// MHz, GFSK from the FIFO, 6-byte preamble, sync 2D D4 4B 59, 4-byte header, variable length,
/// whitening.
pub fn configure_57600(spi: &mut impl SpiDevice, crc: bool) {
    status(spi);
    write(spi, 0x05, &[0x00, 0x00]);
    let profile: [(u8, u8); 17] = [
        (0x1C, 0x95),
        (0x1D, 0x40),
        (0x1E, 0x0A),
        (0x1F, 0x03),
        (0x20, 0x68),
        (0x21, 0x01),
        (0x22, 0x3A),
        (0x23, 0x93),
        (0x24, 0x03),
        (0x25, 0x29),
        (0x2A, 0x3C),
        (0x58, 0x80),
        (0x69, 0x60),
        (0x6E, 0x0E),
        (0x6F, 0xBF),
        (0x70, 0x0D),
        (0x72, 0x48),
    ];
    for (a, v) in profile {
        write(spi, a, &[v]);
    }
    write(spi, 0x71, &[0x23]);
    write(spi, 0x30, &[if crc { 0x8C } else { 0x88 }]); // CRC-CCITT over header+length+data
    write(spi, 0x32, &[0xFF]);
    write(spi, 0x33, &[0x46]);
    write(spi, 0x34, &[0x0C]);
    write(spi, 0x35, &[0x30]);
    write(spi, 0x36, &[0x2D, 0xD4, 0x4B, 0x59]);
    write(spi, 0x3A, &[0x12, 0x34, 0x56, 0x78]);
    write(spi, 0x3F, &[0x12, 0x34, 0x56, 0x78]);
    write(spi, 0x43, &[0xFF, 0xFF, 0xFF, 0xFF]);
    write(spi, 0x6D, &[0x0F]); // +20 dBm
    write(spi, 0x7C, &[62, 32, 32]); // TX almost full, TX almost empty, RX almost full
    write(spi, 0x75, &[0x53, 0x00, 0x00]); // 430 MHz
    write(spi, 0x79, &[0x00, 0x04]); // hop channel 0, step 40 kHz
}

/// Clear both FIFOs (0x08: ffclrrx | ffclrtx, then 0).
pub fn clear_fifos(spi: &mut impl SpiDevice) {
    write(spi, 0x08, &[0x03]);
    write(spi, 0x08, &[0x00]);
}

/// Tau Labs "enter RX": TUNE, clear FIFOs, enable RX interrupts, RX on.
pub fn start_rx(spi: &mut impl SpiDevice) {
    write(spi, 0x05, &[0x00, 0x00]);
    write(spi, 0x07, &[0x02]);
    clear_fifos(spi);
    status(spi);
    write(spi, 0x05, &[0x93, 0xC0]);
    write(spi, 0x07, &[0x06]);
}

/// Load up to 64 bytes and start TX of a `length`-byte packet (the rest is the caller's job).
pub fn start_tx(spi: &mut impl SpiDevice, length: u8, first: &[u8]) {
    write(spi, 0x05, &[0x00, 0x00]);
    write(spi, 0x07, &[0x02]);
    clear_fifos(spi);
    write(spi, 0x3E, &[length]);
    write(spi, 0x7F, first);
    status(spi);
    write(spi, 0x05, &[0x24, 0x00]); // ipksent | itxffaem
    write(spi, 0x07, &[0x0A]);
}

/// Async burst write (embedded-hal-async `SpiDevice`).
pub async fn awrite(spi: &mut impl embedded_hal_async::spi::SpiDevice, address: u8, data: &[u8]) {
    spi.transaction(&mut [Operation::Write(&[address | 0x80]), Operation::Write(data)])
        .await
        .unwrap();
}

/// Async burst read.
pub async fn aread_n(
    spi: &mut impl embedded_hal_async::spi::SpiDevice,
    address: u8,
    n: usize,
) -> Vec<u8> {
    let mut buf = vec![0u8; n];
    spi.transaction(&mut [
        Operation::Write(&[address & 0x7F]),
        Operation::Read(&mut buf),
    ])
    .await
    .unwrap();
    buf
}

/// Async read of 0x03/0x04 (clears both).
pub async fn astatus(spi: &mut impl embedded_hal_async::spi::SpiDevice) -> (u8, u8) {
    let s = aread_n(spi, 0x03, 2).await;
    (s[0], s[1])
}
