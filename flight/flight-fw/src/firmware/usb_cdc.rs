//! A whole answer for the USB CDC class: its text ([`Reply`]), and its sending — 64-byte
//! packets, and the zero-length packet that ends a transfer whose last packet is full.

use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usb::Driver;
use embassy_usb::class::cdc_acm::CdcAcmClass;
use embassy_usb::driver::EndpointError;
use heapless::String;

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

/// One answer's text. Its one `write_str`, never inlined: the answer is written in a few
/// dozen pieces, and the buffer's append inlined at each of them cost 592 B of flash
/// (Sparky2, measured).
pub struct Reply(pub String<2048>);

impl core::fmt::Write for Reply {
    #[inline(never)]
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write_str(s)
    }
}
