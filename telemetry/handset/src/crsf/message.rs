//! Typed view of a frame: [`Message`] decodes every frame type this module knows and builds
//! the frame back.

use heapless::Vec;

use super::channels::RcChannels;
use super::device::{
    BindCommand, COMMAND_BIND, COMMAND_CRSF, DeviceInfo, DevicePing, ModelSelect, TimingCorrection,
};
use super::frame::{Error, Frame, frame_type};
use super::params::{ParameterChunk, ParameterRead, ParameterWrite};
use super::sensors::{
    Attitude, BaroAltitude, Battery, FlightModeFrame, Gps, LinkStatistics, Vario,
};

/// A frame of a known type, decoded.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message {
    /// 0x16, radio → module.
    RcChannels(RcChannels),
    /// 0x14, module → radio.
    LinkStatistics(LinkStatistics),
    /// 0x08, module → radio.
    Battery(Battery),
    /// 0x1E, module → radio.
    Attitude(Attitude),
    /// 0x21, module → radio.
    FlightMode(FlightModeFrame),
    /// 0x02, module → radio.
    Gps(Gps),
    /// 0x07, module → radio.
    Vario(Vario),
    /// 0x09, module → radio.
    BaroAltitude(BaroAltitude),
    /// 0x28, either way.
    DevicePing(DevicePing),
    /// 0x29, either way.
    DeviceInfo(DeviceInfo),
    /// 0x3A / 0x10, module → radio.
    TimingCorrection(TimingCorrection),
    /// 0x32 / 0x10 / 0x05, radio → module.
    ModelSelect(ModelSelect),
    /// 0x32 / 0x10 / 0x01, radio → module.
    Bind(BindCommand),
    /// 0x2C, radio → module.
    ParameterRead(ParameterRead),
    /// 0x2D, radio → module.
    ParameterWrite(ParameterWrite),
    /// 0x2B, module → radio.
    ParameterChunk(ParameterChunk),
}

impl Message {
    /// Decodes a checked frame. Unknown types give `Error::WrongType`; known types with a
    /// malformed payload give the payload's error.
    pub fn from_frame(frame: &Frame) -> Result<Self, Error> {
        let payload = frame.payload.as_slice();
        Ok(match frame.frame_type {
            frame_type::RC_CHANNELS_PACKED => Self::RcChannels(RcChannels::from_frame(frame)?),
            frame_type::LINK_STATISTICS => {
                Self::LinkStatistics(LinkStatistics::from_payload(payload)?)
            }
            frame_type::BATTERY_SENSOR => Self::Battery(Battery::from_payload(payload)?),
            frame_type::ATTITUDE => Self::Attitude(Attitude::from_payload(payload)?),
            frame_type::FLIGHT_MODE => Self::FlightMode(FlightModeFrame::from_payload(payload)?),
            frame_type::GPS => Self::Gps(Gps::from_payload(payload)?),
            frame_type::VARIO => Self::Vario(Vario::from_payload(payload)?),
            frame_type::BARO_ALTITUDE => Self::BaroAltitude(BaroAltitude::from_payload(payload)?),
            frame_type::DEVICE_PING => Self::DevicePing(DevicePing::from_payload(payload)?),
            frame_type::DEVICE_INFO => Self::DeviceInfo(DeviceInfo::from_payload(payload)?),
            frame_type::RADIO_ID => {
                Self::TimingCorrection(TimingCorrection::from_payload(payload)?)
            }
            frame_type::COMMAND => match payload.get(2..4) {
                Some([COMMAND_CRSF, COMMAND_BIND]) => {
                    Self::Bind(BindCommand::from_payload(payload)?)
                }
                _ => Self::ModelSelect(ModelSelect::from_payload(payload)?),
            },
            frame_type::PARAMETER_READ => {
                Self::ParameterRead(ParameterRead::from_payload(payload)?)
            }
            frame_type::PARAMETER_WRITE => {
                Self::ParameterWrite(ParameterWrite::from_payload(payload)?)
            }
            frame_type::PARAMETER_SETTINGS_ENTRY => {
                Self::ParameterChunk(ParameterChunk::from_payload(payload)?)
            }
            found => return Err(Error::WrongType { found }),
        })
    }

    /// Frame type byte of this message.
    pub fn frame_type(&self) -> u8 {
        match self {
            Self::RcChannels(_) => frame_type::RC_CHANNELS_PACKED,
            Self::LinkStatistics(_) => frame_type::LINK_STATISTICS,
            Self::Battery(_) => frame_type::BATTERY_SENSOR,
            Self::Attitude(_) => frame_type::ATTITUDE,
            Self::FlightMode(_) => frame_type::FLIGHT_MODE,
            Self::Gps(_) => frame_type::GPS,
            Self::Vario(_) => frame_type::VARIO,
            Self::BaroAltitude(_) => frame_type::BARO_ALTITUDE,
            Self::DevicePing(_) => frame_type::DEVICE_PING,
            Self::DeviceInfo(_) => frame_type::DEVICE_INFO,
            Self::TimingCorrection(_) => frame_type::RADIO_ID,
            Self::ModelSelect(_) | Self::Bind(_) => frame_type::COMMAND,
            Self::ParameterRead(_) => frame_type::PARAMETER_READ,
            Self::ParameterWrite(_) => frame_type::PARAMETER_WRITE,
            Self::ParameterChunk(_) => frame_type::PARAMETER_SETTINGS_ENTRY,
        }
    }

    /// The frame, with `address` as byte 0 (0xC8 for everything a module sends the radio).
    pub fn to_frame(&self, address: u8) -> Result<Frame, Error> {
        let payload: Vec<u8, { super::frame::MAX_PAYLOAD_LEN }> = match self {
            Self::RcChannels(channels) => Vec::from_iter(channels.pack()),
            Self::LinkStatistics(stats) => Vec::from_iter(stats.to_payload()),
            Self::Battery(battery) => Vec::from_iter(battery.to_payload()),
            Self::Attitude(attitude) => Vec::from_iter(attitude.to_payload()),
            Self::FlightMode(mode) => mode.to_payload(),
            Self::Gps(gps) => Vec::from_iter(gps.to_payload()),
            Self::Vario(vario) => Vec::from_iter(vario.to_payload()),
            Self::BaroAltitude(altitude) => Vec::from_iter(altitude.to_payload()),
            Self::DevicePing(ping) => Vec::from_iter(ping.to_payload()),
            Self::DeviceInfo(info) => info.to_payload()?,
            Self::TimingCorrection(timing) => Vec::from_iter(timing.to_payload()),
            Self::ModelSelect(command) => Vec::from_iter(command.to_payload()),
            Self::Bind(command) => Vec::from_iter(command.to_payload()),
            Self::ParameterRead(read) => Vec::from_iter(read.to_payload()),
            Self::ParameterWrite(write) => write.to_payload(),
            Self::ParameterChunk(chunk) => chunk.to_payload(),
        };
        Ok(Frame {
            address,
            frame_type: self.frame_type(),
            payload,
        })
    }

    /// Encodes the whole frame into `out`; returns the bytes written.
    pub fn encode<'o>(&self, address: u8, out: &'o mut [u8]) -> Result<&'o [u8], Error> {
        self.to_frame(address)?.encode(out)
    }
}
