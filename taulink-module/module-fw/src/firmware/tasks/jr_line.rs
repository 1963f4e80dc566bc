//! The JR pin 5 line (UARTE0 behind the XOR and the tri-state buffer, hardware README),
//! driven as the module core's handset codec asks (`module_core::handset::LineMode`):
//!
//! * CRSF (EdgeTX): 400 kBd, not inverted, half duplex. The UARTE cannot share one wire, so
//!   the driver is re-created per direction (toolchain.md §2): `UarteRx` with idle-line
//!   detection receives the radio's frame, which goes to the CRSF decoder stamped with the
//!   idle time; it is dropped (which disables the UARTE and frees its pins), then the buffer
//!   is enabled and a `UarteTx` sends the responder's reply in the slot after the radio's
//!   frame (DEVICE_INFO, timing, LINK_STATISTICS, sensors).
//! * S.Port (57 600 Bd) / FrSky D (9600 Bd): inverted through the polarity pin, transmit
//!   only, frames pushed unpolled (protocols.md §1.3); the scheduler in the core paces them
//!   (12 ms / 30 ms slots), this task asks every 2 ms.

use embassy_nrf::uarte::{self, Baudrate, UarteRx, UarteTx};
use embassy_time::{Duration, Timer, with_timeout};
use module_core::handset::{LineMode, MAX_LINE_BURST};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{Irqs, JrLine};
use crate::firmware::shared::{now_us, with_app};

/// How often the push modes ask the scheduler (well under its 12 ms S.Port slot).
const PUSH_POLL: Duration = Duration::from_millis(2);

/// UARTE BAUDRATE register for `baud`: baud · 2³² / 16 MHz, low 12 bits cleared as the
/// named presets do (0x0666_6000 ≈ 399 994 Bd for CRSF).
const fn baud_register(baud: u32) -> Baudrate {
    let bits = ((baud as u64) << 32) / 16_000_000;
    Baudrate::from_bits((bits as u32) & 0xFFFF_F000)
}

fn config(baud: u32) -> uarte::Config {
    let mut config = uarte::Config::default();
    config.baudrate = baud_register(baud);
    config
}

#[embassy_executor::task]
pub async fn jr_line_task(mut line: JrLine) {
    let mode = with_app(|app| app.handset().line_mode()).unwrap_or(LineMode::Off);
    defmt::info!("JR line: {}", mode);
    let mut frame = [0u8; 64];
    let mut reply = [0u8; MAX_LINE_BURST];
    loop {
        check_in(Watched::JrLine);
        match mode {
            LineMode::Crsf { baud } => {
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
                let Ok(Ok(count)) = received else {
                    continue;
                };
                let idle_us = now_us();
                let bytes = frame.get(..count).unwrap_or(&[]);
                let length = with_app(|app| {
                    app.on_handset_bytes(idle_us, bytes);
                    app.on_handset_idle(idle_us);
                    app.next_handset_bytes(now_us(), &mut reply)
                })
                .unwrap_or(0);
                send(&mut line, baud, reply.get(..length).unwrap_or(&[])).await;
            }
            LineMode::Push { baud } => {
                line.invert.set_high();
                let length =
                    with_app(|app| app.next_handset_bytes(now_us(), &mut reply)).unwrap_or(0);
                send(&mut line, baud, reply.get(..length).unwrap_or(&[])).await;
                Timer::after(PUSH_POLL).await;
            }
            LineMode::Off => Timer::after(Duration::from_millis(50)).await,
        }
    }
}

/// Sends `bytes` (if any) with the buffer enabled only for them.
async fn send(line: &mut JrLine, baud: u32, bytes: &[u8]) {
    if bytes.is_empty() {
        return;
    }
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
