//! USB OTG FS device core (placeholder while the model is written).

use super::usb_host::UsbHost;

/// The OTG FS core.
#[derive(Default)]
pub struct Otg {
    host: UsbHost,
    /// Settings written that the model ignores.
    pub unmodelled: Vec<&'static str>,
}

impl Otg {
    /// Reset state.
    pub fn new() -> Self {
        Self::default()
    }
    /// Back to reset.
    pub fn reset(&mut self) {}
    /// PLL48 running at 48 MHz.
    pub fn set_clock_ok(&mut self, _ok: bool) {}
    /// Next event.
    pub fn next_event(&self) -> u64 {
        u64::MAX
    }
    /// Process.
    pub fn process(&mut self, _now: u64) {}
    /// IRQ.
    pub fn irq(&self) -> bool {
        false
    }
    /// Read.
    pub fn read(&mut self, _offset: u32, _now: u64) -> Option<u32> {
        None
    }
    /// Write.
    pub fn write(&mut self, _offset: u32, _value: u32, _now: u64) -> Option<()> {
        None
    }
    /// Host.
    pub fn host_mut(&mut self) -> &mut UsbHost {
        &mut self.host
    }
}
