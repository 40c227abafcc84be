//! The effects' arithmetic on the CPU, in f64. `shaders/effects.wgsl` is the
//! same functions in f32, under the same names and in the same order.
//!
//! Every function reduces to the baseline's arithmetic at zero strength
//! (`tests/integration/effects.rs` checks paths bit for bit).

use crate::engine::effects::{
    HarmonicForm, HysteresisForm, MIXTURE_OUTLIER_QUANTILE, MIXTURE_OUTLIER_SHARE, NonGaussianForm, polynomial_linear,
};

/// Harmonic waveform g(c) of a form, c = cos(kθ + φ). The `position` form
/// has none (it follows x: [`position_load`]); it reads as `fourier`'s.
pub fn harmonic_wave(form: HarmonicForm, c: f64, shape: f64, shape_mean: f64) -> f64 {
    match form {
        HarmonicForm::Bumps => c.max(0.0).powf(shape) - shape_mean,
        HarmonicForm::Square => (shape * c).tanh() / shape.tanh(),
        HarmonicForm::Fourier | HarmonicForm::Position => c,
    }
}

/// The `position` form's part of the normal force, N: `(αN0 + βN0 r) r`
/// with `linear_n` = αN0 (N per U0), `quadratic_n` = βN0 (N per U0²) and
/// `r` = x/U0 (–), the displacement at the interval's start over the base
/// amplitude.
pub fn position_load(linear_n: f64, quadratic_n: f64, r: f64) -> f64 {
    (linear_n + quadratic_n * r) * r
}

/// Standardised non-Gaussian transform of a standard normal `g`, with an
/// independent standard normal `g2`; strength `s` and the `polynomial`
/// form's cubic coefficient `d` (both –).
pub fn non_gaussian(form: NonGaussianForm, s: f64, d: f64, g: f64, g2: f64) -> f64 {
    match form {
        NonGaussianForm::Polynomial => g * (polynomial_linear(s, d) + g * (s + d * g)) - s,
        NonGaussianForm::Lognormal => {
            if s == 0.0 {
                g
            } else {
                let v = s * s;
                ((s * g).exp() - (0.5 * v).exp()) / ((v.exp() - 1.0) * v.exp()).sqrt()
            }
        }
        NonGaussianForm::TukeyH => g * (0.5 * s * g * g).exp() * (1.0 - 2.0 * s).powf(0.75),
        NonGaussianForm::Skew => (g + s * (g2 * g2 - 1.0) * std::f64::consts::FRAC_1_SQRT_2) / (1.0 + s * s).sqrt(),
        NonGaussianForm::Mixture => {
            if s == 0.0 {
                return g;
            }
            // With probability p (g2 below its p-quantile) the outlier
            // component N(3s, (1 + s)²), else N(0, 1); standardised.
            let p = MIXTURE_OUTLIER_SHARE;
            let (shift, width) = (3.0 * s, 1.0 + s);
            let x = if g2 < MIXTURE_OUTLIER_QUANTILE { shift + width * g } else { g };
            let mean = p * shift;
            let variance = p * (width * width + shift * shift) + (1.0 - p) - mean * mean;
            (x - mean) / variance.sqrt()
        }
    }
}

/// `e^(−x)` (x ≥ 0) as the library gives it, but 0 without the call past
/// x = 746, where the result underflows to 0 anyway: glibc takes a slow
/// path there (it sets `errno`), and a slip many build-up lengths long
/// asks for it at every stage.
pub fn exp_neg(x: f64) -> f64 {
    if x > 746.0 { 0.0 } else { (-x).exp() }
}

/// `1 − e^(−x)` (x ≥ 0) as the library's `exp` gives it, but 1 without the
/// call past x = 40: there `e^(−x)` < 4.3e-18, under half the spacing of
/// f64 below 1 (2⁻⁵³), so the difference rounds to exactly 1 either way.
pub fn one_minus_exp_neg(x: f64) -> f64 {
    if x > 40.0 { 1.0 } else { 1.0 - (-x).exp() }
}

/// Excess of the static coefficient after `dwell_s` seconds stuck, with
/// ageing time `ageing_s` (stiction `dwell`): `Δ (1 − e^(−t_d/τ_d))`, the
/// full `Δ` at once when `τ_d` is 0.
pub fn dwell_excess(excess: f64, dwell_s: f64, ageing_s: f64) -> f64 {
    if ageing_s == 0.0 { excess } else { excess * one_minus_exp_neg(dwell_s.max(0.0) / ageing_s) }
}

/// Build-up of sliding friction with displacement `d` (m) since slip start,
/// over the characteristic displacement `length` (m); 1 when `length` is 0
/// and for the `lag`, `slip` and `ageing` forms (which act through the
/// friction memory state). `dahl` and `bristle` start from `start` (φ₀, –:
/// −φ at a reversal, 1 after a stick) and turn to 1, `1 − (1 − φ₀) e^(−d/δ)`.
pub fn hysteresis_factor(form: HysteresisForm, d: f64, length: f64, start: f64) -> f64 {
    if length == 0.0 {
        return 1.0;
    }
    let r = d / length;
    match form {
        HysteresisForm::Tanh => r.tanh(),
        HysteresisForm::Rational => r / (r + 1.0),
        HysteresisForm::Exponential => one_minus_exp_neg(r),
        // Past 40 lengths (1 − φ₀) e^(−r) is under 8 · 4.3e-18 < 2⁻⁵⁴ for
        // any φ₀ within ±7, and 1 minus it rounds to exactly 1.
        HysteresisForm::Dahl | HysteresisForm::Bristle if r > 40.0 && (1.0 - start).abs() <= 8.0 => 1.0,
        HysteresisForm::Dahl | HysteresisForm::Bristle => 1.0 - (1.0 - start) * exp_neg(r),
        HysteresisForm::Lag | HysteresisForm::Slip | HysteresisForm::Ageing => 1.0,
    }
}

/// κ = k / (k + k_t) of hysteresis `bristle`, –: the share of the base's
/// motion a block stuck on a contact of stiffness k_t = `held_n` / δ
/// follows, for a rig of stiffness `stiffness_n_per_m` (N/m), the force
/// the contact holds at rest `held_n` (μ₀ N0, N) and the bristle length
/// `length_m` (δ, m): `k δ / (k δ + μ₀ N0)`. 0 (a rigid stick) where δ is 0
/// or the contact holds nothing.
pub fn bristle_compliance(stiffness_n_per_m: f64, held_n: f64, length_m: f64) -> f64 {
    let elastic = stiffness_n_per_m * length_m;
    if elastic > 0.0 && held_n > 0.0 { elastic / (elastic + held_n) } else { 0.0 }
}

/// Rate of the friction memory μ_f under hysteresis `slip` (the slip law),
/// 1/s: it relaxes to the steady law's `steady_mu` (–) over the slip
/// distance `length` (m, > 0) at speed `speed` (m/s, ≥ 0),
/// `(|v|/L)(μ_ss − μ_f)`.
pub fn slip_law_rate(steady_mu: f64, memory_mu: f64, speed: f64, length: f64) -> f64 {
    speed / length * (steady_mu - memory_mu)
}

/// Rate of the contact age θ (`age_s`, s) under hysteresis `ageing` (the
/// ageing law) at speed `speed` (m/s, ≥ 0) with slip distance `length` (m,
/// > 0): `1 − |v| θ / L`, –.
pub fn ageing_rate(age_s: f64, speed: f64, length: f64) -> f64 {
    1.0 - speed * age_s / length
}

/// The contact-age term of hysteresis `ageing`, –:
/// `B ln((θ + θ_0)/(θ_ref + θ_0))` with `strength` B (–), the contact age
/// θ = `age_s` (s; read as 0 where an RK4 stage overshoots below it),
/// `reference_age_s` θ_ref (s: the steady age L/(|v| + v_c) while sliding,
/// θ_c = L/v_c at rest) and the floor age θ_0 = L/v_0 (`floor_age_s`, s).
pub fn contact_age_term(strength: f64, age_s: f64, reference_age_s: f64, floor_age_s: f64) -> f64 {
    strength * ((age_s.max(0.0) + floor_age_s) / (reference_age_s + floor_age_s)).ln()
}

/// The adhesion force of load dependence `adhesion` as it adds to a
/// friction force of magnitude `friction_n` (μN, N): the force `adhesion_n`
/// (A, N), but no less than −μN, so that the sum μN + A, the friction force's
/// magnitude, is clipped at 0.
pub fn adhesion(friction_n: f64, adhesion_n: f64) -> f64 {
    adhesion_n.max(-friction_n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exponentials that skip the library call past their thresholds
    /// give its bits everywhere: on a fine sweep across each threshold,
    /// over the whole range a slip reaches, and for the Dahl factor from
    /// every start within ±7.
    #[test]
    fn skipped_exponentials_are_the_library_s_bits() {
        let sweep = (0..200_000).map(|i| f64::from(i) * 0.005).chain((0..20_000).map(|i| 700.0 + f64::from(i) * 0.005));
        for x in sweep.chain([1e4, 1e300, f64::INFINITY]) {
            assert_eq!(exp_neg(x).to_bits(), (-x).exp().to_bits(), "e^-{x}");
            assert_eq!(one_minus_exp_neg(x).to_bits(), (1.0 - (-x).exp()).to_bits(), "1 - e^-{x}");
            for start in [-7.0, -1.0, -0.3, 0.0, 0.7, 1.0, 7.0] {
                let direct = 1.0 - (1.0 - start) * (-x).exp();
                let factor = hysteresis_factor(HysteresisForm::Dahl, x, 1.0, start);
                assert_eq!(factor.to_bits(), direct.to_bits(), "Dahl from {start} at {x} lengths");
            }
        }
    }

    /// E[f(z)] over a standard normal z, by Simpson's rule on ±12.
    fn expect(f: impl Fn(f64) -> f64) -> f64 {
        let (n, h) = (24_000, 24.0 / 24_000.0);
        let density = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
        (0..=n)
            .map(|i| {
                let z = -12.0 + i as f64 * h;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(z) * density(z)
            })
            .sum::<f64>()
            * h
            / 3.0
    }

    /// (mean, variance, skewness, excess kurtosis) of a transform of z.
    fn moments(f: impl Fn(f64) -> f64) -> [f64; 4] {
        let mean = expect(&f);
        let central = |k: i32| expect(|z| (f(z) - mean).powi(k));
        let var = central(2);
        [mean, var, central(3) / var.powf(1.5), central(4) / (var * var) - 3.0]
    }

    #[test]
    fn one_variable_forms_are_standardised() {
        for (form, s) in [(NonGaussianForm::Lognormal, 0.7), (NonGaussianForm::TukeyH, 0.2)] {
            let [mean, var, ..] = moments(|z| non_gaussian(form, s, 0.0, z, 0.0));
            assert!(mean.abs() < 1e-9 && (var - 1.0).abs() < 1e-9, "{form:?}: mean {mean}, variance {var}");
        }
    }

    #[test]
    fn the_polynomial_sets_skew_and_tails_apart() {
        for (c, d) in [(0.0, 0.0), (0.3, -0.08), (-0.2, 0.1), (0.0, 0.15), (0.5, 0.0)] {
            let [mean, var, skew, kurt] = moments(|z| non_gaussian(NonGaussianForm::Polynomial, c, d, z, 0.0));
            let b = (1.0 - 2.0 * c * c - 6.0 * d * d).sqrt() - 3.0 * d;
            // Fleishman (1978): the skewness and excess kurtosis of −c + bz + cz² + dz³.
            let fleishman_skew = 2.0 * c * (b * b + 24.0 * b * d + 105.0 * d * d + 2.0);
            let fleishman_kurt = 24.0
                * (b * d
                    + c * c * (1.0 + b * b + 28.0 * b * d)
                    + d * d * (12.0 + 48.0 * b * d + 141.0 * c * c + 225.0 * d * d));
            assert!(mean.abs() < 1e-9 && (var - 1.0).abs() < 1e-9, "c {c}, d {d}: mean {mean}, variance {var}");
            assert!((skew - fleishman_skew).abs() < 1e-7, "c {c}, d {d}: skewness {skew} vs {fleishman_skew}");
            assert!((kurt - fleishman_kurt).abs() < 1e-6, "c {c}, d {d}: excess kurtosis {kurt} vs {fleishman_kurt}");
        }
        // A negative cubic makes the tails lighter than a Gaussian's while c skews.
        let [_, _, skew, kurt] = moments(|z| non_gaussian(NonGaussianForm::Polynomial, 0.25, -0.1, z, 0.0));
        assert!(skew > 0.7 && kurt < 0.0, "skewness {skew}, excess kurtosis {kurt}");
    }
}
