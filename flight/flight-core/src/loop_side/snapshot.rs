//! The step's share of the flight log, taken on the loop's side (the log's ring and its
//! encoding are the application's, `flight_app::logging`).

use crate::estimation::ins::State as InsState;
use crate::estimation::quaternion::Quaternion;
use crate::pipeline::{FlightLoop, ImuSample, LinkInput};
use crate::sysid::ekf;

/// What the flight loop's step contributes to the log: taken on the loop's side after a
/// step while a profile records ([`LoopSnapshot::of`]), carried to the app by the loop's
/// report ([`super::LoopReport`]), recorded in the app's flight log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopSnapshot {
    /// The sample the estimator took (the magnetometer calibrated).
    pub sample: ImuSample,
    /// What the link delivered to the step.
    pub link: LinkInput,
    /// The motors were enabled when the sample was estimated.
    pub armed_before: bool,
    /// The accelerometer corrected the complementary filter on this sample.
    pub accel_corrected: bool,
    /// Body → NED attitude after the step.
    pub attitude: Quaternion,
    /// The INS's state while it flies.
    pub ins: Option<InsState>,
    /// The INS's altitude (m, up) while it flies with a recent baro reading.
    pub ins_altitude_m: Option<f32>,
    /// The loop's climb estimate, m/s up.
    pub climb_mps: Option<f32>,
    /// INS fallbacks so far.
    pub fallbacks: u16,
    /// The identification running, as it stands.
    pub identification: Option<ekf::Identification>,
}

impl LoopSnapshot {
    /// The snapshot of `flight` after it stepped on `sample` with `link`.
    pub fn of(
        flight: &FlightLoop,
        sample: &ImuSample,
        link: &LinkInput,
        armed_before: bool,
    ) -> Self {
        let estimator = flight.estimator();
        Self {
            sample: *sample,
            link: *link,
            armed_before,
            accel_corrected: flight.accel_corrected(),
            attitude: flight.attitude(),
            ins: estimator.ins_state(),
            ins_altitude_m: estimator.vertical().map(|(altitude, _)| altitude),
            climb_mps: flight.climb_estimate(),
            fallbacks: estimator.fallbacks(),
            identification: flight.identification_in_progress(),
        }
    }
}
