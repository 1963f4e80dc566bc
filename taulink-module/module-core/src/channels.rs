//! Link channels: up to 16 stick/switch values at CRSF resolution (11 bit), and the mapping
//! between pulse widths in µs and those values.
//!
//! The mapping is the one CRSF transmitters use (ExpressLRS `fmap(us, 988, 2012, 172, 1811)`,
//! protocols.md §2.2): 988 µs ↔ 172 (−100 %), 1500 µs ↔ 992 (centre), 2012 µs ↔ 1811 (+100 %).
//! Beyond ±100 % it extrapolates linearly and clips to the 11-bit range 0…2047
//! (≈ 881…2159 µs), so EdgeTX's extended limits (732…2268 µs) saturate instead of wrapping.

/// Most channels a frame carries (PPM's 16-channel maximum, CRSF's 16 channels).
pub const MAX_CHANNELS: usize = 16;
/// Value of 988 µs (−100 %).
pub const VALUE_MIN_NOMINAL: u16 = 172;
/// Value of 1500 µs (centre).
pub const VALUE_CENTER: u16 = 992;
/// Value of 2012 µs (+100 %).
pub const VALUE_MAX_NOMINAL: u16 = 1811;
/// Largest value 11 bits hold.
pub const VALUE_MAX: u16 = 2047;

/// Pulse width of −100 % in µs.
const US_MIN_NOMINAL: i32 = 988;
/// Span of ±100 % in µs (2012 − 988).
const US_SPAN: i32 = 1024;
/// Span of ±100 % in value steps (1811 − 172).
const VALUE_SPAN: i32 = 1639;

/// Converts a channel pulse width in µs to an 11-bit link value, rounding to nearest and
/// clipping to 0…2047.
pub fn us_to_value(width_us: u16) -> u16 {
    let offset = (i32::from(width_us) - US_MIN_NOMINAL) * VALUE_SPAN;
    // Round half away from zero on the signed offset so the map is symmetric about 1500 µs.
    let steps = if offset >= 0 {
        (offset + US_SPAN / 2) / US_SPAN
    } else {
        (offset - US_SPAN / 2) / US_SPAN
    };
    let value = (i32::from(VALUE_MIN_NOMINAL) + steps).clamp(0, i32::from(VALUE_MAX));
    u16::try_from(value).unwrap_or(VALUE_CENTER)
}

/// Converts an 11-bit link value back to a pulse width in µs (rounded); values above 2047
/// are clipped first.
pub fn value_to_us(value: u16) -> u16 {
    let offset = (i32::from(value.min(VALUE_MAX)) - i32::from(VALUE_MIN_NOMINAL)) * US_SPAN;
    let steps = if offset >= 0 {
        (offset + VALUE_SPAN / 2) / VALUE_SPAN
    } else {
        (offset - VALUE_SPAN / 2) / VALUE_SPAN
    };
    u16::try_from(US_MIN_NOMINAL + steps).unwrap_or(1500)
}

/// One frame of channel values, 1…16 of them, each 0…2047.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Channels {
    values: [u16; MAX_CHANNELS],
    count: u8,
}

impl Channels {
    /// `count` channels (clipped to 16), all centred.
    pub fn centered(count: usize) -> Self {
        Self {
            values: [VALUE_CENTER; MAX_CHANNELS],
            count: u8::try_from(count.min(MAX_CHANNELS)).unwrap_or(0),
        }
    }

    /// Channels from values; values past the 16th are ignored, each value is clipped to 2047.
    pub fn from_values(values: &[u16]) -> Self {
        let mut channels = Self::centered(values.len());
        for (slot, value) in channels.values.iter_mut().zip(values) {
            *slot = (*value).min(VALUE_MAX);
        }
        channels
    }

    /// How many channels the frame carries.
    pub fn count(&self) -> usize {
        usize::from(self.count)
    }

    /// The values, one per channel.
    pub fn as_slice(&self) -> &[u16] {
        self.values.get(..self.count()).unwrap_or(&[])
    }

    /// Value of channel `index` (0-based), `None` past the count.
    pub fn get(&self, index: usize) -> Option<u16> {
        self.as_slice().get(index).copied()
    }

    /// Sets channel `index` (clipped to 2047); returns `false` past the count.
    pub fn set(&mut self, index: usize, value: u16) -> bool {
        let count = self.count();
        match self.values.get_mut(..count).and_then(|v| v.get_mut(index)) {
            Some(slot) => {
                *slot = value.min(VALUE_MAX);
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_points_map_exactly() {
        assert_eq!(us_to_value(988), 172);
        assert_eq!(us_to_value(1500), 992);
        assert_eq!(us_to_value(2012), 1811);
        assert_eq!(value_to_us(172), 988);
        assert_eq!(value_to_us(992), 1500);
        assert_eq!(value_to_us(1811), 2012);
    }

    #[test]
    fn extended_limits_saturate_at_eleven_bits() {
        assert_eq!(us_to_value(750), 0);
        assert_eq!(us_to_value(732), 0);
        assert_eq!(us_to_value(2250), 2047);
        // 881 µs is the last width above zero: 172 + (881 − 988)·1639/1024 = 0.7 → 1.
        assert_eq!(us_to_value(881), 1);
        assert_eq!(value_to_us(0), 881);
        assert_eq!(value_to_us(2047), 2159);
    }

    #[test]
    fn round_trip_within_one_microsecond() {
        for us in 881..=2159u16 {
            let back = value_to_us(us_to_value(us));
            assert!(back.abs_diff(us) <= 1, "{us} µs came back as {back}");
        }
    }

    #[test]
    fn channels_clip_and_bound() {
        let mut ch = Channels::from_values(&[0, 3000, 992]);
        assert_eq!(ch.as_slice(), &[0, 2047, 992]);
        assert!(ch.set(1, 1000));
        assert!(!ch.set(3, 1000));
        assert_eq!(ch.get(1), Some(1000));
        assert_eq!(ch.get(3), None);
        assert_eq!(Channels::centered(20).count(), 16);
    }
}
