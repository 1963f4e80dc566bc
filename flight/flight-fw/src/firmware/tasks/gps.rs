//! The u-blox receiver on the Sparky2's Main port (USART1, `board::Gps`: received into a DMA
//! ring): bytes in go to `FlightApp::on_gps_bytes` (UBX parser; the fixes to the flight
//! loop's INS, telemetry), the app's configuration
//! frames (`FlightApp::gps_to_send`) go out. At boot, the baud-rate messages of both
//! receiver generations at each baud a receiver may power up at, then 115200 Bd for good.
//! No watchdog check-in: a missing or dead receiver must not reset a flying frame; it shows
//! as a lost fix.

use defmt::{info, warn};
use embassy_stm32::mode::Async;
use embassy_stm32::usart::UartTx;
use embassy_time::{Duration, Timer, with_timeout};
use flight_app::app::{GPS_BAUD, GPS_BOOT_BAUDS, gps_baud_messages};
use flight_app::sensors::ubx::frame::MAX_FRAME;
use heapless::Vec;

use crate::firmware::board::Gps;
use crate::firmware::shared::{now_ms, with_app};

/// How long a read waits before the configuration is polled again (its retry period is
/// 250 ms).
const READ_TIMEOUT: Duration = Duration::from_millis(50);

#[embassy_executor::task]
pub async fn gps_task(gps: Gps) {
    let Gps { mut tx, mut rx } = gps;
    announce_baud(&mut tx).await;
    if tx.set_baudrate(GPS_BAUD).is_err() {
        warn!("GPS: USART1 refused {} Bd", GPS_BAUD);
    }
    info!("GPS port at {} Bd", GPS_BAUD);
    rx.start_uart();
    let mut buf = [0u8; 64];
    loop {
        let frame: Option<Vec<u8, MAX_FRAME>> = with_app(|a| {
            a.gps_to_send(now_ms())
                .and_then(|f| Vec::from_slice(f).ok())
        })
        .flatten();
        if let Some(f) = frame
            && tx.write(&f).await.is_err()
        {
            warn!("GPS: write failed");
        }
        match with_timeout(READ_TIMEOUT, rx.read(&mut buf)).await {
            Ok(Ok(n)) => {
                let bytes = buf.get(..n).unwrap_or_default();
                with_app(|a| a.on_gps_bytes(now_ms(), bytes));
            }
            // Overrun (the ring lapped: the task was held longer than it lasts) or framing
            // error: bytes were lost, the parser resynchronises.
            Ok(Err(_)) => warn!("GPS: receive error"),
            Err(_) => {}
        }
    }
}

/// Writes both generations' baud-rate messages at each power-up baud.
async fn announce_baud(tx: &mut UartTx<'static, Async>) {
    for baud in GPS_BOOT_BAUDS {
        if tx.set_baudrate(baud).is_err() {
            continue;
        }
        for m in gps_baud_messages() {
            if tx.write(&m).await.is_err() {
                warn!("GPS: write failed at {} Bd", baud);
            }
        }
        let _ = tx.flush().await;
        // The receiver changes baud after sending its answer; give it a moment.
        Timer::after(Duration::from_millis(20)).await;
    }
}
