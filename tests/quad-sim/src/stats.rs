//! Statistics for the experiments: mean and sample standard deviation, one-way ANOVA, and
//! the F distribution's CDF through the regularized incomplete beta function (Lentz's
//! continued fraction, as in Numerical Recipes §6.4) with a Lanczos ln Γ.

/// Mean and sample standard deviation (n − 1); `None` for fewer than one value.
#[must_use]
pub fn mean_std(values: &[f64]) -> Option<(f64, f64)> {
    if values.is_empty() {
        return None;
    }
    #[allow(clippy::cast_precision_loss)]
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
    let std = if values.len() > 1 {
        (ss / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    Some((mean, std))
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms: ≈ 15 significant digits).
#[must_use]
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        #[allow(clippy::cast_precision_loss)]
        let k = i as f64;
        a += c / (x + k);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularized incomplete beta function I_x(a, b) for a, b > 0, 0 ≤ x ≤ 1.
#[must_use]
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    // The continued fraction converges fast for x < (a + 1)/(a + b + 2); use the symmetry
    // I_x(a, b) = 1 − I_{1−x}(b, a) otherwise.
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_fraction(a, b, x) / a
    } else {
        1.0 - front * beta_fraction(b, a, 1.0 - x) / b
    }
}

/// The continued fraction of I_x(a, b), modified Lentz.
fn beta_fraction(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-15;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=300 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// CDF of the F distribution with (d1, d2) degrees of freedom at `f` ≥ 0.
#[must_use]
pub fn f_cdf(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 0.0;
    }
    incomplete_beta(d1 / 2.0, d2 / 2.0, d1 * f / (d1 * f + d2))
}

/// One-way analysis of variance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Anova {
    /// F statistic (between-group over within-group mean square).
    pub f: f64,
    /// Between-group degrees of freedom, k − 1.
    pub df_between: usize,
    /// Within-group degrees of freedom, N − k.
    pub df_within: usize,
    /// P(F ≥ f) under the null hypothesis of equal means.
    pub p: f64,
}

/// One-way ANOVA over `groups`; `None` with fewer than two groups or no within-group
/// degrees of freedom.
#[must_use]
pub fn one_way_anova(groups: &[Vec<f64>]) -> Option<Anova> {
    let k = groups.len();
    let n: usize = groups.iter().map(Vec::len).sum();
    if k < 2 || n <= k || groups.iter().any(Vec::is_empty) {
        return None;
    }
    #[allow(clippy::cast_precision_loss)]
    let grand = groups.iter().flatten().sum::<f64>() / n as f64;
    let mut ss_between = 0.0;
    let mut ss_within = 0.0;
    for g in groups {
        let (mean, _) = mean_std(g)?;
        #[allow(clippy::cast_precision_loss)]
        let len = g.len() as f64;
        ss_between += len * (mean - grand) * (mean - grand);
        ss_within += g.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>();
    }
    let (df_b, df_w) = (k - 1, n - k);
    #[allow(clippy::cast_precision_loss)]
    let f = (ss_between / df_b as f64) / (ss_within / df_w as f64);
    #[allow(clippy::cast_precision_loss)]
    let p = if f.is_finite() {
        1.0 - f_cdf(f, df_b as f64, df_w as f64)
    } else {
        0.0
    };
    Some(Anova {
        f,
        df_between: df_b,
        df_within: df_w,
        p,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials_and_half_integers() {
        for (x, want) in [(1.0, 1.0f64), (2.0, 1.0), (5.0, 24.0), (11.0, 3_628_800.0)] {
            assert!((ln_gamma(x) - want.ln()).abs() < 1e-12, "{x}");
        }
        // Γ(1/2) = √π.
        let half = std::f64::consts::PI.sqrt().ln();
        assert!((ln_gamma(0.5) - half).abs() < 1e-12);
    }

    #[test]
    fn incomplete_beta_matches_binomial_sums_and_symmetry() {
        // Integer a, b: I_x(a, b) = P(Binomial(a + b − 1, x) ≥ a).
        assert!((incomplete_beta(2.0, 3.0, 0.5) - 11.0 / 16.0).abs() < 1e-12);
        // I_0.3(1, 4) = 1 − 0.7⁴.
        assert!((incomplete_beta(1.0, 4.0, 0.3) - (1.0 - 0.7f64.powi(4))).abs() < 1e-12);
        // I_x(a, a) at x = 1/2 is 1/2 for any a.
        assert!((incomplete_beta(3.5, 3.5, 0.5) - 0.5).abs() < 1e-12);
        let (a, b, x) = (2.5, 7.0, 0.35);
        assert!((incomplete_beta(a, b, x) + incomplete_beta(b, a, 1.0 - x) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn f_distribution_matches_table_critical_values() {
        // Upper critical values from standard F tables: P(F ≥ c) = α.
        for (c, d1, d2, alpha) in [
            (5.143_25, 2.0, 6.0, 0.05),
            (10.924_8, 2.0, 6.0, 0.01),
            (3.354_13, 2.0, 27.0, 0.05),
            (4.964_60, 1.0, 10.0, 0.05),
        ] {
            let p = 1.0 - f_cdf(c, d1, d2);
            assert!((p - alpha).abs() < 1e-4, "F({d1}, {d2}) at {c}: p {p}");
        }
        // d1 = 2 has a closed form: P(F ≥ f) = (1 + 2f/d2)^(−d2/2).
        let (f, d2) = (3.7_f64, 9.0_f64);
        let closed = (1.0 + 2.0 * f / d2).powf(-d2 / 2.0);
        assert!((1.0 - f_cdf(f, 2.0, d2) - closed).abs() < 1e-12);
    }

    #[test]
    fn anova_of_a_textbook_example() {
        let groups = vec![
            vec![4.0, 5.0, 6.0],
            vec![5.0, 6.0, 7.0],
            vec![7.0, 8.0, 9.0],
        ];
        let a = one_way_anova(&groups).unwrap();
        // Means 5, 6, 8; grand 19/3. SSB = 3·((5 − 19/3)² + (6 − 19/3)² + (8 − 19/3)²) = 14;
        // SSW = 3 · 2 = 6; F = (14/2)/(6/6) = 7.
        assert!((a.f - 7.0).abs() < 1e-12, "{a:?}");
        assert_eq!((a.df_between, a.df_within), (2, 6));
        // d1 = 2 closed form.
        let closed = (1.0 + 2.0 * 7.0 / 6.0f64).powf(-3.0);
        assert!((a.p - closed).abs() < 1e-12);
        assert!(one_way_anova(&groups[..1]).is_none());
    }
}
