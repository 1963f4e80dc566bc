//! The USB host on the OTG FS port (placeholder while the model is written).

/// The host.
#[derive(Default)]
pub struct UsbHost {}
