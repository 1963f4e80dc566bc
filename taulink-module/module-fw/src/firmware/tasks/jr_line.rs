//! The JR pin 5 line (UARTE0 behind the XOR and the tri-state buffer, hardware README).
//!
//! * CRSF (EdgeTX): 400 kBd, not inverted, half duplex. The UARTE cannot share one wire, so
//!   the driver is re-created per direction (toolchain.md §2): `UarteRx` with idle-line
//!   detection receives the radio's frame, is dropped (which disables the UARTE and frees
//!   its pins), then the buffer is enabled and a `UarteTx` sends our reply in the slot after
//!   the radio's frame.
//! * S.Port (57 600 Bd) / FrSky D (9600 Bd): inverted, transmit only, frames pushed unpolled
//!   (protocols.md §1.3).
//!
//! SEAM: the bytes in both directions belong to telemetry::handset (CRSF decoder and
//! encoders, S.Port and FrSky-D encoders), which the `HandsetSeam` will hand over; until
//! that lands this task receives and counts, and has nothing to send.

use embassy_nrf::uarte::{self, Baudrate, UarteRx, UarteTx};
use embassy_time::{Duration, Timer, with_timeout};
use module_core::settings::{InputProtocol, OutputProtocol, Settings};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{Irqs, JrLine};
use crate::firmware::shared::with_app;

/// UARTE BAUDRATE register for `baud`: baud · 2³² / 16 MHz, low 12 bits cleared as the
/// named presets do (0x0666_6000 ≈ 399 994 Bd for CRSF).
const fn baud_register(baud: u32) -> Baudrate {
    let bits = ((baud as u64) << 32) / 16_000_000;
    Baudrate::from_bits((bits as u32) & 0xFFFF_F000)
}

/// How the line is used.
#[derive(Clone, Copy, defmt::Format)]
enum Mode {
    /// CRSF half duplex at this rate.
    Crsf(u32),
    /// Inverted, transmit-only pushes at this rate every `period_ms`.
    Push { baud: u32, period_ms: u64 },
    /// Nothing on the line.
    Off,
}

fn mode(settings: &Settings) -> Mode {
    match (settings.input, settings.output) {
        (InputProtocol::Crsf, _) => Mode::Crsf(400_000),
        // openLRSng pushes one S.Port frame every 12 ms (protocols.md §1.3).
        (InputProtocol::Ppm, OutputProtocol::SPort) => Mode::Push {
            baud: 57_600,
            period_ms: 12,
        },
        (InputProtocol::Ppm, OutputProtocol::FrskyHub) => Mode::Push {
            baud: 9_600,
            period_ms: 50,
        },
        (InputProtocol::Ppm, OutputProtocol::Off | OutputProtocol::Crsf) => Mode::Off,
    }
}

fn config(baud: u32) -> uarte::Config {
    let mut config = uarte::Config::default();
    config.baudrate = baud_register(baud);
    config
}

#[embassy_executor::task]
pub async fn jr_line_task(mut line: JrLine, settings: Settings) {
    let mode = mode(&settings);
    defmt::info!("JR line: {}", mode);
    let mut frame = [0u8; 64];
    loop {
        check_in(Watched::JrLine);
        match mode {
            Mode::Crsf(baud) => {
                line.invert.set_low();
                line.driver_enable.set_low();
                let received = {
                    let mut rx = UarteRx::new(
                        line.uarte.reborrow(),
                        Irqs,
                        line.rx.reborrow(),
                        config(baud),
                    )
                    .with_idle(
                        line.idle_timer.reborrow(),
                        line.idle_ppi_start.reborrow(),
                        line.idle_ppi_stop.reborrow(),
                    );
                    with_timeout(Duration::from_millis(50), rx.read_until_idle(&mut frame)).await
                };
                if let Ok(Ok(count)) = received {
                    let bytes = frame.get(..count).unwrap_or(&[]);
                    with_app(|app| app.handset_mut().on_jr_bytes(bytes));
                }
                send(&mut line, baud).await;
            }
            Mode::Push { baud, period_ms } => {
                line.invert.set_high();
                send(&mut line, baud).await;
                Timer::after(Duration::from_millis(period_ms)).await;
            }
            Mode::Off => Timer::after(Duration::from_millis(50)).await,
        }
    }
}

/// Sends the frame the handset seam has ready, if any, with the buffer enabled only for it.
async fn send(line: &mut JrLine, baud: u32) {
    let mut frame = [0u8; 64];
    let Some(count) = with_app(|app| app.handset_mut().next_jr_frame(&mut frame)).flatten() else {
        return;
    };
    let bytes = frame.get(..count).unwrap_or(&[]);
    line.driver_enable.set_high();
    {
        let mut tx = UarteTx::new(
            line.uarte.reborrow(),
            Irqs,
            line.tx.reborrow(),
            config(baud),
        );
        if tx.write(bytes).await.is_err() {
            defmt::warn!("JR line write failed");
        }
        // ENDTX comes when the last byte is loaded, not sent: wait two byte times before
        // the drop disables the UARTE and the buffer lets go of the line.
        Timer::after(Duration::from_micros(
            u64::from(2 * 10 * 1_000_000 / baud) + 1,
        ))
        .await;
    }
    line.driver_enable.set_low();
}
