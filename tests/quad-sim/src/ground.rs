//! Ground contact: a quad resting on flat ground (altitude 0, NED z ≥ 0) with less thrust
//! than its weight does not move or rotate, and its accelerometer reads the ground's
//! reaction (−g on z when the motors are stopped). Above the ground, or with thrust to lift
//! off, the free-flight model stands.

use crate::quad::{GRAVITY_MPS2, Quad, Sensors, Truth};

/// Applies ground contact after [`Quad::step`]: returns the truth and sensors to use
/// (unchanged in the air).
pub fn contact(quad: &mut Quad, truth: Truth, sensors: Sensors) -> (Truth, Sensors) {
    let on_ground = truth.state.position_m[2] >= 0.0;
    let thrust_n: f64 = truth
        .state
        .motor
        .iter()
        .map(|m| m * quad.params().max_thrust_n)
        .sum();
    if !on_ground || thrust_n >= quad.params().mass_kg * GRAVITY_MPS2 {
        return (truth, sensors);
    }
    let mut st = truth.state.clone();
    st.rate_rad_s = [0.0; 3];
    st.velocity_mps = [0.0; 3];
    quad.set_state(st);
    let mut sensors = quad.sensors();
    // The model reads −thrust/m (+ noise) on z; the ground adds thrust/m − g.
    let [ax, ay, az] = sensors.accel_mps2;
    let reaction = thrust_n / quad.params().mass_kg - GRAVITY_MPS2;
    #[allow(clippy::cast_possible_truncation)]
    let az = az + reaction as f32;
    sensors.accel_mps2 = [ax, ay, az];
    let truth = Truth {
        rate_dps: [0.0; 3],
        state: quad.state().clone(),
        ..truth
    };
    (truth, sensors)
}

/// [`contact`], and a quad resting on flat ground stands level (its heading kept). `contact`
/// alone keeps whatever tilt the frame came down with or picked up while hopping (air mode's
/// controllers on a landed frame push the thrust over the weight now and then, and each such
/// step is free flight): 10° of roll over 10 s armed on the ground in the flight SITL, while
/// the accelerometer (the ground's reaction on body z) still reads level.
pub fn contact_level(quad: &mut Quad, truth: Truth, sensors: Sensors) -> (Truth, Sensors) {
    let (truth, sensors) = contact(quad, truth, sensors);
    let resting = truth.state.position_m[2] >= 0.0 && truth.state.velocity_mps == [0.0; 3];
    if !resting {
        return (truth, sensors);
    }
    let half_yaw = truth.euler_deg[2].to_radians() / 2.0;
    let mut st = truth.state.clone();
    st.attitude = [half_yaw.cos(), 0.0, 0.0, half_yaw.sin()];
    st.position_m[2] = 0.0;
    quad.set_state(st);
    let level = quad.state().clone();
    let truth = Truth {
        euler_deg: crate::quad::euler_deg(level.attitude),
        state: level,
        ..truth
    };
    (truth, sensors)
}

/// A quad standing on the ground, level, motors stopped.
pub fn on_the_ground(quad: &mut Quad) {
    let mut ground = quad.state().clone();
    ground.position_m = [0.0; 3];
    ground.motor.iter_mut().for_each(|m| *m = 0.0);
    quad.set_state(ground);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quad::QuadParams;
    use flight_core::control::mixer::QUAD_X;

    #[test]
    fn a_quad_resting_on_flat_ground_stands_level_with_its_heading() {
        let p = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        let tilted = |q: &mut Quad| {
            on_the_ground(q);
            let mut st = q.state().clone();
            // 10° of roll, heading 30° (ZYX: yaw then roll).
            let (r, y) = (5f64.to_radians(), 15f64.to_radians());
            st.attitude = [
                y.cos() * r.cos(),
                y.cos() * r.sin(),
                y.sin() * r.sin(),
                y.sin() * r.cos(),
            ];
            q.set_state(st);
        };
        let mut plain = Quad::new(p.clone(), 3);
        tilted(&mut plain);
        let mut level = Quad::new(p, 3);
        tilted(&mut level);
        let (mut kept, mut stood) = ([0.0; 3], [0.0; 3]);
        for _ in 0..100 {
            let (sensors, truth) = plain.step(0.001, &[0.0; 4]);
            kept = contact(&mut plain, truth, sensors).0.euler_deg;
            let (sensors, truth) = level.step(0.001, &[0.0; 4]);
            stood = contact_level(&mut level, truth, sensors).0.euler_deg;
        }
        assert!(
            (kept[0] - 10.0).abs() < 1e-6 && (kept[2] - 30.0).abs() < 1e-6,
            "{kept:?}"
        );
        assert!(stood[0].abs() < 1e-9 && stood[1].abs() < 1e-9, "{stood:?}");
        assert!((stood[2] - 30.0).abs() < 1e-6, "{stood:?}");
    }

    #[test]
    fn a_stopped_quad_rests_on_the_ground_feeling_one_g_and_lifts_off_with_thrust() {
        let p = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        let mut q = Quad::new(p, 3);
        on_the_ground(&mut q);
        for _ in 0..500 {
            let (sensors, truth) = q.step(0.002, &[0.0; 4]);
            let (truth, sensors) = contact(&mut q, truth, sensors);
            assert!(
                truth.state.position_m[2].abs() < 1e-3,
                "stays on the ground"
            );
            assert_eq!(truth.state.velocity_mps, [0.0; 3]);
            let az = f64::from(sensors.accel_mps2[2]);
            assert!((az + GRAVITY_MPS2).abs() < 0.3, "feels 1 g: {az}");
        }
        // Without contact the accelerometer of the same stopped quad reads free fall.
        let mut free = Quad::new(QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X), 3);
        on_the_ground(&mut free);
        let mut az = 0.0;
        for _ in 0..500 {
            az = f64::from(free.step(0.002, &[0.0; 4]).0.accel_mps2[2]);
        }
        assert!(az.abs() < 0.3, "{az}");
        // Full throttle lifts off.
        for _ in 0..500 {
            let (sensors, truth) = q.step(0.002, &[1.0; 4]);
            contact(&mut q, truth, sensors);
        }
        assert!(q.state().position_m[2] < -0.5, "climbed");
    }
}
