//! Link channels to the loop's input. The link delivers 11-bit CRSF-scaled values
//! (172 = −100 %, 992 = centre, 1811 = +100 %; telemetry `channels`), AETR order by default.
//! Kept here, not in the link, because which channel is which is a flight setting.

use super::flight_loop::LinkInput;
use crate::supervisor::Sticks;

/// Channel value at −100 % (CRSF).
pub const CHANNEL_LOW: u16 = 172;
/// Channel value at centre.
pub const CHANNEL_MID: u16 = 992;
/// Channel value at +100 %.
pub const CHANNEL_HIGH: u16 = 1811;

/// Which channel (0-based) carries what.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelMap {
    /// Roll (aileron).
    pub roll: usize,
    /// Pitch (elevator).
    pub pitch: usize,
    /// Throttle.
    pub throttle: usize,
    /// Yaw (rudder).
    pub yaw: usize,
    /// The arm switch, or `None` for the stick gesture.
    pub arm: Option<usize>,
    /// The flight-mode switch.
    pub mode: usize,
}

impl Default for ChannelMap {
    /// AETR, stick arming, the mode switch on channel 6 (AUX2).
    fn default() -> Self {
        Self {
            roll: 0,
            pitch: 1,
            throttle: 2,
            yaw: 3,
            arm: None,
            mode: 5,
        }
    }
}

/// −1…1 around the centre; a missing channel reads centre.
fn bipolar(channels: &[u16], i: usize) -> f32 {
    let v = channels.get(i).copied().unwrap_or(CHANNEL_MID);
    let half = f32::from(CHANNEL_HIGH - CHANNEL_LOW) / 2.0;
    ((f32::from(v) - f32::from(CHANNEL_MID)) / half).clamp(-1.0, 1.0)
}

impl ChannelMap {
    /// The loop input from the link's channels; `up` is false while the link is in
    /// failsafe (the channels then hold the link's failsafe values, which the loop ignores).
    pub fn link_input(&self, channels: &[u16], up: bool) -> LinkInput {
        let throttle_raw = channels.get(self.throttle).copied().unwrap_or(CHANNEL_LOW);
        let throttle = (f32::from(throttle_raw.saturating_sub(CHANNEL_LOW))
            / f32::from(CHANNEL_HIGH - CHANNEL_LOW))
        .clamp(0.0, 1.0);
        LinkInput {
            up,
            sticks: Sticks {
                throttle,
                roll: bipolar(channels, self.roll),
                pitch: bipolar(channels, self.pitch),
                yaw: bipolar(channels, self.yaw),
            },
            arm_switch: self.arm.map(|i| bipolar(channels, i) > 0.5),
            mode_channel: bipolar(channels, self.mode),
        }
    }
}

/// The channel value for a stick position −1…1 (the inverse of the map; for simulated
/// transmitters and tests).
pub fn channel_for(position: f32) -> u16 {
    let half = f32::from(CHANNEL_HIGH - CHANNEL_LOW) / 2.0;
    let v = f32::from(CHANNEL_MID) + position.clamp(-1.0, 1.0) * half;
    (v + 0.5) as u16
}

/// The channel value for a throttle 0…1.
pub fn throttle_channel(throttle: f32) -> u16 {
    let v =
        f32::from(CHANNEL_LOW) + throttle.clamp(0.0, 1.0) * f32::from(CHANNEL_HIGH - CHANNEL_LOW);
    (v + 0.5) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crsf_scale_maps_to_stick_ranges() {
        let mut ch = [CHANNEL_MID; 16];
        ch[0] = CHANNEL_HIGH;
        ch[1] = CHANNEL_LOW;
        ch[2] = CHANNEL_LOW;
        ch[3] = 1401; // +50 %
        ch[5] = CHANNEL_HIGH;
        let map = ChannelMap::default();
        let input = map.link_input(&ch, true);
        assert!(input.up);
        // 992 sits half a count above the range's middle: ±100 % read 0.9994 and −1.
        assert!(
            (input.sticks.roll - 1.0).abs() < 1e-3,
            "{}",
            input.sticks.roll
        );
        assert_eq!(input.sticks.pitch, -1.0);
        assert_eq!(input.sticks.throttle, 0.0);
        assert!(
            (input.sticks.yaw - 0.4994).abs() < 1e-3,
            "{}",
            input.sticks.yaw
        );
        assert!(input.mode_channel > 0.99);
        assert_eq!(input.arm_switch, None);
        ch[2] = 992;
        let input = map.link_input(&ch, false);
        assert!(!input.up);
        assert!((input.sticks.throttle - 0.5003).abs() < 1e-3);
        // A short channel list reads centred sticks and low throttle.
        let input = map.link_input(&[], true);
        assert_eq!(input.sticks, Sticks::default());
        let with_switch = ChannelMap {
            arm: Some(4),
            ..map
        };
        ch[4] = CHANNEL_HIGH;
        assert_eq!(with_switch.link_input(&ch, true).arm_switch, Some(true));
    }

    #[test]
    fn inverse_round_trips() {
        for p in [-1.0f32, -0.3, 0.0, 0.25, 1.0] {
            let back = bipolar(&[channel_for(p)], 0);
            assert!((back - p).abs() < 2e-3, "{p} {back}");
        }
        let map = ChannelMap::default();
        let mut ch = [CHANNEL_MID; 16];
        ch[2] = throttle_channel(0.42);
        assert!((map.link_input(&ch, true).sticks.throttle - 0.42).abs() < 1e-3);
    }
}
