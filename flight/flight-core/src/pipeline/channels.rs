//! Link channels to the loop's input. The link delivers 11-bit CRSF-scaled values
//! (172 = −100 %, 992 = centre, 1811 = +100 %; telemetry `channels`), AETR order by default.
//! Kept here, not in the link, because which channel is which is a flight setting.

use super::flight_loop::LinkInput;
use super::setup::SetupError;
use crate::settings::{Settings, handles};
use crate::supervisor::Sticks;

/// Channel value at −100 % (CRSF).
pub const CHANNEL_LOW: u16 = 172;
/// Channel value at centre.
pub const CHANNEL_MID: u16 = 992;
/// Channel value at +100 %.
pub const CHANNEL_HIGH: u16 = 1811;

/// The arm switch: a channel and the pulse-width window in which it reads "armed".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArmChannel {
    /// Channel index (0-based).
    pub index: usize,
    /// Lowest pulse width that reads "on", µs.
    pub min_us: u16,
    /// Highest pulse width that reads "on", µs.
    pub max_us: u16,
}

/// A CRSF channel value as the pulse width it stands for, µs (172 → 988, 992 → 1500,
/// 1811 → 2012: the CRSF convention, 5/8 µs per count).
pub fn channel_us(value: u16) -> f32 {
    1500.0 + (f32::from(value) - f32::from(CHANNEL_MID)) * 0.625
}

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
    pub arm: Option<ArmChannel>,
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
    /// The map the settings ask for: AETR and the mode switch as [`ChannelMap::default`], the
    /// arm switch from `arm.channel` (0 = stick gesture, 1–16 = channel number) with its
    /// window `arm.min_us`…`arm.max_us`. Refuses a window that is empty or an arm channel that
    /// is also a stick or the mode switch.
    pub fn from_settings(s: &Settings) -> Result<Self, SetupError> {
        let map = Self::default();
        let channel = s.get(handles::ARM_CHANNEL);
        if channel == 0 {
            return Ok(map);
        }
        let index = (channel - 1) as usize;
        if [map.roll, map.pitch, map.throttle, map.yaw, map.mode].contains(&index) {
            return Err(SetupError::ArmChannelInUse);
        }
        let min_us =
            u16::try_from(s.get(handles::ARM_MIN_US)).map_err(|_| SetupError::ArmWindow)?;
        let max_us =
            u16::try_from(s.get(handles::ARM_MAX_US)).map_err(|_| SetupError::ArmWindow)?;
        if min_us >= max_us {
            return Err(SetupError::ArmWindow);
        }
        Ok(Self {
            arm: Some(ArmChannel {
                index,
                min_us,
                max_us,
            }),
            ..map
        })
    }

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
            // A missing channel reads "off": it can never arm.
            arm_switch: self.arm.map(|a| {
                channels.get(a.index).is_some_and(|&v| {
                    (f32::from(a.min_us)..=f32::from(a.max_us)).contains(&channel_us(v))
                })
            }),
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
            arm: Some(ArmChannel {
                index: 4,
                min_us: 1_750,
                max_us: 2_100,
            }),
            ..map
        };
        ch[4] = CHANNEL_HIGH;
        assert_eq!(with_switch.link_input(&ch, true).arm_switch, Some(true));
        ch[4] = CHANNEL_MID;
        assert_eq!(with_switch.link_input(&ch, true).arm_switch, Some(false));
        assert_eq!(with_switch.link_input(&[], true).arm_switch, Some(false));
    }

    #[test]
    fn the_arm_switch_comes_from_the_settings() {
        use crate::settings::Value;
        let mut s = Settings::default();
        assert_eq!(ChannelMap::from_settings(&s), Ok(ChannelMap::default()));
        s.set("arm.channel", Value::U32(5)).unwrap();
        let map = ChannelMap::from_settings(&s).unwrap();
        assert_eq!(
            map.arm,
            Some(ArmChannel {
                index: 4,
                min_us: 1_750,
                max_us: 2_100
            })
        );
        let mut ch = [CHANNEL_MID; 16];
        // 1811 = 2012 µs: on; 1700 µs (1312): off.
        ch[4] = CHANNEL_HIGH;
        assert_eq!(map.link_input(&ch, true).arm_switch, Some(true));
        ch[4] = 1312;
        assert_eq!(map.link_input(&ch, true).arm_switch, Some(false));
        // A low window (switch down = armed) works too.
        s.set("arm.min_us", Value::U32(900)).unwrap();
        s.set("arm.max_us", Value::U32(1_250)).unwrap();
        let low = ChannelMap::from_settings(&s).unwrap();
        ch[4] = CHANNEL_LOW;
        assert_eq!(low.link_input(&ch, true).arm_switch, Some(true));
        // The throttle channel cannot be the arm switch.
        let mut t = Settings::default();
        assert_eq!(
            t.set("arm.channel", Value::U32(3)),
            Err(crate::settings::ParamError::Invalid(
                crate::pipeline::InvalidSettings::Setup(SetupError::ArmChannelInUse)
            ))
        );
        assert_eq!(ChannelMap::from_settings(&t), Ok(ChannelMap::default()));
        t.set_by_key(607, 3).unwrap();
        assert_eq!(
            ChannelMap::from_settings(&t),
            Err(SetupError::ArmChannelInUse)
        );
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
