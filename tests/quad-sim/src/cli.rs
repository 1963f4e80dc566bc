//! Command-line pieces shared by the `lqg` and `sysid` host commands (clap derive): the
//! axis model, the LQR costs and the Kalman noise, and the value parsers that refuse
//! nonsense where it is typed (a NaN step, a negative or billion-second duration, a τ
//! outside 1 ms..1 s) with a message naming the flag and exit code 2. The ranges are the
//! flight-core model's own (`AxisModel::new`, `check_sample_period`).

use clap::Args;

/// A finite number within `lo..=hi`.
///
/// # Errors
/// Not a number, not finite, or out of range (the message says which).
pub fn number_in(s: &str, lo: f64, hi: f64) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{s} is not a finite number"));
    }
    if v < lo || v > hi {
        return Err(format!("must be within {lo}..={hi}, got {s}"));
    }
    Ok(v)
}

/// Any finite number.
///
/// # Errors
/// As [`number_in`].
pub fn finite(s: &str) -> Result<f64, String> {
    number_in(s, f64::MIN, f64::MAX)
}

/// ln β (natural log of the authority, (deg/s²)/unit): 0..=20.
///
/// # Errors
/// As [`number_in`].
pub fn ln_beta(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 20.0)
}

/// τ, s: 0.001..=1.
///
/// # Errors
/// As [`number_in`].
pub fn tau(s: &str) -> Result<f64, String> {
    number_in(s, 0.001, 1.0)
}

/// Loop period, s: 1e-5..=0.1.
///
/// # Errors
/// As [`number_in`].
pub fn sample_period(s: &str) -> Result<f64, String> {
    number_in(s, 1e-5, 0.1)
}

/// A simulated duration, s: more than 0, at most 3600 (an hour at 1 kHz is 3.6 M steps).
///
/// # Errors
/// As [`number_in`], or zero.
pub fn duration(s: &str) -> Result<f64, String> {
    let v = number_in(s, 0.0, 3600.0)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be greater than 0, got {s}"))
    }
}

/// A non-negative finite number up to 1e12 (noise σ, variances, costs).
///
/// # Errors
/// As [`number_in`].
pub fn non_negative(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 1e12)
}

/// Exactly three comma-separated non-negative finite numbers: `4,0.04,10000`.
///
/// # Errors
/// Wrong count or a bad number.
pub fn triple(s: &str) -> Result<[f64; 3], String> {
    let items: Vec<f64> = s.split(',').map(non_negative).collect::<Result<_, _>>()?;
    <[f64; 3]>::try_from(items)
        .map_err(|v| format!("needs 3 comma-separated numbers, got {}", v.len()))
}

/// The axis model: ln β1 [ln β2], τ, loop period.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct ModelArgs {
    /// ln β1: natural log of the axis authority in (deg/s²) per unit of output, 0..=20
    /// (a 250-class quad's roll is about 10).
    #[arg(long, value_name = "L", value_parser = ln_beta)]
    pub ln_beta1: f64,
    /// ln β2: a lag-free (yaw-direct) authority besides β1, 0..=20.
    #[arg(long, value_name = "L", value_parser = ln_beta)]
    pub ln_beta2: Option<f64>,
    /// Motor time constant τ, seconds (0.001..=1).
    #[arg(long, value_name = "S", value_parser = tau)]
    pub tau: f64,
    /// Loop period, seconds (1e-5..=0.1).
    #[arg(long, value_name = "S", default_value_t = 0.001, value_parser = sample_period)]
    pub ts: f64,
}

/// LQR costs: given, frame-invariant, or (neither) autotuned.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct CostArgs {
    /// Absolute costs per sample (r = 1): angle, rate, torque.
    #[arg(long, value_name = "ANGLE,RATE,TORQUE", value_parser = triple, conflicts_with = "invariant")]
    pub q: Option<[f64; 3]>,
    /// With --q: make the torque cost β1·X (frame-invariant torque cost).
    #[arg(long, value_name = "X", value_parser = non_negative, requires = "q")]
    pub q4: Option<f64>,
    /// Fully frame-invariant costs q1,q2,q4: q_angle = q1/β1, q_rate = q2/β1, q3 = β1·q4.
    #[arg(long, value_name = "Q1,Q2,Q4", value_parser = triple)]
    pub invariant: Option<[f64; 3]>,
}

/// Kalman filter noise.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct NoiseArgs {
    /// Process noise per sample: rate, torque, bias (Tau Labs' default 1,1e-5,1e-7).
    #[arg(long, value_name = "RATE,TORQUE,BIAS", value_parser = triple)]
    pub kf_q: Option<[f64; 3]>,
    /// Gyro measurement variance, (deg/s)² (default 1000).
    #[arg(long, value_name = "R", value_parser = non_negative)]
    pub kf_r: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_refuse_nonsense() {
        assert_eq!(triple("4, 0.04,10000"), Ok([4.0, 0.04, 10000.0]));
        assert!(triple("4,0.04").is_err());
        assert!(triple("4,x,1").is_err());
        assert!(triple("4,nan,1").is_err());
        for bad in ["-5", "1e9", "nan", "inf", "0", "x"] {
            assert!(duration(bad).is_err(), "{bad}");
        }
        assert_eq!(duration("2.5"), Ok(2.5));
        assert!(finite("nan").is_err());
        assert!(tau("0").is_err());
        assert!(ln_beta("21").is_err());
    }
}
