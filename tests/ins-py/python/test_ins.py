"""Tests of the `ins` module (tests/ins-py): the C module's API on flight-core's INS, the
replay and the magnetometer calibration. Run: python -m unittest discover -s tests/ins-py/python

The filter is driven the way the Tau Labs suite drove its C module (../shared/reference/ekf.md
§5): predict at 666 Hz; GPS position and velocity every 60th step, baro and magnetometer every
20th, each its own correction with its mask bits.
"""

import math
import os
import tempfile
import unittest

import numpy

import ins

DT = 1.0 / 666.0
GRAVITY = ins.GRAVITY
LEVEL = numpy.array([0.0, 0.0, -GRAVITY])
NORTH_FIELD = numpy.array([400.0, 0.0, 1600.0])

POS, VEL, MAG, BARO = 0x003, 0x038, 0x1C0, 0x200


def prepare():
    """init() and the variances the C suite's wrapper (cins.py) configures."""
    state = ins.init()
    ins.configure(
        mag_var=numpy.array([10.0, 10.0, 100.0]),
        gyro_var=numpy.array([1e-5, 1e-5, 1e-4]),
        accel_var=numpy.array([0.01, 0.01, 0.01]),
        baro_var=0.1,
        gps_var=numpy.array([1e-3, 1e-2, 10.0]),
    )
    return state


def z_vector(pos=(0.0, 0.0, 0.0), vel=(0.0, 0.0, 0.0), mag=(0.0, 0.0, 0.0), baro=0.0):
    return numpy.array([*pos, *vel, *mag, baro])


def run_static(seconds, gyro=(0.0, 0.0, 0.0), accel=LEVEL, mag=NORTH_FIELD):
    """A still craft at the origin; returns the final state."""
    state = None
    for k in range(int(seconds * 666)):
        state = ins.prediction(numpy.array(gyro), numpy.array(accel), DT)
        if k % 60 == 59:
            ins.correction(z_vector(), POS)
            state = ins.correction(z_vector(), VEL)
        if k % 20 == 8:
            state = ins.correction(z_vector(baro=0.0), BARO)
        if k % 20 == 15:
            state = ins.correction(z_vector(mag=mag), MAG)
    return state


def yaw_deg(q):
    q0, q1, q2, q3 = q
    return math.degrees(math.atan2(2 * (q1 * q2 + q0 * q3), q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3))


def tilt_deg(q):
    q0, q1, q2, q3 = q
    roll = math.atan2(2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)
    pitch = math.asin(max(-1.0, min(1.0, -2 * (q1 * q3 - q0 * q2))))
    return math.degrees(max(abs(roll), abs(pitch)))


class TheCModulesApi(unittest.TestCase):
    def setUp(self):
        prepare()

    def test_init_returns_the_16_value_state_at_the_origin_level_north(self):
        state = ins.init()
        self.assertIsInstance(state, numpy.ndarray)
        self.assertEqual(state.dtype, numpy.float64)
        self.assertEqual(state.shape, (16,))
        numpy.testing.assert_array_equal(state[6:10], [1.0, 0.0, 0.0, 0.0])
        numpy.testing.assert_array_equal(numpy.delete(state, 6), numpy.zeros(15))

    def test_a_still_craft_stays_at_the_origin(self):
        state = run_static(20.0)
        self.assertLess(numpy.abs(state[0:6]).max(), 1e-3)
        self.assertLess(tilt_deg(state[6:10]), 0.01)
        self.assertLess(abs(yaw_deg(state[6:10])), 0.01)

    def test_facing_east_is_found_from_the_magnetometer(self):
        # The C suite's test_face_west: the field reads [0, -400, 1600], yaw is +90°.
        state = run_static(10.0, mag=numpy.array([0.0, -400.0, 1600.0]))
        self.assertAlmostEqual(yaw_deg(state[6:10]), 90.0, delta=0.1)

    def test_a_gyro_bias_is_learned(self):
        bias = [0.02, -0.03, 0.04]
        state = run_static(30.0, gyro=bias)
        numpy.testing.assert_allclose(state[10:13], bias, atol=0.002)
        self.assertLess(tilt_deg(state[6:10]), 0.1)

    def test_an_accelerometer_bias_beyond_the_c_filters_clamp_is_learned(self):
        # The C filter clamps the z bias at ±0.1 m/s² and fails this (ekf.md §7).
        state = run_static(60.0, accel=[0.0, 0.0, -GRAVITY - 0.2])
        self.assertAlmostEqual(state[15], -0.2, delta=0.005)
        numpy.testing.assert_array_equal(state[13:15], [0.0, 0.0])
        self.assertLess(numpy.abs(state[0:6]).max(), 0.05)

    def test_set_state_overwrites_only_what_it_is_given_and_normalises_q(self):
        ins.set_state(pos=numpy.array([1.0, 2.0, 3.0]), q=[2.0, 0.0, 0.0, 0.0])
        ins.set_state(accel_bias=[0.5, 0.5, 0.25])
        state = ins.get_state()
        numpy.testing.assert_allclose(state[0:3], [1.0, 2.0, 3.0])
        numpy.testing.assert_allclose(state[6:10], [1.0, 0.0, 0.0, 0.0])
        numpy.testing.assert_allclose(state[13:16], [0.0, 0.0, 0.25])

    def test_corrections_shrink_the_variances(self):
        before = ins.get_variance()
        self.assertEqual(before.shape, (14,))
        run_static(2.0)
        after = ins.get_variance()
        self.assertLess(after[0], before[0] / 100)
        self.assertLess(after[3], before[3] / 100)

    def test_configure_sets_how_far_a_baro_reading_pulls(self):
        # From the initial 25 m² down-position variance, a 1 m reading moves the estimate by
        # the Kalman gain P/(P + R).
        for baro_var in (0.01, 100.0):
            prepare()
            ins.configure(baro_var=baro_var)
            p = ins.get_variance()[2]
            state = ins.correction(z_vector(baro=1.0), BARO)
            self.assertAlmostEqual(-state[2], p / (p + baro_var), delta=1e-4)


class RefusedInput(unittest.TestCase):
    def setUp(self):
        prepare()

    def test_vectors_of_the_wrong_length_or_shape(self):
        with self.assertRaisesRegex(ValueError, "received 2 and expected 3"):
            ins.prediction([0.0, 0.0], LEVEL, DT)
        with self.assertRaises(ValueError):
            ins.prediction(numpy.zeros((3, 1)), LEVEL, DT)
        with self.assertRaises(ValueError):
            ins.correction(numpy.zeros(9), POS)
        with self.assertRaises(ValueError):
            ins.set_state(q=[1.0, 0.0, 0.0])

    def test_non_finite_values_and_time_steps(self):
        with self.assertRaises(ValueError):
            ins.prediction([math.nan, 0.0, 0.0], LEVEL, DT)
        with self.assertRaises(ValueError):
            ins.prediction([0.0, 0.0, 0.0], LEVEL, 0.0)
        with self.assertRaises(ValueError):
            ins.configure(baro_var=math.inf)
        numpy.testing.assert_array_equal(ins.get_state()[6:10], [1.0, 0.0, 0.0, 0.0])

    def test_masks_the_filter_has_no_update_for(self):
        for sensors in (0x001, 0x004, 0x008, 0x400, -1):
            with self.assertRaises(ValueError, msg=hex(sensors)):
                ins.correction(z_vector(), sensors)
        # Row 8 (vertical field) alone is accepted and does nothing, as its H was zero in C.
        before = ins.get_state()
        numpy.testing.assert_array_equal(ins.correction(z_vector(mag=(0, 400, 0)), 0x100), before)


class Replay(unittest.TestCase):
    def write(self, lines):
        f = tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False)
        f.write("\n".join(lines) + "\n")
        f.close()
        self.addCleanup(os.remove, f.name)
        return f.name

    def test_a_still_log_facing_east_replays_level_and_east(self):
        # 10 s at 250 Hz, level, facing east: the field (0.2 G north) reads on −y.
        lines = []
        for k in range(2500):
            t = k * 4000
            lines.append(f"{t},imu,0,0,{-GRAVITY},0,0,0")
            if k % 5 == 0:
                lines.append(f"{t},mag,0,-0.2,0.43")
            if k % 10 == 0:
                lines.append(f"{t},baro,100.0")
            if k % 25 == 0:
                lines.append(f"{t},gps,100000,80000000,470000000,0,0,0")
        rows = ins.replay(self.write(lines))
        self.assertEqual(rows.shape, (2500, len(ins.REPLAY_COLUMNS)))
        self.assertEqual(ins.REPLAY_COLUMNS[0], "time_us")
        last = rows[-1]
        self.assertEqual(last[0], 2499 * 4000)
        q = last[1:5]
        self.assertAlmostEqual(yaw_deg(q), 90.0, delta=0.5)
        self.assertLess(tilt_deg(q), 0.1)
        self.assertLess(numpy.abs(last[5:11]).max(), 0.05)

    def test_a_malformed_log_names_its_line(self):
        path = self.write(["0,imu,0,0,-9.8,0,0,0", "4000,imu,0,0,nan,0,0,0"])
        with self.assertRaisesRegex(ValueError, "line 2"):
            ins.replay(path)


class MagnetometerCalibration(unittest.TestCase):
    def test_recovers_a_hard_iron_offset_from_a_rotation(self):
        offset = numpy.array([12.0, -30.0, 45.0])
        scale = numpy.array([1.1, 0.9, 1.0])
        samples = []
        for i in range(20):
            for j in range(20):
                theta = math.pi * (i + 0.5) / 20
                phi = 2 * math.pi * j / 20
                d = numpy.array(
                    [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]
                )
                samples.append(50.0 * d * scale + offset)
        result = ins.magcal(numpy.array(samples))
        numpy.testing.assert_allclose(result["offset"], offset, atol=0.05)
        self.assertEqual(result["matrix"].shape, (3, 3))
        self.assertAlmostEqual(numpy.linalg.det(result["matrix"]), 1.0, places=3)
        self.assertLess(result["residual_pct"], 0.5)
        self.assertGreater(result["coverage"], 0.7)

    def test_refuses_a_turn_in_one_plane(self):
        samples = [[50 * math.cos(a), 50 * math.sin(a), 0.0] for a in numpy.linspace(0, 6.2, 200)]
        with self.assertRaises(ValueError):
            ins.magcal(samples)


if __name__ == "__main__":
    unittest.main()
