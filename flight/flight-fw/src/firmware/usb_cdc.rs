//! Writing a whole answer to the USB CDC class: 64-byte packets, and the zero-length packet
//! that ends a transfer whose last packet is full.

use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usb::Driver;
use embassy_usb::class::cdc_acm::CdcAcmClass;
use embassy_usb::driver::EndpointError;

/// Sends `bytes` as one transfer.
pub async fn send(
    class: &mut CdcAcmClass<'static, Driver<'static, USB_OTG_FS>>,
    bytes: &[u8],
) -> Result<(), EndpointError> {
    for chunk in bytes.chunks(64) {
        class.write_packet(chunk).await?;
    }
    if bytes.len().is_multiple_of(64) && !bytes.is_empty() {
        // A full last packet needs a zero-length one to end the transfer.
        class.write_packet(&[]).await?;
    }
    Ok(())
}
