//! Status LED patterns: what the single LED says about the link.

/// What the module is doing, as far as the pilot needs to know.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkState {
    /// Starting up or the radio is missing.
    NoRadio,
    /// Bind in progress.
    Binding,
    /// Bound, no answer from the other end.
    Searching,
    /// Link up.
    Connected,
}

impl LinkState {
    /// The LED pattern as (on ms, off ms): slow blink searching, fast blink binding, solid
    /// when connected, a short flash every 2 s with no radio.
    pub const fn blink(self) -> (u32, u32) {
        match self {
            LinkState::NoRadio => (50, 1950),
            LinkState::Binding => (100, 100),
            LinkState::Searching => (500, 500),
            LinkState::Connected => (1000, 0),
        }
    }
}
