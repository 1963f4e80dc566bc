//! The Python module `ins`: flight-core's 14-state INS ([`Ins`]: the filter and its aiding
//! policy) behind the API of the Tau Labs / dRonin `python/ins` C extension (`insmodule.c`),
//! so analysis scripts written for that module — its `cins.py` wrapper and `test.py` suite —
//! run on our estimator; plus the `replay` tool and the magnetometer calibration.
//!
//! The C extension holds one filter in globals; so does this module (one `Session` behind
//! a mutex), created at import as the C module's init did. Vectors are accepted as any 1-D
//! sequence of numbers of the stated length (numpy arrays, lists, tuples); state vectors are
//! returned as float64 numpy arrays of 16: position, velocity, quaternion, gyro bias and
//! accelerometer bias `[0, 0, z]` (only the z bias is a state), as the C module returned them.
//!
//! What the C module's calls mean here (its `insgps.h` semantics, `../shared/reference/ekf.md`
//! §4–6):
//! - `configure(gyro_var=, accel_var=)` are per-step variances that the C filter scaled by
//!   dT² at each predict; ours takes noise densities, and PSD = variance·dT gives the same
//!   per-step noise, so the density is set from them at each `prediction`'s dT. The
//!   accelerometer noise is isotropic here: the mean of the three is used; `mag_var` is the
//!   variance of each horizontal heading-frame component (its z is unused, as the C filter's
//!   row 8 had H = 0).
//! - `correction(Z, sensors)` takes the C mask bits: GPS position north/east (0x003, both
//!   or neither) and down (0x004, only with north/east), GPS velocity (0x038, all three or
//!   none), magnetometer (any of 0x0C0 fuses the heading; 0x100 alone does nothing, as in C),
//!   baro (0x200). Partial masks the filter has no update for raise `ValueError`, naming it.
//! - Rejected measurements are outcomes, not errors (the aiding resets a part of the state
//!   after a run of them); a diverged filter raises `RuntimeError` until `init()`.

use std::sync::{Mutex, MutexGuard};

use flight_core::estimation::Error;
use flight_core::estimation::ins::aiding::AidingConfig;
use flight_core::estimation::ins::{Config, Ins, STATES, State};
use flight_core::estimation::magcal::{MagCalConfig, fit};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The earth field the C module's `init()` set (its `INSSetMagNorth`).
const EARTH_FIELD: [f32; 3] = [400.0, 0.0, 1600.0];

/// Sensor mask bits of `insgps.h`.
mod mask {
    pub const HORIZONTAL_POSITION: i64 = 0x003;
    pub const VERTICAL_POSITION: i64 = 0x004;
    pub const VELOCITY: i64 = 0x038;
    pub const MAG_HORIZONTAL: i64 = 0x0C0;
    pub const BARO: i64 = 0x200;
    pub const ALL: i64 = 0x3FF;
}

/// The C filter's configurable variances, as its setters took them.
#[derive(Debug, Clone, Copy)]
struct Variances {
    gyro: [f32; 3],
    accel: [f32; 3],
}

/// The module's filter.
struct Session {
    ins: Ins,
    variances: Variances,
    /// dT the noise densities were last set for.
    dt_s: f32,
}

impl Session {
    /// `INSGPSInit()` + `INSSetMagNorth([400, 0, 1600])`: the C defaults for what its API
    /// configures (gyro 1e-5, accel 1e-5, GPS 0.004 / vertical 0.036, baro 0.05, mag 0.005),
    /// flight-core's own tuning for the rest (bias walks, initial covariance, gate, limits).
    fn new() -> Self {
        let config = Config {
            earth_field_ned: EARTH_FIELD,
            gps_horizontal_var_m2: 0.004,
            gps_vertical_var_m2: 0.036,
            gps_velocity_var_m2ps2: 0.004,
            baro_var_m2: 0.05,
            mag_var: 0.005,
            ..Config::default()
        };
        let mut session = Self {
            ins: Ins::new(config, AidingConfig::default()),
            variances: Variances {
                gyro: [1e-5; 3],
                accel: [1e-5; 3],
            },
            dt_s: 0.0,
        };
        session.set_noise_for(1.0 / 666.0);
        session
    }

    /// The noise densities for a step of `dt_s` (PSD = the C variance · dT).
    fn set_noise_for(&mut self, dt_s: f32) {
        let mut config = *self.ins.filter().config();
        config.gyro_noise_psd = self.variances.gyro.map(|v| v * dt_s);
        let [a0, a1, a2] = self.variances.accel;
        config.accel_noise_psd = (a0 + a1 + a2) / 3.0 * dt_s;
        self.ins.filter_mut().set_config(config);
        self.dt_s = dt_s;
    }

    fn configure(&mut self, change: impl FnOnce(&mut Config, &mut Variances)) {
        let mut config = *self.ins.filter().config();
        change(&mut config, &mut self.variances);
        self.ins.filter_mut().set_config(config);
        let dt = self.dt_s;
        self.set_noise_for(dt);
    }

    /// The state as the C module packed it (16 values).
    fn packed(&self) -> [f64; 16] {
        let s = self.ins.state();
        let [p0, p1, p2] = s.position_ned_m;
        let [v0, v1, v2] = s.velocity_ned_mps;
        let [q0, q1, q2, q3] = s.attitude;
        let [b0, b1, b2] = s.gyro_bias_radps;
        [
            p0,
            p1,
            p2,
            v0,
            v1,
            v2,
            q0,
            q1,
            q2,
            q3,
            b0,
            b1,
            b2,
            0.0,
            0.0,
            s.accel_bias_z_mps2,
        ]
        .map(f64::from)
    }
}

static SESSION: Mutex<Option<Session>> = Mutex::new(None);

/// The module's session, created if none.
fn session() -> PyResult<MutexGuard<'static, Option<Session>>> {
    let mut guard = SESSION
        .lock()
        .map_err(|_| PyRuntimeError::new_err("the INS session is poisoned by an earlier panic"))?;
    if guard.is_none() {
        *guard = Some(Session::new());
    }
    Ok(guard)
}

/// Runs `f` on the session.
fn with_session<T>(f: impl FnOnce(&mut Session) -> PyResult<T>) -> PyResult<T> {
    let mut guard = session()?;
    match guard.as_mut() {
        Some(s) => f(s),
        None => Err(PyRuntimeError::new_err("no INS session")),
    }
}

/// An estimator error as the Python exception it means.
fn py_error(e: Error) -> PyErr {
    match e {
        Error::NonFinite => PyValueError::new_err("non-finite input refused"),
        Error::InvalidTimeStep => PyValueError::new_err("dT must be within (0, 0.1] s"),
        Error::Diverged => {
            PyRuntimeError::new_err("the INS state is no longer finite: call ins.init()")
        }
    }
}

/// A 1-D sequence of exactly `N` numbers.
fn vector<const N: usize>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<[f32; N]> {
    let shape_error =
        || PyValueError::new_err(format!("{name} must be a 1-D sequence of {N} numbers"));
    let mut out = [0.0_f32; N];
    let mut n = 0;
    for item in obj.try_iter().map_err(|_| shape_error())? {
        let v: f64 = item?.extract().map_err(|_| shape_error())?;
        match out.get_mut(n) {
            Some(slot) => *slot = v as f32,
            None => return Err(shape_error()),
        }
        n += 1;
    }
    if n == N {
        Ok(out)
    } else {
        Err(PyValueError::new_err(format!(
            "{name}: vector length incorrect, received {n} and expected {N}"
        )))
    }
}

/// A float64 numpy array of `values` (nested lists give more dimensions).
fn array<'py, T>(py: Python<'py>, values: T) -> PyResult<Bound<'py, PyAny>>
where
    T: IntoPyObject<'py>,
{
    py.import("numpy")?
        .call_method1("array", (values, "float64"))
}

fn state_array<'py>(py: Python<'py>, s: &Session) -> PyResult<Bound<'py, PyAny>> {
    array(py, s.packed().to_vec())
}

/// Reset the INS (the C module's `init`): origin, level, facing north, default variances,
/// earth field [400, 0, 1600]. Returns the state.
#[pyfunction]
fn init(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let mut guard = session()?;
    let s = guard.insert(Session::new());
    state_array(py, s)
}

/// Advance the state by one step: gyros (rad/s, 3), accels (m/s², 3; level reads
/// [0, 0, −9.805]), dT (s). Returns the state.
#[pyfunction]
#[pyo3(name = "prediction")]
fn prediction<'py>(
    py: Python<'py>,
    gyros: &Bound<'py, PyAny>,
    accels: &Bound<'py, PyAny>,
    dt: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let gyro = vector::<3>("gyros", gyros)?;
    let accel = vector::<3>("accels", accels)?;
    let dt = dt as f32;
    with_session(|s| {
        if dt != s.dt_s && dt > 0.0 {
            s.set_noise_for(dt);
        }
        s.ins.predict(gyro, accel, dt).map_err(py_error)?;
        state_array(py, s)
    })
}

/// Apply the measurements `sensors` selects from Z = [pN, pE, pD, vN, vE, vD, mx, my, mz,
/// baro altitude] (the C mask bits, see the module doc). Returns the state.
#[pyfunction]
fn correction<'py>(
    py: Python<'py>,
    z: &Bound<'py, PyAny>,
    sensors: i64,
) -> PyResult<Bound<'py, PyAny>> {
    let [pn, pe, pd, vn, ve, vd, mx, my, mz, baro] = vector::<10>("Z", z)?;
    if sensors & !mask::ALL != 0 || sensors < 0 {
        return Err(PyValueError::new_err(format!(
            "sensors 0x{sensors:X} has bits outside 0x3FF"
        )));
    }
    let horizontal = sensors & mask::HORIZONTAL_POSITION;
    let vertical = sensors & mask::VERTICAL_POSITION != 0;
    if horizontal != 0 && horizontal != mask::HORIZONTAL_POSITION || vertical && horizontal == 0 {
        return Err(PyValueError::new_err(
            "GPS position: north and east are fused together (0x003), down only with them (0x007)",
        ));
    }
    let velocity = sensors & mask::VELOCITY;
    if velocity != 0 && velocity != mask::VELOCITY {
        return Err(PyValueError::new_err(
            "GPS velocity: the three axes are fused together (0x038)",
        ));
    }
    with_session(|s| {
        if horizontal != 0 {
            s.ins
                .gps_position([pn, pe, pd], vertical)
                .map_err(py_error)?;
        }
        if velocity != 0 {
            s.ins.gps_velocity([vn, ve, vd]).map_err(py_error)?;
        }
        if sensors & mask::MAG_HORIZONTAL != 0 {
            s.ins.mag([mx, my, mz]).map_err(py_error)?;
        }
        if sensors & mask::BARO != 0 {
            s.ins.baro(baro).map_err(py_error)?;
        }
        state_array(py, s)
    })
}

/// Set the variances (the C module's `configure`): mag_var (3, heading-frame components),
/// accel_var (3), gyro_var (3), baro_var (a 0 is ignored), gps_var = [position, velocity,
/// vertical position]. Returns None.
#[pyfunction]
#[pyo3(signature = (mag_var=None, accel_var=None, gyro_var=None, baro_var=0.0, gps_var=None))]
fn configure(
    mag_var: Option<&Bound<'_, PyAny>>,
    accel_var: Option<&Bound<'_, PyAny>>,
    gyro_var: Option<&Bound<'_, PyAny>>,
    baro_var: f64,
    gps_var: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let mag = mag_var.map(|v| vector::<3>("mag_var", v)).transpose()?;
    let accel = accel_var.map(|v| vector::<3>("accel_var", v)).transpose()?;
    let gyro = gyro_var.map(|v| vector::<3>("gyro_var", v)).transpose()?;
    let gps = gps_var.map(|v| vector::<3>("gps_var", v)).transpose()?;
    let all = [mag, accel, gyro, gps]
        .iter()
        .flatten()
        .flatten()
        .chain(std::iter::once(&(baro_var as f32)))
        .all(|v| v.is_finite() && *v >= 0.0);
    if !all {
        return Err(PyValueError::new_err(
            "variances must be finite and not negative",
        ));
    }
    with_session(|s| {
        s.configure(|config, variances| {
            if let Some([m0, m1, _]) = mag {
                config.mag_var = 0.5 * (m0 + m1);
            }
            if let Some(a) = accel {
                variances.accel = a;
            }
            if let Some(g) = gyro {
                variances.gyro = g;
            }
            if baro_var != 0.0 {
                config.baro_var_m2 = baro_var as f32;
            }
            if let Some([pos, vel, vertical]) = gps {
                config.gps_horizontal_var_m2 = pos;
                config.gps_velocity_var_m2ps2 = vel;
                config.gps_vertical_var_m2 = vertical;
            }
        });
        Ok(())
    })
}

/// Overwrite parts of the state (the C module's `set_state`): pos (3), vel (3), q (4,
/// normalised), gyro_bias (3), accel_bias (3, only z is a state). The covariance is kept.
/// Returns None.
#[pyfunction]
#[pyo3(signature = (pos=None, vel=None, q=None, gyro_bias=None, accel_bias=None))]
fn set_state(
    pos: Option<&Bound<'_, PyAny>>,
    vel: Option<&Bound<'_, PyAny>>,
    q: Option<&Bound<'_, PyAny>>,
    gyro_bias: Option<&Bound<'_, PyAny>>,
    accel_bias: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let pos = pos.map(|v| vector::<3>("pos", v)).transpose()?;
    let vel = vel.map(|v| vector::<3>("vel", v)).transpose()?;
    let q = q.map(|v| vector::<4>("q", v)).transpose()?;
    let gyro_bias = gyro_bias.map(|v| vector::<3>("gyro_bias", v)).transpose()?;
    let accel_bias = accel_bias
        .map(|v| vector::<3>("accel_bias", v))
        .transpose()?;
    with_session(|s| {
        let old = s.ins.state();
        let new = State {
            position_ned_m: pos.unwrap_or(old.position_ned_m),
            velocity_ned_mps: vel.unwrap_or(old.velocity_ned_mps),
            attitude: q.unwrap_or(old.attitude),
            gyro_bias_radps: gyro_bias.unwrap_or(old.gyro_bias_radps),
            accel_bias_z_mps2: accel_bias.map_or(old.accel_bias_z_mps2, |[_, _, z]| z),
        };
        s.ins.filter_mut().set_state(&new).map_err(py_error)
    })
}

/// The state (16 values, as `init` returns it).
#[pyfunction]
fn get_state(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    with_session(|s| state_array(py, s))
}

/// The variances of the 14 states (the diagonal of P): position, velocity, quaternion,
/// gyro bias, z accelerometer bias.
#[pyfunction]
fn get_variance(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    with_session(|s| {
        let p = s.ins.filter().covariance();
        let diag: Vec<f64> = (0..STATES)
            .map(|i| {
                p.get(i)
                    .and_then(|row| row.get(i))
                    .copied()
                    .map_or(f64::NAN, f64::from)
            })
            .collect();
        array(py, diag)
    })
}

/// The columns of `replay`'s rows.
const REPLAY_COLUMNS: &str = ins_sim::replay::HEADER;

/// Run the INS over a PX4 ECL replay-format sensor log (what `cargo run -p ins-sim --bin
/// replay` does): returns an N×15 float64 array, one row per IMU sample, columns
/// `REPLAY_COLUMNS` (time_us, quaternion, velocity, position, gyro bias, z accel bias).
/// `noise` is the replay's `--noise` list (e.g. "gyro=0.004,mag=0.005"), `declination_deg`
/// its `--declination-deg`. A malformed log raises `ValueError` naming the line.
#[pyfunction]
#[pyo3(signature = (path, noise=None, declination_deg=0.0))]
fn replay<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    noise: Option<&str>,
    declination_deg: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let text = std::fs::read_to_string(&path)
        .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
    let records = ins_sim::replay::parse_sensors(&text)
        .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
    let declination = declination_deg as f32;
    if !(declination.is_finite() && (-180.0..=180.0).contains(&declination)) {
        return Err(PyValueError::new_err(
            "declination_deg must be within -180..=180",
        ));
    }
    let noise = noise
        .map(ins_sim::noise::parse_noise)
        .transpose()
        .map_err(PyValueError::new_err)?;
    let options = ins_sim::replay::Options {
        declination_deg: declination,
        noise,
        ..ins_sim::replay::Options::default()
    };
    let rows = py.detach(|| ins_sim::replay::run(&records, &options));
    let table: Vec<[f64; 15]> = rows
        .iter()
        .map(|r| {
            let [qw, qx, qy, qz] = r.attitude;
            let [vn, ve, vd] = r.velocity_ned_mps;
            let [pn, pe, pd] = r.position_ned_m;
            let [bx, by, bz] = r.gyro_bias_radps;
            [
                r.time_us as f64,
                qw,
                qx,
                qy,
                qz,
                vn,
                ve,
                vd,
                pn,
                pe,
                pd,
                bx,
                by,
                bz,
                r.accel_bias_z_mps2,
            ]
        })
        .collect();
    array(py, table)
}

/// Hard/soft-iron magnetometer calibration (what `magcal` and the flight console's
/// `magcal` do) from readings taken while the frame is turned through every orientation:
/// `samples` is N×3 (any consistent unit). Returns a dict with `offset` (3), `matrix` (3×3,
/// calibrated = matrix · (raw − offset)), `field`, `residual_pct` and `coverage`; data that
/// cannot determine a calibration raises `ValueError` with the reason.
#[pyfunction]
fn magcal<'py>(py: Python<'py>, samples: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let mut readings = Vec::new();
    for item in samples.try_iter()? {
        readings.push(vector::<3>("each sample", &item?)?);
    }
    let c = fit(&readings, &MagCalConfig::default())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let out = PyDict::new(py);
    out.set_item("offset", array(py, c.offset.map(f64::from).to_vec())?)?;
    let matrix: Vec<Vec<f64>> = c
        .matrix
        .iter()
        .map(|row| row.iter().map(|&v| f64::from(v)).collect())
        .collect();
    out.set_item("matrix", array(py, matrix)?)?;
    out.set_item("field", f64::from(c.field))?;
    out.set_item("residual_pct", f64::from(c.residual_pct))?;
    out.set_item("coverage", f64::from(c.coverage))?;
    Ok(out)
}

#[pymodule]
fn ins(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(init, m)?)?;
    m.add_function(wrap_pyfunction!(prediction, m)?)?;
    m.add_function(wrap_pyfunction!(correction, m)?)?;
    m.add_function(wrap_pyfunction!(configure, m)?)?;
    m.add_function(wrap_pyfunction!(set_state, m)?)?;
    m.add_function(wrap_pyfunction!(get_state, m)?)?;
    m.add_function(wrap_pyfunction!(get_variance, m)?)?;
    m.add_function(wrap_pyfunction!(replay, m)?)?;
    m.add_function(wrap_pyfunction!(magcal, m)?)?;
    m.add(
        "REPLAY_COLUMNS",
        REPLAY_COLUMNS.split(',').collect::<Vec<_>>(),
    )?;
    m.add("GRAVITY", f64::from(flight_core::estimation::GRAVITY_MPS2))?;
    // As the C module's import did: a fresh filter.
    drop(session()?);
    Ok(())
}
